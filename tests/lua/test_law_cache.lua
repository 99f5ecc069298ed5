-- test_law_cache.lua - compiled programs shared between laws
-- (src/lua/trace/lua_trace_cache.c): a law built anew from the same
-- function reuses the program an earlier law traced and checked, with its
-- own float params bound, but only while everything else the program
-- baked in (upvalues, globals, other params, the code itself) is what it
-- was.  Every reuse must give, bit for bit, what a fresh trace gives,
-- and what the law run as Lua gives (to the node solvers' tolerance: see
-- close_to_lua).
local tests = {}

local stats = debug.getregistry()["dfle.trace.stats"]

local function channel()
    return dfle.channel{ dx = 20, A_max = 1e6 }
end

local function steady_z(law)
    local m = dfle.model{ channel = channel(), law = law }
    m:init_fluvial_steady()
    local r = m:run_to_steady{ method = "direct" }
    T.ok(r.converged, "no steady state")
    return m:get("z")
end

local bits_equal = T.bits_equal

local close_to_lua = T.close_to_lua

local function differs(a, b)
    for i = 1, #a do if a[i] ~= b[i] then return true end end
    return false
end

-- What the counters moved by while fn ran.
local function counted(fn)
    local s0 = stats()
    fn()
    local s1 = stats()
    local d = {}
    for k, v in pairs(s1) do d[k] = v - s0[k] end
    return d
end

local function factor(c, p) return c.t_p * c.h ^ p.beta * c.Theta end
local function rate(c, p) return p.k_df * c.S ^ p.alpha * c.F end

-- The law of an ensemble sample: the same functions, new params.
local function eq6(k_df, alpha, how)
    local def = { params = { k_df = k_df, alpha = alpha or 6, beta = 1 }, factor = factor,
                  rate = rate }
    for k, v in pairs(how or {}) do def[k] = v end
    return dfle.law.define(def)
end

tests["a law built anew reuses the program, bit for bit a fresh trace and Lua"] = function()
    steady_z(eq6(1e-4)) -- traced and checked, or found: either way cached now
    for _, k in ipairs{ 2e-4, 7.3e-5, 1e-4 } do
        local z
        local d = counted(function() z = steady_z(eq6(k)) end)
        T.eq(d.found, 2, "factor and rate found for k_df = " .. k)
        T.eq(d.traced, 0, "nothing traced")
        T.eq(d.checked, 0, "a program found is not checked again")
        bits_equal(z, steady_z(eq6(k, 6, { cache = false })), "fresh trace, k_df = " .. k)
        close_to_lua(z, steady_z(eq6(k, 6, { compile = false })), "Lua, k_df = " .. k)
    end
    T.ok(differs(steady_z(eq6(2e-4)), steady_z(eq6(1e-4))), "a new k_df gives a new profile")
end

tests["cache = false traces every law and checks it, as before"] = function()
    local d = counted(function() steady_z(eq6(3e-4, 6, { cache = false })) end)
    T.eq(d.found, 0)
    T.eq(d.traced, 2)
    T.eq(d.checked, 2)
    T.eq(d.kept, 0, "nothing kept either")
end

tests["an integer param is baked in: another value is traced and checked anew"] = function()
    steady_z(eq6(1e-4, 6))
    local z
    local d = counted(function() z = steady_z(eq6(1e-4, 5)) end)
    T.eq(d.traced, 1, "rate traced again (factor does not read alpha)")
    T.eq(d.checked, 1)
    T.eq(d.found, 1, "factor found")
    close_to_lua(z, steady_z(eq6(1e-4, 5, { compile = false })), "alpha = 5")
    -- alpha = 6.0 is a float: read as an input, not the integer's program
    close_to_lua(steady_z(eq6(1e-4, 6.0)), steady_z(eq6(1e-4, 6.0, { compile = false })), "6.0")
end

tests["an upvalue changed between models gives the new result"] = function()
    local gain = 1
    local function r(c, p) return gain * p.k_df * c.S ^ 6 * c.F end
    local function law(compile) return dfle.law.define{
        params = { k_df = 1e-4, beta = 1 }, factor = factor, rate = r, compile = compile } end
    local z1 = steady_z(law())
    gain = 2.5
    local z2
    local d = counted(function() z2 = steady_z(law()) end)
    T.eq(d.traced, 1, "rate traced again")
    close_to_lua(z2, steady_z(law(false)), "gain = 2.5")
    T.ok(differs(z1, z2), "the new gain shows")
    -- closures of one expression with other upvalues: never the other's
    local function make(g) return function(c, p) return g * p.k_df * c.S ^ 6 * c.F end end
    local zs = {}
    for i, g in ipairs{ 1, 3, 1 } do
        local def = { params = { k_df = 1e-4, beta = 1 }, factor = factor, rate = make(g) }
        zs[i] = steady_z(dfle.law.define(def))
        def.compile = false
        close_to_lua(zs[i], steady_z(dfle.law.define(def)), "closure with g = " .. g)
    end
    T.ok(differs(zs[1], zs[2]))
    bits_equal(zs[1], zs[3], "same upvalue value")
