-- test_compile.lua - Lua laws run compiled (src/lua/trace/): a law
-- that is a formula is traced once and evaluated in C.  The compiled form
-- must give exactly (bit for bit) what the same law gives run as Lua
-- (compile = false), for every operation and math function it accepts;
-- everything it cannot record must be refused, with a reason, and still
-- run (as Lua) with the same results; values it read from outside must be
-- re-read when the script changes them.
local tests = {}

local function channel()
    return dfle.channel{ dx = 20, A_max = 1e6 }
end

-- A model at the fluvial steady state with `law`; E_df evaluated there.
local function e_df(law, router)
    local m = dfle.model{ channel = channel(), law = law, router = router }
    m:init_fluvial_steady()
    return m:get("E_df"), m
end

-- The same definition compiled and run as Lua.
local function pair(def)
    local a, b = {}, {}
    for k, v in pairs(def) do a[k], b[k] = v, v end
    a.name, b.name = def.name or "compiled", (def.name or "lua") .. "_lua"
    b.compile = false
    return dfle.law.define(a), dfle.law.define(b)
end

local bits_equal = T.bits_equal

local function steady_z(law, method, router)
    local m = dfle.model{ channel = channel(), law = law, router = router }
    m:init_fluvial_steady()
    local r = m:run_to_steady{ method = method }
    T.ok(r.converged, "no steady state (" .. method .. ")")
    return m:get("z")
end

tests["Eq. (6) compiles, and equals the law run as Lua, bit for bit by the explicit method"] = function()
    for _, method in ipairs{ "explicit", "implicit", "direct" } do
        local c, l = pair{
            params = { k_df = 1e-4, alpha = 6, beta = 1 },
            factor = function(c, p) return c.t_p * c.h ^ p.beta * c.Theta end,
            rate = function(c, p) return p.k_df * c.S ^ p.alpha * c.F end,
        }
        -- bit for bit by the explicit method; the node solvers take
        -- Newton steps with the compiled law only (T.close_to_lua)
        local compare = method == "explicit" and bits_equal or T.close_to_lua
        compare(steady_z(c, method), steady_z(l, method), method)
        local st = c:compiled()
        T.eq(st.factor, true, method .. ": factor")
        T.eq(st.rate, true, method .. ": rate")
        T.has(l:compiled().rate, "compile = false")
        -- and the built-in law, to the issue's tolerance
        local ref = steady_z(dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 }, method)
        local z = steady_z(c, method)
        for i = 1, #z do T.close(z[i], ref[i], 1e-9, 0, method .. " vs built-in, node " .. i) end
    end
    T.eq(dfle.law.power{}:compiled(), nil, "a built-in law is C already")
end

tests["process router: factor, rate and a Lua integrand compile and equal Lua"] = function()
    local function router() return dfle.router.process{} end
    local ch = dfle.channel{ dx = 20, A_max = 2e5 }
    local function z_of(law)
        local m = dfle.model{ channel = ch, law = law, router = router() }
        m:init_fluvial_steady()
        m:run{ years = 2000, method = "explicit" }
        return m:get("z")
    end
    local c, l = pair{
        params = { k_df = 1e-4, alpha = 6, beta = 1 },
        factor = function(c, p) return c.I end,
        rate = function(c, p) return p.k_df * c.S ^ p.alpha * c.F end,
        integrand = function(h, v, lambda, p) return h ^ p.beta * (1 + 0 * v * lambda) end,
    }
    bits_equal(z_of(c), z_of(l), "process")
    local st = c:compiled()
    T.eq(st.factor, true, "factor")
    T.eq(st.rate, true, "rate")
    T.eq(st.integrand, true, "integrand")
end

