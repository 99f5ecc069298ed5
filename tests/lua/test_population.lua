-- test_population.lua - debris flows as a population (dfle.router.population):
-- the characteristic flow as its zero-width limit, the closed-form
-- expectation where Theta = 1, the modified Eq. (19), and the expected
-- frequency of flows reaching each node worked out by hand.
local T = ...
local tests = {}

local U = 5e-4
-- Eqs. (6), (15), (16) with Theta = 1: E_df ~ t_p h^beta ~ M^kappa with
-- kappa = (1 - c2) + c2 beta / 3.
local function kappa(c2, beta) return 1 - c2 + c2 * beta / 3 end

local function model(rt, law, opts)
    opts = opts or {}
    return dfle.model{ channel = opts.channel or dfle.channel{ dx = 20 }, U = U,
                       fluvial = opts.fluvial, router = rt, law = law }
end

tests["zero width: the characteristic flow bit for bit, with every solver"] = function()
    local rt, law = dfle.router.empirical{}, dfle.law.power{}
    local dists = {
        { kind = "lognormal", sigma = 0 },
        { kind = "power_law", b = 1.5, f_min = 1, f_max = 1 },
        { kind = "uniform", f_min = 1, f_max = 1 },
        { kind = "table", values = { 1 } },
    }
    for _, method in ipairs{ "direct", "implicit", "explicit" } do
        local m1 = model(rt, law)
        local z0 = m1:get("z")
        T.ok(m1:run_to_steady{ method = method }.converged, method .. " converged")
        T.ok(math.abs(m1:get("z")[1] - z0[1]) > 1, method .. ": the head moved from the start")
        for k, d in ipairs(dists) do
            local pop = dfle.router.population{ router = rt, volume = d, order = 5 }
            local m2 = model(pop, law)
            m2:run_to_steady{ method = method }
            T.bits_equal(m2:get("z"), m1:get("z"), method .. ", volume " .. k)
            T.bits_equal(m2:get("E_df"), m1:get("E_df"), method .. ", volume " .. k .. ", E_df")
        end
    end
    -- A transient too.
    local m1, m2 = model(rt, law), model(dfle.router.population{ router = rt,
                                                                 volume = dists[1] }, law)
    m1:run{ years = 2e4 }
    m2:run{ years = 2e4 }
    T.bits_equal(m2:get("z"), m1:get("z"), "run")
end

tests["Theta = 1: E_df is lambda E[f^kappa] times the characteristic rate"] = function()
    local rt = dfle.router.empirical{ tau_y = 0 }
    local law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 }
    local k = kappa(0.78, 1)
    local cases = {
        { volume = { kind = "lognormal", sigma = 1.2, median = 0.7 }, order = 16 },
        { volume = { kind = "power_law", b = 1.6, f_min = 0.01, f_max = 100 }, order = 32 },
        { volume = { kind = "power_law", b = 1, f_min = 0.1, f_max = 10 }, order = 24 },
        { volume = { kind = "uniform", f_min = 0.2, f_max = 3 }, order = 16 },
        { volume = { kind = "table", values = { 0.1, 1, 10 }, weights = { 5, 3, 1 } } },
    }
    local m1 = model(rt, law, { fluvial = false })
    local E1 = m1:get("E_df")
    for c, case in ipairs(cases) do
        local pop = dfle.router.population{ router = rt, volume = case.volume, order = case.order,
                                            frequency = 3 }
        local m2 = model(pop, law, { fluvial = false })
        local E2 = m2:get("E_df")
        local factor = 3 * dfle.router.moment(case.volume, k)
        for i = 1, m1.n - 1 do
            T.ok(E1[i] > 0, "every node eroded")
            T.close(E2[i], factor * E1[i], 1e-10, 0, "case " .. c .. ", node " .. i)
        end
    end
    -- The closed forms against sums done here.
    T.close(dfle.router.moment({ kind = "table", values = { 0.1, 1, 10 }, weights = { 5, 3, 1 } }, k),
            (5 * 0.1 ^ k + 3 + 10 ^ k) / 9, 1e-14)
    T.close(dfle.router.moment({ kind = "lognormal", sigma = 0.5, median = 2 }, 2),
            math.exp(2 * math.log(2) + 0.5 * 4 * 0.25), 1e-14)
    T.close(dfle.router.moment({ kind = "uniform", f_min = 1, f_max = 3 }, 1), 2, 1e-14)
end

