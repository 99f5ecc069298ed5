-- test_physics.lua - the model's physics seen through Lua: steady states
-- against the analytical solutions, the fit of Eq. (2), stopping rules
-- and the consistency of the fields a script reads.
local T = ...
local tests = {}

local U = 5e-4

-- The largest |S_i / S_ref(A_i) - 1| over every node but the outlet.
local function worst_rel_error(m, reference)
    local S, A = m:get("S"), m:get("A")
    local worst, at = 0, 0
    for i = 1, m.n - 1 do
        local e = math.abs(S[i] / reference(A[i]) - 1)
        if not (e <= worst) then worst, at = e, i end
    end
    return worst, at
end

tests["fluvial only: relaxes from 3U to the Eq. (26) steady state of U"] = function()
    local fl = dfle.fluvial.stochastic_threshold{}
    local m = dfle.model{ channel = dfle.channel{ dx = 20 }, U = 1.5e-3, fluvial = fl, router = false }
    m:set_U(U)
    local function eq26(A) return fl:steady_slope(U, A) end
    -- The start is far from the target, so convergence means something.
    local before = worst_rel_error(m, eq26)
    T.ok(before > 0.5, "initial misfit " .. before)
    local r = m:run_to_steady{ tol = 1e-4 }
    T.eq(r.converged, true)
    T.eq(r.reason, "steady")
    T.ok(r.rate_ratio <= 1e-4, "rate_ratio " .. r.rate_ratio)
    local worst, at = worst_rel_error(m, eq26)
    T.ok(worst <= 5e-3, string.format("S off Eq. (26) by %.3g at node %d", worst, at))
    -- No debris flows ran, and erosion balances uplift.
    local E_df, E_f = m:get("E_df"), m:get("E_f")
    for i = 1, m.n - 1 do
        T.eq(E_df[i], 0)
        T.close(E_f[i], U, 1e-3, 0, "E_f at node " .. i)
    end
end

tests["debris flows only: converges to Eq. (19) with tau_y = 0"] = function()
    local rt = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500, tau_y = 0 }
    local law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 }
    local m = dfle.model{ channel = dfle.channel{ dx = 20 }, U = U, fluvial = false, router = rt, law = law }
    local function eq19(A) return dfle.analytical_slope(rt, law, { U = U, A = A }) end
    local before = worst_rel_error(m, eq19)
    T.ok(before > 0.05, "initial misfit " .. before)
    local r = m:run_to_steady{ tol = 1e-4 }
    T.eq(r.converged, true)
    T.ok(r.routings > 0, "debris flows were routed")
    local worst, at = worst_rel_error(m, eq19)
    T.ok(worst <= 5e-3, string.format("S off Eq. (19) by %.3g at node %d", worst, at))
    -- Theta = 1 everywhere (tau_y = 0) and no fluvial erosion.
    local Theta, E_f = m:get("Theta"), m:get("E_f")
    for i = 1, m.n - 1 do
        T.close(Theta[i], 1, 1e-12)
        T.eq(E_f[i], 0)
    end
end

tests["steady state: dz/dt = U - E_f - E_df, and |dz/dt| <= tol U"] = function()
    local m = dfle.model{ channel = dfle.channel{ A_max = 1e6, dx = 10 } }
    local tol = 1e-3
    local r = m:run_to_steady{ tol = tol }
    T.eq(r.converged, true)
    local dzdt, E_f, E_df = m:get("dzdt"), m:get("E_f"), m:get("E_df")
    local biggest = 0
    for i = 1, m.n - 1 do
        T.close(dzdt[i], U - E_f[i] - E_df[i], 1e-9, 1e-15, "dz/dt at node " .. i)
        biggest = math.max(biggest, math.abs(dzdt[i]))
    end
    T.ok(biggest <= tol * U * (1 + 1e-9), "max |dz/dt| " .. biggest)
    T.close(r.rate_ratio, biggest / U, 1e-9)
    -- Both processes take part in the steady state of the default model.
    local any_f, any_df = false, false
    for i = 1, m.n - 1 do
        any_f = any_f or E_f[i] > 0
        any_df = any_df or E_df[i] > 0
    end
    T.ok(any_f and any_df, "both fluvial and debris-flow erosion active")
end

