-- test_population_mobility.lua - populations whose mobility varies:
-- factors on the viscosity mu and the yield strength tau_y beside the
-- volume (dfle.router.population{mu =, tau_y =}), checked against the
-- closed form where Theta = 1, a quadrature done by hand over flows
-- routed one by one, the volume-only population as the zero-width
-- limit, and events.
local T = ...
local tests = {}

local U = 5e-4
local function kappa(c2, beta) return 1 - c2 + c2 * beta / 3 end

local function model(rt, law, channel)
    return dfle.model{ channel = channel or dfle.channel{ dx = 20 }, U = U, fluvial = false,
                       router = rt, law = law }
end

tests["Theta = 1: E_df is lambda E[f^kappa] E[g^(beta/3)] times the characteristic rate"] = function()
    -- h ~ (mu Q / S w)^(1/3) and t_p = M / Q: with tau_y = 0 one flow
    -- erodes S^alpha t_p h^beta ~ M^kappa mu^(beta/3).
    local rt = dfle.router.empirical{ tau_y = 0 }
    for _, beta in ipairs{ 1, 2 } do
        local law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = beta }
        local volume = { kind = "lognormal", sigma = 0.8 }
        local cases = {
            { mu = { kind = "lognormal", sigma = 0.7, median = 1.3 }, order = 16 },
            { mu = { kind = "uniform", f_min = 0.2, f_max = 2 }, order = 16 },
            { mu = { kind = "power_law", b = 1.5, f_min = 0.1, f_max = 10 }, order = 24 },
        }
        local E1 = model(rt, law):get("E_df")
        for c, case in ipairs(cases) do
            local pop = dfle.router.population{ router = rt, volume = volume, order = 16,
                                                frequency = 2, mu = case.mu,
                                                mobility_order = case.order }
            local E2 = model(pop, law):get("E_df")
            local factor = 2 * dfle.router.moment(volume, kappa(0.78, beta))
                             * dfle.router.moment(case.mu, beta / 3)
            for i = 1, #E1 - 1 do
                T.ok(E1[i] > 0, "node eroded")
                T.close(E2[i], factor * E1[i], 1e-10, 0, ("beta %g, case %d, node %d"):format(beta, c, i))
            end
        end
    end
    -- tau_y factors on tau_y = 0 change nothing (Theta stays 1).
    local law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 }
    local pop = dfle.router.population{ router = rt, volume = { kind = "table", values = { 1 } },
                                        tau_y = { kind = "uniform", f_min = 0.5, f_max = 2 } }
    T.eq(#dfle.router.quadrature(pop).f, 8, "eight tau_y flows")
    local E1, E2 = model(rt, law):get("E_df"), model(pop, law):get("E_df")
    for i = 1, #E1 do T.close(E2[i], E1[i], 1e-13, 0, "node " .. i) end
end

-- A profile steep at the head, flattening down the channel: flows of
-- different volume and yield strength stop at different nodes.
local function runout_model(rt, law)
    local m = model(rt, law, dfle.channel{ dx = 20, length = 400 })
    local x = m:get("x")
    local z = {}
    for i = 1, m.n do z[i] = 60 * (1 - x[i] / x[m.n]) ^ 2 end
    m:set_z(z)
    return m
end

tests["runout: volume x tau_y x mu, against flows routed one by one and summed by hand"] = function()
    local o = { M0 = 3000, mu = 500, tau_y = 650 }
    local law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 }
    local lambda = 3
    -- Tables for volume and mu; tau_y uniform on [0.5, 1.5], whose
    -- 3-point Gauss-Legendre rule is worked out here: nodes 1 and
    -- 1 -+ 0.5 sqrt(3/5), weights 8/18 and 5/18.
    local fv, wv = { 0.05, 1, 20 }, { 5, 3, 2 }
    local fm, wm = { 0.5, 2 }, { 1, 1 }
    local r35 = 0.5 * math.sqrt(3 / 5)
    local ft, wt = { 1 - r35, 1, 1 + r35 }, { 5 / 18, 8 / 18, 5 / 18 }
    local pop = dfle.router.population{
        router = dfle.router.empirical(o), frequency = lambda,
        volume = { kind = "table", values = fv, weights = wv },
        mu = { kind = "table", values = fm, weights = wm },
        tau_y = { kind = "uniform", f_min = 0.5, f_max = 1.5 }, mobility_order = 3 }
    T.eq(#dfle.router.quadrature(pop).f, 18, "3 x 2 x 3 flows")
    local m = runout_model(pop, law)
    local E, reach = {}, {}
    for i = 1, m.n do E[i], reach[i] = 0, 0 end
    local stops = {}
    for a = 1, 3 do
        for b = 1, 2 do
            for c = 1, 3 do
                local rate = lambda * (wv[a] / 10) * (wm[b] / 2) * wt[c]
                local one = dfle.router.empirical{ M0 = o.M0 * fv[a], mu = o.mu * fm[b],
                                                   tau_y = o.tau_y * ft[c] }
                local mj = runout_model(one, law)
                local Ej, rj = mj:get("E_df"), one:route(mj).reach
                local last = 0
                for i = 1, m.n do
                    E[i] = E[i] + rate * Ej[i]
                    reach[i] = reach[i] + rate * rj[i]
                    if rj[i] > 0 then last = i end
                end
                stops[last] = true
            end
        end
    end
    local distinct = 0
    for _ in pairs(stops) do distinct = distinct + 1 end
    T.ok(distinct >= 5, "the flows stop at different nodes: " .. distinct)
    local got, Ep = pop:route(m).reach, m:get("E_df")
    for i = 1, m.n do
        T.close(got[i], reach[i], 1e-12, 0, "reach at node " .. i)
        T.close(Ep[i], E[i], 1e-12, 1e-300, "E_df at node " .. i)
    end
end

tests["zero-width mobility: the volume-only population bit for bit"] = function()
    local rt, law = dfle.router.empirical{}, dfle.law.power{}
    local volume = { kind = "lognormal", sigma = 1 }
    local m1 = dfle.model{ channel = dfle.channel{ dx = 20 }, U = U,
                           router = dfle.router.population{ router = rt, volume = volume }, law = law }
    m1:run_to_steady{}
    for _, d in ipairs{ { kind = "lognormal", sigma = 0 }, { kind = "uniform", f_min = 1, f_max = 1 },
                        { kind = "table", values = { 1 } } } do
        local pop = dfle.router.population{ router = rt, volume = volume, mu = d, tau_y = d }
        local m2 = dfle.model{ channel = dfle.channel{ dx = 20 }, U = U, router = pop, law = law }
        m2:run_to_steady{}
        T.bits_equal(m2:get("z"), m1:get("z"), d.kind .. ": z")
        T.bits_equal(m2:get("E_df"), m1:get("E_df"), d.kind .. ": E_df")
    end
end

tests["events with varying mobility: the long-run mean is the expected rate"] = function()
    local pop = dfle.router.population{
        router = dfle.router.empirical{ tau_y = 650 }, frequency = 2,
        volume = { kind = "table", values = { 0.05, 1, 20 }, weights = { 5, 3, 2 } },
        mu = { kind = "table", values = { 0.5, 2 } },
        tau_y = { kind = "table", values = { 0.6, 1.4 }, weights = { 2, 1 } } }
    local m = runout_model(pop, dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 })
    local E, R = m:get("E_df"), pop:route(m).reach
    local r = m:run_events{ years = 2e4, seed = 9, hold = true }
    local checked, partial = 0, 0
    for i = 1, m.n - 1 do
        if E[i] > 0 then
            T.ok(math.abs(r.mean[i] - E[i]) <= 4 * r.se[i],
                 ("node %d: mean %.6g, expected %.6g, se %.3g"):format(i, r.mean[i], E[i], r.se[i]))
            checked = checked + 1
            if R[i] < 2 * (1 - 1e-12) then partial = partial + 1 end
        end
    end
    T.ok(checked >= 5 and partial >= 3, ("checked %d nodes, %d reached by part"):format(checked, partial))
