-- test_laws.lua - erosion laws written in Lua (dfle.law.define) and the
-- built-in inertial and excess-stress laws: a Lua law equal to a built-in
-- one gives the same steady state with both routers and every method;
-- errors in user code stop the run with the law's name, the user's
-- file:line and a traceback; frequency(A) is evaluated once per area.
-- (A Lua law in a parallel ensemble is left to the ensemble runner's tests.)
local tests = {}

local function small_channel()
    return dfle.channel{ dx = 20, A_max = 1e6 }
end

-- Eq. (6) in Lua, split as the paper caches it: the flow factor after
-- each routing, the slope part every step.
local function lua_eq6(k_df, alpha, beta)
    return dfle.law.define{
        name = "eq6",
        params = { k_df = k_df or 1e-4, alpha = alpha or 6, beta = beta or 1 },
        factor = function(c, p)
            if c.I ~= 0 then return c.I end -- time-resolved: the Eq. (11) sum
            return c.t_p * c.h ^ p.beta * c.Theta
        end,
        rate = function(c, p) return p.k_df * c.S ^ p.alpha * c.F end,
        integrand = { h = beta or 1 },
    }
end

-- Eq. (6) as one rate function that reads the flow itself.
local function lua_eq6_rate_only()
    return dfle.law.define{
        name = "eq6r", params = { k_df = 1e-4, alpha = 6, beta = 1 },
        rate = function(c, p) return p.k_df * c.S ^ p.alpha * c.t_p * c.h ^ p.beta * c.Theta end,
    }
end

local function steady_z(law, opts)
    opts = opts or {}
    local m = dfle.model{ channel = opts.channel or small_channel(), law = law,
                          router = opts.router }
    m:init_fluvial_steady()
    local r = opts.years and m:run{ years = opts.years, method = opts.method }
                          or m:run_to_steady{ method = opts.method }
    if not opts.years then T.ok(r.converged, "no steady state with " .. law.name) end
    return m:get("z"), m
end

local function same_profile(a, b, rel, what)
    T.eq(#a, #b, what)
    for i = 1, #a do T.close(a[i], b[i], rel, 0, what .. " at node " .. i) end
end

tests["define: a Lua Eq. (6) matches the built-in law, empirical router, every method"] = function()
    for _, method in ipairs{ "explicit", "implicit", "direct" } do
        local ref = steady_z(dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 }, { method = method })
        same_profile(steady_z(lua_eq6(), { method = method }), ref, 1e-9, method .. " (split)")
        same_profile(steady_z(lua_eq6_rate_only(), { method = method }), ref, 1e-9,
                     method .. " (rate only)")
    end
end

tests["define: a Lua Eq. (6) matches the built-in law, process router"] = function()
    local ch = dfle.channel{ dx = 20, A_max = 2e5 }
    local function run(law, method)
        return steady_z(law, { channel = ch, router = dfle.router.process{}, method = method })
    end
    local lua_integrand = dfle.law.define{
        name = "eq6g", params = { k_df = 1e-4, alpha = 6 },
        rate = function(c, p) return p.k_df * c.S ^ p.alpha * c.F end,
        integrand = function(h, v, lambda, p) return h end,
    }
    for _, method in ipairs{ "direct", "implicit" } do
        local ref = run(dfle.law.power{}, method)
        same_profile(run(lua_eq6(), method), ref, 1e-9, method .. " (integrand {h = 1})")
        same_profile(run(lua_integrand, method), ref, 1e-9, method .. " (integrand function)")
    end
end

tests["define: name, params and errors in the definition"] = function()
    local law = lua_eq6(2e-4, 5, 1.5)
    T.eq(law.name, "eq6")
    T.eq(law.k_df, 2e-4)
    T.eq(law:params().alpha, 5)
    T.eq(tostring(law), "dfle.law.eq6(alpha = 5, beta = 1.5, k_df = 0.0002)")
    -- The law keeps its own copy of params.
    local p = { k = 1 }
    local l2 = dfle.law.define{ params = p, rate = function(c, q) return q.k end }
    p.k = 2
    T.eq(l2.k, 1)
    T.eq(l2.name, "lua")
    T.raises_here(function() return dfle.law.define{ params = {} } end, "'rate'", "is required")
    T.raises_here(function() return dfle.law.define{ rate = 1 } end, "'rate' must be a function")
    T.raises_here(function() return dfle.law.define{ rate = print, factor = "x" } end,
                  "'factor' must be a function")
    T.raises_here(function() return dfle.law.define{ rate = print, rates = print } end,
                  "unknown parameter 'rates'", "frequency")
    T.raises_here(function() return dfle.law.define{ rate = print, integrand = { beta = 1 } } end,
                  "unknown parameter 'beta'", "h, v, lambda")
    T.raises_here(function() return dfle.law.define{ rate = print, integrand = 3 } end,
                  "'integrand' must be a function")
    T.raises_here(function() return dfle.law.define{ rate = print, params = 3 } end,
                  "'params' must be a table")
end

-- The run must fail with the law's name, the position of `fn`'s
-- definition (file:line) and every text given.
local function run_fails(law, opts, ...)
    local msg = T.errors_with(function() steady_z(law, opts) end, "dfle.law." .. law.name, ...)
    return msg
end

local function line_of(fn)
    local info = debug.getinfo(fn, "S")
    return info.short_src .. ":" .. info.linedefined
end

tests["errors: wrong return type names the law, the node and the user's line"] = function()
    local rate = function(c, p) return "fast" end
    local law = dfle.law.define{ name = "wrongtype", rate = rate }
    for _, method in ipairs{ "explicit", "direct" } do
        run_fails(law, { method = method }, "law 'wrongtype': rate (defined at " .. line_of(rate) .. ")",
                  "returned string, expected a number", "S = ", "A = ")
    end
    local msg = run_fails(law, { method = "explicit" }, "at node 1")
    T.match(msg, "^[^\n]*test_laws%.lua:%d+: dfle%.law%.wrongtype")
end

tests["errors: NaN from factor or frequency names the law, the node and the user's line"] = function()
    local factor = function(c, p) return 0 / 0 end
    local law = dfle.law.define{ name = "nan", factor = factor, rate = function(c) return c.F end }
    run_fails(law, {}, "factor (defined at " .. line_of(factor) .. ")", "returned NaN",
              "expected a finite number")
    local freq = function(A) return -1 end
    local law2 = dfle.law.define{ name = "negfreq", rate = function() return 1e-3 end, frequency = freq }
    run_fails(law2, {}, "frequency (defined at " .. line_of(freq) .. ")", "returned -1",
              "expected a finite number >= 0")
end

tests["errors: a runtime error carries the user's line and a traceback"] = function()
    local rate = function(c, p) return c.nope + 1 end
    local law = dfle.law.define{ name = "oops", rate = rate }
    for _, method in ipairs{ "explicit", "implicit", "direct" } do
        run_fails(law, { method = method }, line_of(rate) .. ": attempt to perform arithmetic on a nil value (field 'nope')",
                  "stack traceback:")
    end
    -- error() with a message of the user's own.
    local law2 = dfle.law.define{ name = "raises", rate = function() error("bad parameter set") end }
    run_fails(law2, {}, "test_laws.lua", "bad parameter set")
end

tests["errors: a failing integrand stops a process-router run"] = function()
    local g = function(h, v, lambda, p) return h.x end
    local law = dfle.law.define{ name = "badg", rate = function(c) return c.F end, integrand = g }
    run_fails(law, { channel = dfle.channel{ dx = 20, A_max = 2e5 }, router = dfle.router.process{} },
              line_of(g) .. ": attempt to index a number value (local 'h')")
    local g2 = function() return "x" end
    local law2 = dfle.law.define{ name = "badg2", rate = function(c) return c.F end, integrand = g2 }
    run_fails(law2, { channel = dfle.channel{ dx = 20, A_max = 2e5 }, router = dfle.router.process{} },
              "integrand (defined at " .. line_of(g2) .. ") returned string")
    local law3 = dfle.law.define{ name = "nog", rate = function(c) return c.F end }
    run_fails(law3, { channel = dfle.channel{ dx = 20, A_max = 2e5 }, router = dfle.router.process{} },
              "has no integrand")
end

tests["define: with the process router, rate sees the slope part only"] = function()
    local rate = function(c, p) return 1e-4 * c.S ^ 6 * c.h end
    local law = dfle.law.define{ name = "flowinrate", rate = rate, integrand = { h = 1 } }
    run_fails(law, { channel = dfle.channel{ dx = 20, A_max = 2e5 }, router = dfle.router.process{} },
              line_of(rate) .. ": attempt to perform arithmetic on a nil value (field 'h')")
end

tests["errors: the law works again once the user's code is fixed"] = function()
    local broken = true
    local law = dfle.law.define{
        name = "flaky", params = { k_df = 1e-4, alpha = 6 },
        rate = function(c, p)
            if broken then error("not yet") end
            return p.k_df * c.S ^ p.alpha * c.t_p * c.h * c.Theta
        end,
    }
    local m = dfle.model{ channel = small_channel(), law = law }
    T.errors_with(function() m:run_to_steady{} end, "not yet")
    broken = false
    T.ok(m:run_to_steady{}.converged)
end

tests["frequency(A): multiplies the rate and is called once per drainage area"] = function()
    local calls, areas = 0, {}
    local law = dfle.law.define{
        name = "freq", params = { k_df = 1e-4, alpha = 6, f = 0.5 },
        factor = function(c, p) return c.t_p * c.h * c.Theta end,
        rate = function(c, p) return 2 * p.k_df * c.S ^ p.alpha * c.F end,
        frequency = function(A, p) calls = calls + 1; areas[A] = true; return p.f end,
    }
    local z, m
    for _, method in ipairs{ "explicit", "implicit", "direct" } do
        local ref = steady_z(dfle.law.power{ k_df = 1e-4 }, { method = method })
        z, m = steady_z(law, { method = method })
        same_profile(z, ref, 1e-9, "2 k_df * f = k_df, " .. method)
    end
    local distinct = 0
    for _ in pairs(areas) do distinct = distinct + 1 end
    T.eq(calls, distinct, "calls of frequency(A)")
    T.ok(distinct <= m.n)
end

tests["frequency(A): an area-dependent frequency changes the steady state"] = function()
    -- Appendix D generalised: fewer flows per year further down the fan.
    local law = dfle.law.define{
        name = "freqA", params = { k_df = 1e-4, alpha = 6 },
        factor = function(c, p) return c.t_p * c.h * c.Theta end,
        rate = function(c, p) return p.k_df * c.S ^ p.alpha * c.F end,
        frequency = function(A) return (A / 1e4) ^ -0.3 end,
    }
    local _, m = steady_z(law)
    local _, m0 = steady_z(dfle.law.power{})
    local S, S0, A = m:get("S"), m0:get("S"), m:get("A")
    -- Where A > 1e4 m^2 the flows are rarer, so the debris-flow reach is steeper.
    for i = 1, 5 do
        if A[i] > 2e4 and m0:get("E_df")[i] > 0.5 * 5e-4 then T.ok(S[i] > S0[i], "node " .. i) end
    end
end

-- The inertial law written in Lua, as the issue's example.  For the
-- process router the factor is the default one (F = I, the Eq. (11) sum
-- of the integrand).
local function lua_inertial(o, process)
    return dfle.law.define{
        name = "inertial_lua", params = o,
        factor = not process and function(c, p)
            if c.Theta <= 0 then return 0 end
            local shear = c.v / c.h
            return c.t_p * p.rho_s * (p.D * shear) ^ 2
        end or nil,
        rate = function(c, p) return p.k * c.S ^ p.alpha * c.F end,
        integrand = function(h, v, lambda, p) return p.rho_s * (p.D * v / h) ^ 2 end,
    }
end

tests["inertial: the built-in law equals its Lua definition (both routers)"] = function()
    local o = { k = 3e-7, D = 0.09, rho_s = 2600, alpha = 1.5 }
    local law = dfle.law.inertial(o)
    T.eq(law.name, "inertial")
    T.eq(law.D, 0.09)
    T.has(tostring(law), "dfle.law.inertial(k = 3e-07")
    for _, method in ipairs{ "explicit", "direct" } do
        same_profile(steady_z(lua_inertial(o), { method = method }),
                     steady_z(law, { method = method }), 1e-9, "empirical, " .. method)
    end
    local ch = dfle.channel{ dx = 20, A_max = 2e5 }
    local po = { k = 1e-8, D = 0.09, rho_s = 2600, alpha = 1.5 }
    same_profile(steady_z(lua_inertial(po, true), { channel = ch, router = dfle.router.process{} }),
                 steady_z(dfle.law.inertial(po), { channel = ch, router = dfle.router.process{} }),
                 1e-9, "process")
    -- The formula itself, node by node, on a profile that is not steady.
    local m = dfle.model{ channel = small_channel(), law = law }
    local E, S, h, v, t_p, Th = m:get("E_df"), m:get("S"), m:get("h"), m:get("v"), m:get("t_p"),
                                m:get("Theta")
    local checked = 0
    for i = 1, m.n - 1 do
        if Th[i] > 0 then
            T.close(E[i], o.k * S[i] ^ o.alpha * t_p[i] * o.rho_s * (o.D * v[i] / h[i]) ^ 2, 1e-12, 0,
                    "E_df at node " .. i)
            checked = checked + 1
        else
            T.eq(E[i], 0)
        end
    end
    T.ok(checked > 3, "flow reaches a few nodes")
    T.raises_here(function() return dfle.law.inertial{ D = 0 } end, "D must be > 0")
    T.raises_here(function() return dfle.law.inertial{ d = 1 } end, "unknown parameter 'd'")
end

tests["excess_stress: the built-in law equals its Lua definition"] = function()
    local o = { k = 2e-9, tau_c = 400, p = 1.5 }
    local law = dfle.law.excess_stress(o)
    T.eq(law.name, "excess_stress")
    T.eq(law.tau_c, 400)
    local lua = dfle.law.define{
        name = "excess_lua", params = o,
        factor = function(c, p)
            local x = c.tau - p.tau_c
            if x <= 0 or c.Theta <= 0 then return 0 end
            return x ^ p.p
        end,
        rate = function(c, p) return p.k * c.F end,
    }
    for _, method in ipairs{ "explicit", "direct" } do
        same_profile(steady_z(lua, { method = method }), steady_z(law, { method = method }), 1e-9,
                     method)
    end
    local m = dfle.model{ channel = small_channel(), law = law }
    local E, tau = m:get("E_df"), m:get("tau")
    local checked = 0
    for i = 1, m.n - 1 do
        local x = tau[i] - o.tau_c
        T.close(E[i], x > 0 and o.k * x ^ o.p or 0, 1e-12, 0, "E_df at node " .. i)
        if x > 0 then checked = checked + 1 end
    end
    T.ok(checked > 3, "stress above tau_c at a few nodes")
    T.errors_with(function()
        steady_z(law, { channel = dfle.channel{ dx = 20, A_max = 2e5 }, router = dfle.router.process{} })
    end, "integrand")
    T.raises_here(function() return dfle.law.excess_stress{ p = 0 } end, "p must be > 0")
    T.raises_here(function() return dfle.law.excess_stress{ tau_c = -1 } end, "tau_c must be >= 0")
end

tests["define: fields seen by the law, with their values"] = function()
    local seen
    local law = dfle.law.define{
        name = "probe",
        rate = function(c, p)
            if seen == nil then
                seen = {}
                for _, k in ipairs{ "S", "A", "w", "h", "v", "t_p", "tau", "Theta", "Q", "M", "I", "F" } do
                    seen[k] = c[k]
                end
            end
            return 0
        end,
    }
    local m = dfle.model{ channel = small_channel(), law = law }
    m:init_fluvial_steady()
    m:get("E_df")
    for _, k in ipairs{ "S", "A", "w", "h", "v", "t_p", "tau", "Theta", "Q", "M" } do
        T.close(seen[k], m:get(k)[1], 1e-15, 0, k)
    end
    T.eq(seen.I, 0)
    T.eq(seen.F, 1)
end

tests["U(t): uplift as a function of time, evaluated every step"] = function()
    local calls = 0
    local ch = small_channel()
    local m = dfle.model{ channel = ch, U = function(t)
        calls = calls + 1
        return t < 5e4 and 5e-4 or 1e-3
    end }
    T.eq(m.U, 5e-4) -- U(0)
    m:init_fluvial_steady()
    local r = m:run{ years = 1e5 }
    T.eq(m.U, 1e-3)
    T.ok(calls >= r.steps, "one call per step at least")
    -- Its steady state is that of the final uplift rate.
    T.ok(m:run_to_steady{}.converged)
    local ref = dfle.model{ channel = ch, U = 1e-3 }
    ref:init_fluvial_steady()
    ref:run_to_steady{}
    same_profile(m:get("z"), ref:get("z"), 1e-9, "U(t) -> 1e-3")
    -- A constant set later replaces the function.
    m:set_U(5e-4)
    m:run{ years = 1e3 }
    T.eq(m.U, 5e-4)
end

tests["U(t): errors and bad values stop the run with the user's line"] = function()
    local f = function(t) if t > 10 then error("no uplift data after 10 yr") end return 5e-4 end
    local m = dfle.model{ channel = small_channel(), U = f }
    T.errors_with(function() m:run{ years = 1e4 } end, "dfle.model: U(t) failed at t = ",
                  line_of(f) .. ": no uplift data after 10 yr", "stack traceback:")
    local m2 = dfle.model{ channel = small_channel(), U = function(t) return t > 10 and -1 or 5e-4 end }
    T.errors_with(function() m2:run{ years = 1e4 } end, "U(t) must be > 0 m/yr (got -1")
    local m3 = dfle.model{ channel = small_channel(), U = function(t) return t > 10 and "x" or 5e-4 end }
    T.errors_with(function() m3:run{ years = 1e4 } end, "U(t) must return a number, got string")
    T.raises_here(function() return dfle.model{ U = function() return {} end } end,
                  "U(t) must return a number, got table (at t = 0)")
    T.raises_here(function() return dfle.model{ U = function() return -1 end } end, "U must be > 0")
end

-- The empirical router (router_empirical.h) written in Lua.
local function lua_empirical(o)
    return dfle.router.define{
        name = "empirical_lua",
        params = o or { M0 = 3000, gamma = 0.5, mu = 500, tau_y = 300, c1 = 0.135, c2 = 0.78,
                        rho_b = 1800, g = 9.81 },
        flow = function(c, p)
            local M = p.M0 * (1e-6 * c.A) ^ p.gamma
            local Q = p.c1 * M ^ p.c2
            local h = (3 * p.mu * Q / (p.rho_b * p.g * c.w) / c.S) ^ (1 / 3)
            local tau = p.rho_b * p.g * (c.w * h / (c.w + 2 * h)) * c.S / math.sqrt(1 + c.S * c.S)
            c.M, c.Q, c.h, c.v, c.t_p = M, Q, h, Q / (c.w * h), M / Q
            c.tau, c.Theta = tau, 1 - p.tau_y / tau
            return tau >= p.tau_y
        end,
    }
end

tests["router.define: a Lua empirical router matches the built-in one, every method"] = function()
    local rt = lua_empirical()
    T.eq(rt.name, "empirical_lua")
    T.eq(rt.mu, 500)
    T.eq(rt:params().tau_y, 300)
    T.eq(tostring(rt), "dfle.router.empirical_lua(M0 = 3000, c1 = 0.135, c2 = 0.78, g = 9.81, "
                       .. "gamma = 0.5, mu = 500, rho_b = 1800, tau_y = 300)")
    for _, method in ipairs{ "explicit", "implicit", "direct" } do
        local ref = steady_z(dfle.law.power{}, { method = method, router = dfle.router.empirical{} })
        same_profile(steady_z(dfle.law.power{}, { method = method, router = rt }), ref, 1e-9,
                     method)
        -- Lua router and Lua law together.
        same_profile(steady_z(lua_eq6(), { method = method, router = rt }), ref, 1e-9,
                     method .. ", Lua law")
    end
    -- rt:route(m) works like the built-in router's.
    local m = dfle.model{ channel = small_channel(), router = rt }
    local r, r0 = rt:route(m), dfle.router.empirical{}:route(m)
    T.eq(r.runout_end, r0.runout_end)
    for i = 1, #r0.h do T.close(r.h[i], r0.h[i], 1e-12, 0, "h at " .. i) end
end

tests["router.define: rt:route(m) with the model's own router routes once"] = function()
    local calls = 0
    local rt = dfle.router.define{
        name = "counted",
        flow = function(c, p)
            calls = calls + 1
            c.h, c.v, c.t_p, c.tau = 1, 1, 100, 1000
            return true
        end,
    }
    local m = dfle.model{ channel = small_channel(), router = rt }
    rt:route(m)             -- the model not evaluated yet: its slopes alone are needed
    local route = calls
    calls = 0
    m:get("S")              -- an evaluation routes the model's flow once
    T.ok(calls > 0)
    T.eq(route, calls)
end

tests["router.define: errors in flow() carry the user's line, every method"] = function()
    local flow = function(c, p)
        if c.S < 0.3 then error("no relation for gentle slopes") end
        c.h, c.v, c.t_p = 1, 1, 1
        return true
    end
    local rt = dfle.router.define{ name = "gentle", flow = flow }
    for _, method in ipairs{ "explicit", "implicit", "direct" } do
        T.errors_with(function() steady_z(dfle.law.power{}, { router = rt, method = method }) end,
                      "dfle.router.gentle: ", "test_laws.lua:", "no relation for gentle slopes",
                      "stack traceback:")
    end
    local noh = function(c, p) c.v, c.t_p = 1, 1 return true end
    T.errors_with(function() steady_z(dfle.law.power{}, { router = dfle.router.define{ name = "noh", flow = noh } }) end,
                  "router 'noh': flow (defined at " .. line_of(noh) .. ") set h to nil, expected a number",
                  "at node 1")
    local nanv = function(c, p) c.h, c.v, c.t_p = 1, 0 / 0, 1 return true end
    T.errors_with(function() steady_z(dfle.law.power{}, { router = dfle.router.define{ name = "nanv", flow = nanv }, method = "explicit" }) end,
                  "set v to NaN, expected a finite number")
    T.raises_here(function() return dfle.router.define{ name = "x" } end, "'flow'", "is required")
    T.raises_here(function() return dfle.router.define{ flow = print, depth = print } end,
                  "unknown parameter 'depth'")
end

return tests