end

tests["a global changed between models gives the new result"] = function()
    dfle_test_cache_K = 1e-4
    local function r(c, p) return dfle_test_cache_K * c.S ^ 6 * c.F end
    local function law(compile) return dfle.law.define{
        params = { beta = 1 }, factor = factor, rate = r, compile = compile } end
    local z1 = steady_z(law())
    dfle_test_cache_K = 4e-4
    local z2 = steady_z(law())
    close_to_lua(z2, steady_z(law(false)), "K = 4e-4")
    T.ok(differs(z1, z2))
    dfle_test_cache_K = 1e-4
    local z3
    local d = counted(function() z3 = steady_z(law()) end)
    T.eq(d.found, 2, "the program of K = 1e-4 serves again")
    bits_equal(z3, z1, "back to K = 1e-4")
    dfle_test_cache_K = nil
end

tests["two different functions never share a program"] = function()
    local function r5(c, p) return p.k_df * c.S ^ 5 * c.F end
    -- the same text as `rate`, on other lines: another function
    local function r6(c, p) return p.k_df * c.S ^ p.alpha * c.F end
    steady_z(eq6(1e-4))
    local z5, z6
    local d = counted(function()
        z5 = steady_z(dfle.law.define{ params = { k_df = 1e-4, beta = 1 }, factor = factor,
                                       rate = r5 })
        z6 = steady_z(dfle.law.define{ params = { k_df = 1e-4, alpha = 6, beta = 1 },
                                       factor = factor, rate = r6 })
    end)
    T.eq(d.traced, 2, "both rates traced")
    close_to_lua(z5, steady_z(dfle.law.define{ params = { k_df = 1e-4, beta = 1 },
                                             factor = factor, rate = r5, compile = false }), "S^5")
    bits_equal(z6, steady_z(eq6(1e-4)), "S^6")
    T.ok(differs(z5, z6))
    -- a function with and without a factor: other fields, other programs
    local whole = function(c, p) return p.k_df * c.S ^ 6 * c.t_p * c.h * c.Theta end
    local d2 = counted(function()
        steady_z(dfle.law.define{ params = { k_df = 1e-4 }, rate = whole })
    end)
    T.eq(d2.found, 0)
end

tests["the closures of one expression share (ensemble build functions)"] = function()
    local function build(k)
        return dfle.law.define{
            params = { k_df = k, beta = 1 },
            factor = function(c, p) return c.t_p * c.h ^ p.beta * c.Theta end,
            rate = function(c, p) return p.k_df * c.S ^ 6 * c.F end,
        }
    end
    steady_z(build(1e-4))
    local z
    local d = counted(function() z = steady_z(build(2.5e-4)) end)
    T.eq(d.found, 2)
    T.eq(d.traced, 0)
    local ref = dfle.law.define{ params = { k_df = 2.5e-4, beta = 1 }, compile = false,
        factor = function(c, p) return c.t_p * c.h ^ p.beta * c.Theta end,
        rate = function(c, p) return p.k_df * c.S ^ 6 * c.F end }
    close_to_lua(z, steady_z(ref), "k_df = 2.5e-4")
end

tests["a param the function compares is baked in, and read again for each law"] = function()
    local function r(c, p)
        if p.mode > 0.5 then return p.k_df * c.S ^ 6 * c.F end
        return 2 * p.k_df * c.S ^ 6 * c.F
    end
    local function law(mode, compile)
        return dfle.law.define{ params = { k_df = 1e-4, beta = 1, mode = mode },
                                factor = factor, rate = r, compile = compile }
    end
    local a, b = law(0.75), law(0.25)
    local za, zb
    local da = counted(function() za = steady_z(a) end)
    local db = counted(function() zb = steady_z(b) end)
    T.eq(a:compiled().rate, true, "compiled with mode as a constant")
    T.eq(b:compiled().rate, true)
    -- the first law learns that rate needs its params as constants (one
    -- trace refused, one kept); the next law of the same code traces
    -- once, with constants, straight away
    T.eq(da.retraced, 1, "rate refused once with params as inputs")
    T.eq(db.retraced, 0, "the same code: no second attempt")
    T.eq(db.traced, 1, "rate traced once for the new mode (factor found)")
    close_to_lua(za, steady_z(law(0.75, false)), "mode = 0.75")
    close_to_lua(zb, steady_z(law(0.25, false)), "mode = 0.25")
    T.ok(differs(za, zb))