end

tests["mobility: parameters are checked and named"] = function()
    local rt = dfle.router.empirical{}
    local v = { kind = "lognormal", sigma = 1 }
    T.raises_here(function() return dfle.router.population{ router = rt, volume = v, mu = { kind = "gamma" } } end,
                  "mu kind")
    T.raises_here(function() return dfle.router.population{ router = rt, volume = v, tau_y = { kind = "lognormal" } } end,
                  "lognormal tau_y needs sigma")
    T.raises_here(function() return dfle.router.population{ router = rt, volume = v, mu = { kind = "lognormal", sigma = -1 } } end,
                  "population: mu: lognormal sigma must be >= 0")
    T.raises_here(function() return dfle.router.population{ router = rt, volume = v, tau_y = { kind = "table", values = { 1, -1 } } } end,
                  "population: tau_y: table value 2 must be > 0")
    T.raises_here(function() return dfle.router.population{ router = rt, volume = v, mu = 3 } end,
                  "parameter 'mu' must be a table")
    T.raises_here(function() return dfle.router.population{ router = rt, volume = v, mu = v, mobility_order = 0 } end,
                  "mobility_order")
    T.raises_here(function() return dfle.router.population{ router = rt, volume = v, order = 64, mu = v, tau_y = v, mobility_order = 9 } end,
                  "more than 4096")
end

return tests