tests["router fields: volume, discharge, passage time follow Sect. 2.3"] = function()
    local rt = dfle.router.empirical{ M0 = 3000, gamma = 0.5, tau_y = 300 }
    local m = dfle.model{ channel = dfle.channel{ A_max = 2e5 }, router = rt }
    local A, w, S = m:get("A"), m:get("w"), m:get("S")
    local M, Q, t_p, h, v = m:get("M"), m:get("Q"), m:get("t_p"), m:get("h"), m:get("v")
    local tau, Theta = m:get("tau"), m:get("Theta")
    local flowing = 0
    for i = 1, m.n do
        if h[i] > 0 then
            flowing = flowing + 1
            T.close(M[i], 3000 * (1e-6 * A[i]) ^ 0.5, 1e-9, 0, "M")
            T.close(Q[i], 0.135 * M[i] ^ 0.78, 1e-9, 0, "Q")
            T.close(t_p[i], M[i] / Q[i], 1e-9, 0, "t_p")
            T.close(h[i], (3 * 500 * Q[i] / (1800 * 9.81 * S[i] * w[i])) ^ (1 / 3), 1e-9, 0, "h")
            T.close(v[i], Q[i] / (w[i] * h[i]), 1e-9, 0, "v")
            T.ok(tau[i] >= 300, "flow continues only while tau >= tau_y")
            T.close(Theta[i], 1 - 300 / tau[i], 1e-9, 0, "Theta")
        else
            T.eq(M[i], 0)
            T.eq(tau[i], 0)
        end
    end
    T.ok(flowing > 0, "the flow reached some nodes")
    -- The flow starts at the head and, once stopped, stays stopped.
    T.ok(h[1] > 0, "flow at the head")
    local stopped = false
    for i = 1, m.n do
        if h[i] == 0 then stopped = true end
        T.ok(not (stopped and h[i] > 0), "flow resumed below its runout at node " .. i)
    end
end

tests["model:run: advances time by `years` and stops for reason 'time'"] = function()
    local m = dfle.model{ channel = dfle.channel{ A_max = 2e5 } }
    local r = m:run{ years = 1000 }
    T.eq(r.reason, "time")
    T.eq(r.converged, false)
    T.close(r.time, 1000, 1e-12)
    T.close(m.time, 1000, 1e-12)
    T.ok(r.steps >= 1 and r.dt_max <= 1000 and r.dt_min > 0, "steps and dt")
    r = m:run{ years = 1000 }
    T.close(m.time, 2000, 1e-12)
    -- max_steps stops the run early.
    r = m:run{ years = 1e6, max_steps = 3 }
    T.eq(r.reason, "steps")
    T.eq(r.steps, 3)
    T.ok(r.time < 1e6)
    T.close(m.time, 2000 + r.time, 1e-12)
end

tests["model:run: plain time stepping ignores the steady state"] = function()
    local m = dfle.model{ channel = dfle.channel{ A_max = 2e5 }, router = false }
    -- Start at the fluvial steady state: run_to_steady stops at once...
    local r = m:run_to_steady{}
    T.eq(r.reason, "steady")
    T.eq(r.steps, 0)
    T.eq(m.time, 0)
    -- ...while run{} keeps going for the years asked.
    r = m:run{ years = 5000 }
    T.eq(r.reason, "time")
    T.close(m.time, 5000, 1e-12)
end

tests["model:run_to_steady: max_time bounds an unconverged run"] = function()
    local m = dfle.model{ channel = dfle.channel{ A_max = 2e5 }, U = 1.5e-3 }
    m:set_U(5e-4)
    local r = m:run_to_steady{ tol = 1e-6, max_time = 3000, method = "explicit" }
    T.eq(r.converged, false)
    T.eq(r.reason, "time")
    T.close(r.time, 3000, 1e-12)
    T.ok(r.rate_ratio > 1e-6)
end

tests["uplift: a higher U gives steeper steady slopes (S ~ U^(1/n))"] = function()
    local fl = dfle.fluvial.stream_power{ K = 1e-5, m = 0.5, n = 1 }
    local function steady_S1(u)
        local m = dfle.model{ channel = dfle.channel{ A_max = 2e5 }, U = u, fluvial = fl, router = false }
        local z = {}
        for i = 1, m.n do z[i] = (m.n - i) * 0.5 end
        m:set_z(z)
        T.eq(m:run_to_steady{ tol = 1e-5 }.converged, true)
        return m:get("S")[1], m:get("A")[1]
    end
    local s1, A1 = steady_S1(1e-4)
    local s2 = steady_S1(4e-4)
    T.close(s2 / s1, 4, 1e-3)
    T.close(s1, 1e-4 / 1e-5 * A1 ^ -0.5, 1e-3)
end