tests["Theta = 1: the steady slope follows Eq. (19) with k_df lambda E[f^kappa]"] = function()
    local rt = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500, tau_y = 0 }
    local law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 }
    local volume = { kind = "lognormal", sigma = 1 }
    local lambda = 0.5
    local pop = dfle.router.population{ router = rt, volume = volume, order = 16,
                                        frequency = lambda }
    local m = model(pop, law, { fluvial = false })
    local r = m:run_to_steady{ method = "direct" }
    T.ok(r.converged, "converged")
    local shift = (lambda * dfle.router.moment(volume, kappa(0.78, 1))) ^ (-1 / (6 - 1 / 3))
    T.ok(math.abs(shift - 1) > 0.05, "the population moves the slope: " .. shift)
    local S, A = m:get("S"), m:get("A")
    for i = 1, m.n - 1 do
        local S19 = dfle.analytical_slope(rt, law, { U = U, A = A[i] })
        T.close(S[i], S19 * shift, 1e-8, 0, "node " .. i)
    end
end

tests["runout: the expected frequency reaching each node, by hand"] = function()
    local o = { M0 = 3000, gamma = 0.5, mu = 500, tau_y = 650, c1 = 0.135, c2 = 0.78,
                rho_b = 1800, g = 9.81 }
    local rt = dfle.router.empirical(o)
    local law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 }
    local f, wt, lambda = { 0.01, 1, 100 }, { 5, 3, 2 }, 4
    local pop = dfle.router.population{ router = rt, frequency = lambda,
                                        volume = { kind = "table", values = f, weights = wt } }
    local m = model(pop, law, { channel = dfle.channel{ dx = 20, length = 400 }, fluvial = false })
    -- A profile steep at the head and flattening down the channel, so
    -- the three flows stop at different nodes.
    local x = m:get("x")
    local z = {}
    for i = 1, m.n do z[i] = 60 * (1 - x[i] / x[m.n]) ^ 2 end
    m:set_z(z)
    local S, A, w = m:get("S"), m:get("A"), m:get("w")
    local reach, E = {}, {}
    for i = 1, m.n do reach[i], E[i] = 0, 0 end
    local stops = {}
    for j = 1, 3 do
        local rate = lambda * wt[j] / 10
        for i = 1, m.n do
            local M = f[j] * o.M0 * (1e-6 * A[i]) ^ o.gamma
            local Q = o.c1 * M ^ o.c2
            local h = (3 * o.mu * Q / (o.rho_b * o.g * S[i] * w[i])) ^ (1 / 3)
            local Rh = w[i] * h / (w[i] + 2 * h)
            local tau = o.rho_b * o.g * Rh * S[i] / math.sqrt(1 + S[i] ^ 2)
            if not (S[i] > 0 and tau >= o.tau_y) then stops[j] = i; break end
            reach[i] = reach[i] + rate
            E[i] = E[i] + rate * 1e-4 * S[i] ^ 6 * (M / Q) * h * (1 - o.tau_y / tau)
        end
    end
    T.ok(stops[1] and stops[1] > 3 and stops[2] and stops[3] and stops[1] < stops[2] and stops[2] < stops[3],
         "three different runouts")
    local got = pop:route(m).reach
    local E_df = m:get("E_df")
    for i = 1, m.n do
        T.close(got[i], reach[i], 1e-12, 0, "reach at node " .. i)
        T.close(E_df[i], E[i], 1e-10, 1e-300, "E_df at node " .. i)
    end
end

tests["population: parameters are checked and named"] = function()
    local rt = dfle.router.empirical{}
    T.raises_here(function() return dfle.router.population{ router = rt, volume = { kind = "lognormal", sigma = -1 } } end,
                  "sigma must be >= 0")
    T.raises_here(function() return dfle.router.population{ router = rt, volume = { kind = "power_law", b = 2, f_min = 2, f_max = 1 } } end,
                  "f_max")
    T.raises_here(function() return dfle.router.population{ router = rt, volume = { kind = "gamma" } } end,
                  "volume kind")
    T.raises_here(function() return dfle.router.population{ router = rt, volume = { kind = "lognormal" } } end,
                  "needs sigma")
    T.raises_here(function() return dfle.router.population{ router = rt, volume = { kind = "lognormal", sigma = 1 }, order = 0 } end,
                  "order")
    T.raises_here(function() return dfle.router.population{ router = rt, volume = { kind = "lognormal", sigma = 1 }, frequency = 0 } end,
                  "frequency must be > 0")
    T.raises_here(function() return dfle.router.population{ router = rt, volume = { kind = "table", values = { 1, 2 }, weights = { 1 } } } end,
                  "weights")
    T.raises_here(function() return dfle.router.population{ router = rt, volume = { kind = "table", values = { 1, -2 } } } end,
                  "table value 2 must be > 0")
    T.raises_here(function() return dfle.router.population{ volume = { kind = "lognormal", sigma = 1 } } end,
                  "'router' is required")
    T.raises_here(function() return dfle.router.population{ router = rt, volume = { kind = "lognormal", sigma = 1, mean = 1 } } end,
                  "unknown parameter 'mean'")
    local pr = dfle.router.process{}
    T.raises_here(function() return dfle.router.population{ router = pr, volume = { kind = "lognormal", sigma = 1 } } end,
                  "empirical")