end

tests["a program is checked where it is traced, and kept only once checked"] = function()
    -- frequency(A) is memoised by the Lua sweep: until it has run, a
    -- compiled rate hands its calls to Lua, which here raises.  Those calls
    -- are no check, so the rate stays unchecked and out of the cache.
    local fail = true
    local function law()
        return dfle.law.define{
            params = { k_df = 1e-4, beta = 1 }, factor = factor,
            rate = function(c, p) return p.k_df * c.S ^ 6 * c.F end,
            frequency = function(A)
                if fail then error("not now") end
                return 1
            end,
        }
    end
    local l1 = law()
    T.errors(function() steady_z(l1) end, "not now")
    local d = counted(function() T.errors(function() steady_z(law()) end, "not now") end)
    T.eq(d.found, 1, "only the (checked) factor was kept")
    T.eq(d.kept, 0)
    fail = false
    local d1 = counted(function() steady_z(l1) end)
    T.eq(d1.traced, 0, "l1 keeps its program")
    T.eq(d1.checked, 1, "checked on the first call it completes")
    T.eq(d1.kept, 1, "then kept")
    local z
    local d2 = counted(function() z = steady_z(law()) end)
    T.eq(d2.found, 2, "a new law finds both programs")
    T.eq(d2.checked, 0)
    close_to_lua(z, steady_z(dfle.law.define{ params = { k_df = 1e-4, beta = 1 }, factor = factor,
        compile = false, rate = function(c, p) return p.k_df * c.S ^ 6 * c.F end,
        frequency = function() return 1 end }), "with frequency")
end

tests["a table given a metatable after the trace is read again"] = function()
    local env = { math = math }
    local r = load("return function(c, p) return (K or 1) * 1e-4 * c.S ^ 6 * c.F end",
                   "=cache_env", "t", env)()
    local function law(compile)
        return dfle.law.define{ params = { beta = 1 }, factor = factor, rate = r,
                                compile = compile }
    end
    local z1 = steady_z(law())
    setmetatable(env, { __index = function(_, k) if k == "K" then return 3 end end })
    local l2 = law()
    local z2 = steady_z(l2)
    T.has(l2:compiled().rate, "runs as Lua", "not set")
    bits_equal(z2, steady_z(law(false)), "K through __index")
    T.ok(differs(z1, z2))
end

tests["a Lua integrand found in the cache is bound and not checked again"] = function()
    local ch = dfle.channel{ dx = 20, A_max = 2e5 }
    local function z_of(beta, how)
        local def = { params = { k_df = 1e-4, beta = beta },
                      rate = function(c, p) return p.k_df * c.S ^ 6 * c.F end,
                      integrand = function(h, v, lambda, p) return h ^ p.beta end }
        for k, v in pairs(how or {}) do def[k] = v end
        local m = dfle.model{ channel = ch, law = dfle.law.define(def),
                              router = dfle.router.process{} }
        m:init_fluvial_steady()
        m:run{ years = 500, method = "explicit" }
        return m:get("z")
    end
    z_of(1.0)
    local z
    local d = counted(function() z = z_of(1.5) end)
    T.ok(d.found >= 1, "integrand found")
    T.eq(d.checked, 0)
    bits_equal(z, z_of(1.5, { compile = false }), "beta = 1.5")
end

tests["an ensemble of fresh laws gives the rows of uncached ones"] = function()
    local function run(cache, out)
        return dfle.ensemble{
            params = { k_df = { 5e-5, 1e-3, log = true }, U = { 1e-4, 1e-3 } },
            n = 8, seed = 3, out = out, workers = 1, resume = false,
            build = function(p)
                return dfle.model{ channel = dfle.channel{ dx = 20 }, U = p.U,
                    law = dfle.law.define{ cache = cache, params = { k = p.k_df, beta = 1 },
                        factor = function(c, q) return c.t_p * c.h ^ q.beta * c.Theta end,
                        rate = function(c, q) return q.k * c.S ^ 6 * c.F end } }
            end,
            outputs = { "S_df", "A_df", "r2" },
        }
    end
    local a, b = T.tmpname(".csv"), T.tmpname(".csv")
    local d = counted(function() run(true, a) end)
    T.ok(d.found >= 14, "the samples after the first reuse the programs")
    run(false, b)
    T.eq(T.read_file(a), T.read_file(b))
    os.remove(a)
    os.remove(b)
end

return tests