tests["fit_slope_area: recovers S_df, A_df, a2 of synthetic Eq. (2) data"] = function()
    local A, S = {}, {}
    local S_df, A_df, a2 = 0.8, 1e5, 0.9
    for i = 1, 400 do
        A[i] = 10 ^ (3 + 4 * (i - 1) / 399)
        S[i] = S_df / (1 + (A[i] / A_df) ^ a2)
    end
    -- The options table is passed explicitly: without it the call fails
    -- (and without one, below).
    local f = assert(dfle.fit_slope_area({ A = A, S = S }, {}))
    T.close(f.S_df, S_df, 1e-2)
    T.close(f.A_df, A_df, 2e-2)
    T.close(f.a2, a2, 1e-2)
    T.ok(f.r2 > 0.999, "r2 " .. f.r2)
    -- S_max - S_ch: Eq. (2) falls monotonically, so the head is the max.
    T.close(f.S_max_minus_S_ch, 0, 0, 1e-12)
    -- A different curve gives different parameters (the fit is not canned).
    for i = 1, #A do S[i] = 0.5 / (1 + (A[i] / 3e4) ^ 1.2) end
    local g = assert(dfle.fit_slope_area({ A = A, S = S }, { nbins = 50 }))
    T.close(g.S_df, 0.5, 1e-2)
    T.close(g.A_df, 3e4, 2e-2)
    T.close(g.a2, 1.2, 1e-2)
end

tests["fit_slope_area: S_max - S_ch measures a hump near the head"] = function()
    local A, S = {}, {}
    for i = 1, 300 do
        A[i] = 10 ^ (3 + 4 * (i - 1) / 299)
        -- Rises from 0.5 at the head to about 0.8, then falls off.
        S[i] = 0.8 / (1 + (A[i] / 1e5) ^ 0.9) - 0.3 * math.exp(-(A[i] / 3e3))
    end
    local f = assert(dfle.fit_slope_area({ A = A, S = S }, { nbins = 100 }))
    T.ok(f.S_max_minus_S_ch > 0.1, "S_max - S_ch " .. f.S_max_minus_S_ch)
    T.close(f.S_max_minus_S_ch, f.S_max - f.S_ch, 1e-12)
end

-- lua_analysis.c l_fit_slope_area: get_slope_area() pushes the A and S
-- arrays onto the stack before get_nbins() reads argument 2, so with a
-- single argument the A array is taken for the options table:
--   dfle.fit_slope_area{A = {...}, S = {...}}
--   --> "dfle.fit_slope_area: parameters are named (key = value); got a number key"
tests["fit_slope_area{A =, S =} works without an options argument"] = function()
    local A, S = {}, {}
    for i = 1, 200 do
        A[i] = 10 ^ (3 + 4 * (i - 1) / 199)
        S[i] = 0.8 / (1 + (A[i] / 1e5) ^ 0.9)
    end
    local f = assert(dfle.fit_slope_area{ A = A, S = S })
    T.close(f.A_df, 1e5, 2e-2)
end

-- lua_plot.c l_plot_slope_area: plot_pairs() pushes the A and S arrays
-- onto the stack, so an absent 3rd argument is taken to be the A array
-- ("fit table lacks number 'S_df'") and an absent 4th the scratch copy.
tests["plot.slope_area({A =, S =}, path) works without fit and options"] = function()
    local A, S = {}, {}
    for i = 1, 100 do
        A[i] = 10 ^ (3 + 4 * (i - 1) / 99)
        S[i] = 0.8 / (1 + (A[i] / 1e5) ^ 0.9)
    end
    local p = T.tmpname(".png")
    dfle.plot.slope_area({ A = A, S = S }, p)
    T.eq(assert(T.read_file(p)):sub(1, 4), "\137PNG")
end

tests["fit_slope_area: a model's fit matches the fit of its own (A, S) pairs"] = function()
    local m = dfle.model{ channel = dfle.channel{ A_max = 1e6, dx = 10 } }
    m:run_to_steady{}
    local A, S = m:get("A"), m:get("S")
    -- The model's fit uses the nodes above the outlet.
    A[#A], S[#S] = nil, nil
    local f1 = assert(dfle.fit_slope_area(m, { nbins = 30 }))
    local f2 = assert(dfle.fit_slope_area({ A = A, S = S }, { nbins = 30 }))
    for _, k in ipairs{ "S_df", "A_df", "a2", "r2", "S_max_minus_S_ch" } do
        T.close(f1[k], f2[k], 1e-9, 1e-12, k)
    end
end

return tests