end

tests["population: a Lua sampler gives equal-weight draws"] = function()
    local rt = dfle.router.empirical{}
    local drawn = {}
    local pop = dfle.router.population{ router = rt, order = 4, frequency = 2,
        volume = { kind = "sampler", sample = function(k) drawn[#drawn + 1] = k; return k / 2 end } }
    T.eq(#drawn, 4)
    local q = dfle.router.quadrature(pop)
    for j = 1, 4 do
        T.close(q.f[j], j / 2, 1e-15)
        T.close(q.rate[j], 0.5, 1e-15)
    end
end

-- 2D: the same population API on a landscape (per head: volume scaling
-- with the head's area as for one flow, the spread on top).
local z34 = { 100, 120, 100, 80, 90, 80, 70, 60, 70, 50, 40, 50 }
local edges34 = { south = "base_level", north = "closed", east = "closed", west = "closed" }

tests["landscape: zero width is the characteristic flow bit for bit"] = function()
    local rt = dfle.router.empirical{}
    local pop = dfle.router.population{ router = rt, volume = { kind = "lognormal", sigma = 0 } }
    local function grid(r)
        return dfle.landscape{ nx = 24, ny = 20, dx = 20, U = 1e-3, A0 = 3 * 400, router = r,
                               noise = { seed = 2, amplitude = 5 } }
    end
    local a, b = grid(rt), grid(pop)
    for step = 1, 5 do
        local sa, sb = a:step(500), b:step(500)
        T.eq(sb.V_df, sa.V_df, "V_df at step " .. step)
    end
    T.ok(a:get("E_df")[1] >= 0, "evaluated")
    T.bits_equal(b:get("z"), a:get("z"), "z")
    T.bits_equal(b:get("E_df"), a:get("E_df"), "E_df")
    T.bits_equal(b:get("reach"), a:get("reach"), "reach")
end

tests["landscape: Theta = 1, joined flows counted: lambda E[f^kappa] times each cell's rate"] = function()
    local rt = dfle.router.empirical{ tau_y = 0 }
    local volume = { kind = "power_law", b = 1.8, f_min = 0.05, f_max = 50 }
    local pop = dfle.router.population{ router = rt, volume = volume, order = 32, frequency = 2 }
    local function grid(r)
        return dfle.landscape{ nx = 3, ny = 4, dx = 100, z = z34, edges = edges34, A0 = 2e4,
                               router = r, combine = "count" }
    end
    local a, b = grid(rt), grid(pop)
    local Ea, Eb, Ra, Rb = a:get("E_df"), b:get("E_df"), a:get("reach"), b:get("reach")
    local factor = 2 * dfle.router.moment(volume, kappa(0.78, 1))
    local eroded = 0
    for i = 1, 12 do
        T.close(Eb[i], factor * Ea[i], 1e-10, 0, "E_df, cell " .. i)
        -- Every flow of the population goes on where the one flow does:
        -- lambda flows a year for each head upstream.
        T.close(Rb[i], 2 * Ra[i], 1e-14, 0, "reach, cell " .. i)
        if Ea[i] > 0 then eroded = eroded + 1 end
    end
    T.eq(Ra[8], 3, "three heads join at (2,1)")
    T.ok(eroded >= 4, "the heads and the join eroded: " .. eroded)
end

tests["landscape: runout, reach and E_df of each cell are the flows' sums, routed one by one"] = function()
    -- A stepped landscape where stiff flows stop part-way down: each
    -- member of a table population, built as a characteristic flow of
    -- volume f M0 on the same surface, gives the cells it reaches; the
    -- population's reach and E_df are lambda sum_j w_j of the members'.
    local o = { M0 = 3000, tau_y = 1000 }
    local shape = { nx = 30, ny = 24, dx = 20, U = 1e-3, A0 = 3 * 400, combine = "count" }
    local function grid(rt, z)
        local t = { router = rt, z = z }
        for k, v in pairs(shape) do t[k] = v end
        if z == nil then t.noise = { seed = 2, amplitude = 5 } end
        return dfle.landscape(t)
    end
    local start = grid(dfle.router.empirical(o))
    for _ = 1, 10 do start:step(500) end
    local z = start:get("z")
    local f, wt, lambda = { 0.05, 1, 100 }, { 5, 3, 2 }, 3
    local pop = dfle.router.population{ router = dfle.router.empirical(o), frequency = lambda,
                                        volume = { kind = "table", values = f, weights = wt } }
    local ls = grid(pop, z)
    local R, E = ls:get("reach"), ls:get("E_df")
    local Rs, Es, reached = {}, {}, {}
    for c = 1, ls.n do Rs[c], Es[c] = 0, 0 end
    for j = 1, 3 do
        local one = grid(dfle.router.empirical{ M0 = o.M0 * f[j], tau_y = o.tau_y }, z)
        local Rj, Ej = one:get("reach"), one:get("E_df")
        reached[j] = 0
        for c = 1, ls.n do
            Rs[c] = Rs[c] + lambda * wt[j] / 10 * Rj[c]
            Es[c] = Es[c] + lambda * wt[j] / 10 * Ej[c]
            if Rj[c] > 0 then reached[j] = reached[j] + 1 end
        end
    end
    T.ok(reached[1] > 0 and reached[1] < reached[2] and reached[2] < reached[3],
         ("larger flows reach more cells: %d, %d, %d"):format(reached[1], reached[2], reached[3]))
    for c = 1, ls.n do
        T.close(R[c], Rs[c], 1e-12, 0, "reach, cell " .. c)
        T.close(E[c], Es[c], 1e-12, 1e-300, "E_df, cell " .. c)
    end
end

tests["events: the long-run mean erosion is the expected rate, within its reported error"] = function()
    local rt = dfle.router.empirical{}
    local volume = { kind = "lognormal", sigma = 1 }
    local pop = dfle.router.population{ router = rt, volume = volume, order = 16, frequency = 2 }
    local m = model(pop, dfle.law.power{})
    m:run_to_steady{}
    local E, z0, t0 = m:get("E_df"), m:get("z"), m.time
    local r = m:run_events{ years = 2e4, dt = 1, seed = 11, hold = true }
    T.eq(r.years, 2e4)
    T.ok(r.events > 3.8e4 and r.events < 4.2e4, "Poisson(lambda T) events: " .. r.events)
    local checked = 0
    for i = 1, m.n - 1 do
        if E[i] > 1e-6 * U then
            T.ok(math.abs(r.mean[i] - E[i]) <= 4 * r.se[i],
                 ("node %d: mean %.6g, expected %.6g, se %.3g"):format(i, r.mean[i], E[i], r.se[i]))
            T.ok(r.se[i] < 0.02 * E[i], "the error is small: " .. r.se[i] / E[i])
            checked = checked + 1
        end
    end
    T.ok(checked > 10, "nodes checked: " .. checked)
    -- Held: the state and the time did not move.
    T.bits_equal(m:get("z"), z0, "held z")
    T.eq(m.time, t0)
end

tests["events: a transient is fixed by its seed"] = function()
    local rt = dfle.router.empirical{}
    local pop = dfle.router.population{ router = rt, order = 4,
                                        volume = { kind = "power_law", b = 1.5, f_min = 0.1, f_max = 10 } }
    local function run(seed)
        local m = model(pop, dfle.law.power{})
        local r = m:run_events{ years = 500, dt = 2, seed = seed }
        return m:get("z"), r
    end
    local za, ra = run(3)
    local zb, rb = run(3)
    local zc = run(4)
    T.bits_equal(zb, za, "same seed")
    T.eq(rb.events, ra.events)
    T.ok(ra.events > 400 and ra.events < 600, "events: " .. ra.events)
    local differ = false
    for i = 1, #za do differ = differ or za[i] ~= zc[i] end
    T.ok(differ, "another seed, another history")
    T.raises_here(function() return model(rt, dfle.law.power{}):run_events{ years = 10 } end,
                  "population")
    T.raises_here(function() return model(pop, dfle.law.power{}):run_events{ years = -1 } end,
                  "years must be > 0")
end

return tests