-- Every operation and math function the tracer records, each in a law of
-- its own so that a difference is named.  Values stay finite on the
-- fluvial steady state of the test channel.
local battery = {
    add_sub_mul_div = function(c, p) return (c.S + c.h - 0.5 * c.w) * c.v / c.A end,
    mod = function(c, p) return c.S % 0.01 + (-c.S) % 0.03 + c.A % -7.5 + 5 % (c.S + 1) end,
    idiv = function(c, p) return c.h // 0.1 + c.S // -0.01 + 7 // (c.S + 0.5) end,
    pow = function(c, p) return c.S ^ 2 + c.S ^ 0.5 + c.h ^ p.one + 2 ^ c.S + c.S ^ 6 + c.S ^ c.h end,
    unm = function(c, p) return -c.S + -(-c.h) end,
    sqrt_exp_log = function(c, p)
        return math.sqrt(c.A) + math.exp(-c.S) + math.log(c.A) + math.log(c.A, 2)
            + math.log(c.A, 10) + math.log(c.A, 3) + math.log(c.A, c.w)
    end,
    abs_floor_ceil = function(c, p)
        return math.abs(-c.S) + math.floor(c.A / 7) * 0.5 + math.ceil(c.h * 10) * 0.25
    end,
    fmod = function(c, p) return math.fmod(c.A, 7.5) + math.fmod(-c.A, 3) + math.fmod(5, c.S) end,
    max_min = function(c, p)
        return math.max(c.S, 0.1) + math.min(c.S, 0.1, c.h) + math.max(c.S - 0.2, 0) * 2.0
            + math.max(0, c.S - 0.1) / c.w + math.min(c.S)
    end,
    trig = function(c, p)
        return math.sin(c.S) + math.cos(c.S) + math.tan(c.S)
            + math.atan(c.S) + math.atan(c.S, -1) + math.deg(c.S) + math.rad(c.A)
            + math.asin(c.S / (1 + c.S)) + math.acos(c.h / (1 + c.h))
    end,
    constants = function(c, p) return math.pi * c.S + p.one * 3 + 2 ^ 10 * c.h + (1 // 2) end,
    loop_and_locals = function(c, p)
        local x = 0
        for i = 1, 5 do x = x + c.S * i end
        local function sq(y) return y * y end
        return sq(x) + sq(c.h)
    end,
    constant_result = function(c, p) return 1.5 end,
}

tests["every recorded operation equals Lua bit for bit"] = function()
    for name, fn in pairs(battery) do
        local c, l = pair{ name = name, params = { one = 1 }, rate = fn }
        local ec, el = e_df(c), e_df(l)
        T.eq(c:compiled().rate, true, name)
        bits_equal(ec, el, name)
    end
end

-- The replay of every operation, against Lua itself, over operands of
-- every class.  A law never hands its program NaN, infinities or (as a
-- result it keeps) a non-finite value, so this goes through the test hook
-- that traces fn(x, y) and replays it both ways the laws do (column by
-- column for a sweep, point by point for an integrand).
local replay = debug.getregistry()["dfle.trace.replay"]

-- Bit for bit, but any NaN equals any NaN.  A Lua integer result (from
-- math.floor, math.max with an integer bound) counts as the float the
-- law would see.
local function same_bits(a, b)
    if a ~= a and b ~= b then return true end
    return string.pack("<d", a) == string.pack("<d", b)
end

-- Operands: negative, -0.0, +0.0, positive, integer-valued and fractional,
-- subnormal, huge, infinite, NaN (floats all: flow fields are floats).
local operands = { -7.25, -5.5, -3.0, -2.0, -1.0, -0.5, -0.0, 0.0, 0.5, 1.0, 2.0, 3.0, 5.5,
                   7.25, 10.0, 1e-310, 1e300, -1e300, math.huge, -math.huge, 0 / 0 }
-- Constants baked into a program: the same, and Lua integers.
local constants = { -3, -2, -1, 0, 1, 2, 3, 10 }
for _, v in ipairs(operands) do constants[#constants + 1] = v end

local replayed = {
    ["+"] = function(x, y) return x + y end,
    ["-"] = function(x, y) return x - y end,
    ["*"] = function(x, y) return x * y end,
    ["/"] = function(x, y) return x / y end,
    ["%"] = function(x, y) return x % y end,
    ["//"] = function(x, y) return x // y end,
    ["^"] = function(x, y) return x ^ y end,
    ["math.fmod"] = function(x, y) return math.fmod(x, y) end,
    ["math.max"] = function(x, y) return math.max(x, y) end,
    ["math.min"] = function(x, y) return math.min(x, y) end,
    ["math.max (3)"] = function(x, y) return math.max(y, x, y) end,
    ["math.min (3)"] = function(x, y) return math.min(y, x, y) end,
    ["math.log (base)"] = function(x, y) return math.log(x, y) end,
    ["math.atan (2)"] = function(x, y) return math.atan(x, y) end,
    ["unary -"] = function(x) return -x end,
    ["math.sqrt"] = function(x) return math.sqrt(x) end,
    ["math.exp"] = function(x) return math.exp(x) end,
    ["math.log"] = function(x) return math.log(x) end,
    ["math.log (2)"] = function(x) return math.log(x, 2) end,
    ["math.log (2.0)"] = function(x) return math.log(x, 2.0) end,
    ["math.log (10)"] = function(x) return math.log(x, 10) end,
    ["math.log (3)"] = function(x) return math.log(x, 3) end,
    ["math.log (0.5)"] = function(x) return math.log(x, 0.5) end,
    ["math.abs"] = function(x) return math.abs(x) end,
    ["math.floor"] = function(x) return math.floor(x) end,
    ["math.ceil"] = function(x) return math.ceil(x) end,
    ["math.sin"] = function(x) return math.sin(x) end,
    ["math.cos"] = function(x) return math.cos(x) end,
    ["math.tan"] = function(x) return math.tan(x) end,
    ["math.asin"] = function(x) return math.asin(x) end,
    ["math.acos"] = function(x) return math.acos(x) end,
    ["math.atan"] = function(x) return math.atan(x) end,
    ["math.deg"] = function(x) return math.deg(x) end,
    ["math.rad"] = function(x) return math.rad(x) end,
}
-- The operations that take a second operand, which may be a constant.
local with_constant = { "+", "-", "*", "/", "%", "//", "^", "math.fmod", "math.max",
                        "math.min", "math.log (base)", "math.atan (2)" }

-- Replay fn at every (x, y) and compare both replays with fn run by Lua
-- (with params p, read as inputs, if given).
local function check_replay(what, fn, xs, ys, p)
    local cols, points = replay(fn, xs, ys, p)
    T.ok(cols ~= nil, what .. ": not compiled (" .. tostring(points) .. ")")
    for i = 1, #xs do
        local want = fn(xs[i], ys[i], p)
        for _, got in ipairs{ cols[i], points[i] } do
            if not same_bits(got, want) then
                T.fail(string.format("%s at x = %s, y = %s: replayed %s, Lua %s", what,
                                     T.fmt(xs[i]), T.fmt(ys[i]), T.fmt(got), T.fmt(want)))
            end
        end
    end
end

tests["every replayed operation equals Lua bit for bit, operands of every sign and class"] = function()
    local xs, ys = {}, {}
    for _, x in ipairs(operands) do
        for _, y in ipairs(operands) do xs[#xs + 1], ys[#ys + 1] = x, y end
    end
    local n = 0
    for what, fn in pairs(replayed) do
        check_replay(what, fn, xs, ys)
        n = n + 1
    end
    for _, what in ipairs(with_constant) do
        local op = replayed[what]
        for _, k in ipairs(constants) do
            check_replay(what .. " constant " .. T.fmt(k) .. " second",
                         function(x) return op(x, k) end, xs, ys)
            check_replay(what .. " constant " .. T.fmt(k) .. " first",
                         function(x) return op(k, x) end, xs, ys)
        end
    end
    T.eq(n, 34, "operations checked")
    -- The same with the constant a float param, read as an input of the
    -- program (a law's params are, so that laws can share programs).
    for _, what in ipairs(with_constant) do
        local op = replayed[what]
        for _, k in ipairs(operands) do
            local p = { k = k }
            check_replay(what .. " param " .. T.fmt(k) .. " second",
                         function(x, y, q) return op(x, q.k) end, xs, ys, p)
            check_replay(what .. " param " .. T.fmt(k) .. " first",
                         function(x, y, q) return op(q.k, x) end, xs, ys, p)
        end
    end
    -- The cases that were wrong: Lua's % floors (both operands negative
    -- keep fmod's result), and an integer result has no -0.
    T.eq(string.pack("<d", replay(function(x, y) return x % y end, { -5.5 }, { -2.0 })[1]),
         string.pack("<d", -1.5))
    T.eq(string.pack("<d", replay(function(x) return math.floor(x) end, { -0.0 }, { 0.0 })[1]),
         string.pack("<d", 0.0))
    -- A param read as an input is no key: p[p.k] is another field for
    -- each k (here p[3], set), so the function is traced with k as a
    -- constant, and p[3] guarded.
    check_replay("p[p.k]", function(x, y, q) return (q[q.k] or 1) * x end, { 2, -1 }, { 2, 0 },
                 { k = 3.0, [3] = 5.0 })
end

-- The way the bug showed: a law compiled (and checked against Lua on its
-- first use) while its operands had one sign, then given others.
tests["a compiled law stays exact when its operands change sign after the first use"] = function()
    local theta = {}
    local function set_theta(f) for i = 1, 51 do theta[i] = f(i) end end
    -- A router that hands the law Theta straight from the script.
    local rt = dfle.router.define{
        name = "theta",
        flow = function(c, p)
            c.h, c.v, c.t_p = 1, 1, 1
            c.Theta = theta[math.floor(c.x / 20 + 0.5) + 1]
            return true
        end,
    }
    local function law(compile)
        return dfle.law.define{
            name = compile and "mod" or "mod_lua", compile = compile,
            params = { b = -2, c = 0.75 },
            factor = function(c, p) return c.Theta end,
            rate = function(c, p)
                return c.F % p.b + c.F % p.c + p.b % c.F + c.F // p.b + math.floor(c.F * p.c)
            end,
        }
    end
    local function model(l)
        local m = dfle.model{ channel = dfle.channel{ dx = 20, length = 1000 }, router = rt,
                              law = l }
        m:init_fluvial_steady()
        return m
    end
    local c, l = law(true), law(false)
    local mc, ml = model(c), model(l)
    set_theta(function(i) return 0.25 + 0.5 * i end)
    bits_equal(mc:get("E_df"), ml:get("E_df"), "positive")
    T.eq(c:compiled().rate, true, "rate compiled")
    T.eq(c:compiled().factor, true, "factor compiled")
    -- Negative, -0.0 and +0.0 (which the driver skips), integer-valued and
    -- fractional: the program is not checked again, only the values.
    local values = { -5.5, -3.0, -2.0, -1.0, -0.25, -0.0, 0.0, 0.25, 1.0, 2.0, 3.0, 5.5 }
    set_theta(function(i) return values[(i - 1) % #values + 1] end)
    for _, m in ipairs{ mc, ml } do m:set_z(m:get("z")) end
    local ec, el = mc:get("E_df"), ml:get("E_df")
    bits_equal(ec, el, "every sign")
    T.eq(c:compiled().rate, true, "still compiled")
    local negative = 0
    for i = 1, #ec do if ec[i] < 0 then negative = negative + 1 end end
    T.ok(negative > 0, "negative operands reached the rate")
end

-- Helpers reached through upvalues and globals are vetted like the law.
local sqrt = math.sqrt
local function helper(x) return sqrt(x) * 2 end
local k_up = 3

tests["helpers, upvalues, globals and math aliases compile"] = function()
    dfle_test_global_k = 0.25
    function dfle_test_global_fn(x) return x * dfle_test_global_k end
    local m = math
    local c, l = pair{
        rate = function(c, p)
            return helper(c.S) + k_up * c.h + dfle_test_global_fn(c.v) + m.sqrt(c.A)
        end,
    }
    T.eq(c:compiled().rate, false, "not used yet")
    bits_equal(e_df(c), e_df(l), "helpers")
    T.eq(c:compiled().rate, true)
    dfle_test_global_k, dfle_test_global_fn = nil, nil
end

-- Each of these cannot be recorded: the law must say why and run as Lua.
local refused = {
    { "uses '==' or '~='", function(c, p) if c.S == 0 then return 0 end return c.S end },
    { "uses '==' or '~='", function(c, p) if c.h ~= 0.5 then return c.S end return 1 end },
    { "uses '==' or '~='", function(c, p) return c.h == c.v and 1 or c.S end },
    { "uses '==' or '~='", function(c, p) return p.missing == nil and c.S or 1 end },
    { "compares a flow field", function(c, p) return c.S < 0.1 and c.S or 2 * c.S end },
    { "compares a flow field", function(c, p) return c.S >= 0.1 and c.S or 2 * c.S end },
    { "calls the global 'print'", function(c, p) local say = print return c.S end },
    { "calls the global 'type'", function(c, p) return type(c.S) and c.S end },
    { "reads the table the global 'string'", function(c, p) return string.len("ab") * c.S end },
    { "it assigns to the global 'dfle_test_last'",
      function(c, p) dfle_test_last = 1 return c.S end },
    { "it assigns to p.x", function(c, p) p.x = 1 return c.S end },
    { "it assigns to a field of c", function(c, p) c.S = 1 return c.S end },
    { "uses a flow field as a string", function(c, p) return #(c.S .. "") * c.S end },
    { "may do integer arithmetic", function(c, p) return (math.max(c.S - 1, 0) + 1) * c.S end },
    { "may do integer arithmetic", function(c, p) return -math.floor(c.S) + c.S end },
    { "calls math.random", function(c, p) return c.S * (1 + 0 * math.random()) end },
    { "it reads the table the upvalue 't'",
      (function() local t = { 1 } return function(c, p) return t[1] * c.S end end)() },
    -- values no guard could watch: the real length of p, string methods
    -- (string.len may be replaced after the trace)
    { "takes the length of p", function(c, p) return #p * c.S end },
    { "calls a string method", function(c, p) return ("ab"):len() * c.S end },
    -- a computed key names another field for each value (p[c.S] is p[1]
    -- where S = 1, nil elsewhere)
    { "indexes p with a computed value", function(c, p) return (p[c.S] or 1) * c.S end },
}

tests["what cannot be recorded runs as Lua, says why, and gives the same values"] = function()
    for i, case in ipairs(refused) do
        local want, fn = case[1], case[2]
        if want == "calls math.random" then want = "math.random" end
        local c, l = pair{ name = "refused" .. i, params = { one = 1 }, rate = fn }
        local ec, el = e_df(c), e_df(l)
        local st = c:compiled().rate
        T.ok(type(st) == "string", "case " .. i .. ": expected a reason, got " .. tostring(st))
        T.has(st, "runs as Lua", want)
        bits_equal(ec, el, "case " .. i)
    end
    dfle_test_last = nil
end

tests["helpers nested deeper than the tracer follows run as Lua"] = function()
    local f = function(x) return x * 2 end
    for _ = 1, 10 do
        local g = f
        f = function(x) return g(x) + 1 end
    end
    local c, l = pair{ rate = function(c, p) return 1e-9 * f(c.S) end }
    local ec, el = e_df(c), e_df(l)
    T.has(c:compiled().rate, "runs as Lua", "nested more than")
    bits_equal(ec, el, "nested helpers")
    local shallow = dfle.law.define{ rate = function(c, p) return 1e-9 * c.S end, integrand = { h = 1 } }
    e_df(shallow)
    T.eq(shallow:compiled().integrand, true, "a table integrand is C")
end

tests["a law with side effects is called per node, as written"] = function()
    local calls = 0
    local law = dfle.law.define{ rate = function(c, p) calls = calls + 1 return 1e-9 * c.S end }
    local ec, m = e_df(law)
    T.has(law:compiled().rate, "assigns to an upvalue")
    local n = 0
    for i = 1, #ec do if ec[i] ~= 0 then n = n + 1 end end
    T.ok(n > 0 and calls >= n, "the counter counts every node")
    T.eq(#m:get("z"), #ec)
end

tests["values read from outside are re-read when the script changes them"] = function()
    local k = 1e-4
    dfle_test_K = 2
    local law = dfle.law.define{
        factor = function(c, p) return c.t_p * c.h * c.Theta end,
        rate = function(c, p) return k * dfle_test_K * c.S ^ 6 * c.F end,
    }
    local function ref(kk)
        return dfle.law.define{ compile = false,
            factor = function(c, p) return c.t_p * c.h * c.Theta end,
            rate = function(c, p) return kk * c.S ^ 6 * c.F end }
    end
    T.close_to_lua(steady_z(law, "direct"), steady_z(ref(2e-4), "direct"), "first")
    T.eq(law:compiled().rate, true)
    k = 3e-4 -- an upvalue
    T.close_to_lua(steady_z(law, "direct"), steady_z(ref(6e-4), "direct"), "upvalue changed")
    dfle_test_K = 1 -- a global
    T.close_to_lua(steady_z(law, "direct"), steady_z(ref(3e-4), "direct"), "global changed")
    dfle_test_K = nil
end

tests["a global changed by U(t) during a run reaches the compiled law"] = function()
    local function run(compile)
        dfle_test_gain = 1
        local law = dfle.law.define{
            compile = compile,
            factor = function(c, p) return c.t_p * c.h * c.Theta end,
            rate = function(c, p) return 1e-4 * dfle_test_gain * c.S ^ 6 * c.F end,
        }
        local m = dfle.model{ channel = channel(), law = law, U = function(t)
            dfle_test_gain = 1 + t / 1000
            return 5e-4
        end }
        m:init_fluvial_steady()
        m:run{ years = 3000, method = "explicit" }
        return m:get("z"), law
    end
    local zc, law = run(true)
    local zl = run(false)
    T.eq(law:compiled().rate, true)
    bits_equal(zc, zl, "U(t) changing a global")
    dfle_test_gain = nil
end

tests["math functions are known by what they are, not by their name"] = function()
    local real_sqrt = math.sqrt
    math.sqrt = math.exp -- a script that renames things
    local ok, err = pcall(function()
        local c, l = pair{ rate = function(c, p) return math.sqrt(-c.S) end }
        local ec, m = e_df(c)
        bits_equal(ec, e_df(l), "math.sqrt = math.exp")
        T.eq(c:compiled().rate, true)
        local S, n = m:get("S"), 0
        for i = 1, #ec do
            if ec[i] ~= 0 then
                T.eq(ec[i], math.exp(-S[i]), "exp, node " .. i)
                n = n + 1
            end
        end
        T.ok(n > 0, "some erosion")
    end)
    math.sqrt = real_sqrt
    if not ok then error(err, 0) end
end

tests["errors from a compiled law are those of the law run as Lua"] = function()
    local law = dfle.law.define{ name = "bad",
        rate = function(c, p) return math.sqrt(-c.S) end }
    local line = debug.getinfo(1, "l").currentline - 1
    local err = T.errors_with(function() e_df(law) end, "law 'bad'", "rate (defined at ",
                              ":" .. line, "expected a finite number", "at node 1")
    T.ok(not err:find("not compilable"), err)
end

tests["the tracer leaves the script's environment as it was"] = function()
    local env = _ENV
    local mt = getmetatable(_G)
    local c = pair{ rate = function(c, p) return helper(c.S) + dfle_test_none_such * 0 end }
    pcall(e_df, c)
    T.ok(_ENV == env and getmetatable(_G) == mt, "environment restored")
    local smt = getmetatable("")
    local s = pair{ rate = function(c, p) return ("ab"):len() * c.S end }
    e_df(s)
    T.eq(getmetatable(""), smt)
    T.eq(smt.__index, string, "strings' methods restored")
    T.eq(("ab"):upper(), "AB")
    T.eq(sqrt, math.sqrt, "upvalue restored")
    T.eq(helper(4), 4)
end

return tests
