-- test_population_events.lua - debris flows of a population as events on
-- a landscape (ls:run_events) and as replicates through the ensemble
-- driver: the long-run mean erosion is the expected rate, within the
-- Monte Carlo error the run reports.
local T = ...
local tests = {}

-- A small landscape with channels, stepped so that flows go partway
-- down (some cells reached by part of the population only).
local function landscape(pop)
    local ls = dfle.landscape{ nx = 30, ny = 24, dx = 20, U = 1e-3, A0 = 3 * 400, router = pop,
                               combine = "count", noise = { seed = 2, amplitude = 5 } }
    for _ = 1, 10 do ls:step(500) end
    return ls
end

tests["landscape events: the long-run mean is the expected rate, within its error"] = function()
    local rt = dfle.router.empirical{ tau_y = 600 }
    local lambda = 2
    for _, volume in ipairs{ { kind = "table", values = { 0.1, 1, 5 }, weights = { 3, 2, 1 } },
                             { kind = "lognormal", sigma = 1 } } do
        local pop = dfle.router.population{ router = rt, order = 16, frequency = lambda,
                                            volume = volume }
        local ls = landscape(pop)
        local E, R, z0, t0 = ls:get("E_df"), ls:get("reach"), ls:get("z"), ls.time
        local r = ls:run_events{ years = 2e4, seed = 5 }
        T.eq(r.years, 2e4)
        -- Poisson(lambda T): mean 4e4, standard deviation 200.
        T.ok(math.abs(r.events - lambda * 2e4) < 5 * math.sqrt(lambda * 2e4), "events: " .. r.events)
        local eroded, partial = 0, 0
        for c = 1, ls.n do
            if E[c] > 0 then
                eroded = eroded + 1
                if R[c] < lambda * (1 - 1e-12) then partial = partial + 1 end
                T.ok(math.abs(r.mean[c] - E[c]) <= 4 * r.se[c],
                     ("%s, cell %d: mean %.6g, expected %.6g, se %.3g"):format(volume.kind, c,
                                                                            r.mean[c], E[c], r.se[c]))
                T.ok(r.se[c] < 0.05 * E[c], "the error is small: " .. r.se[c] / E[c])
            elseif E[c] == 0 then
                T.eq(r.mean[c], 0, "no flow, no event erosion at cell " .. c)
            end
        end
        T.ok(eroded >= 10, "cells eroded: " .. eroded)
        T.ok(partial >= 1, "cells reached by part of the population: " .. partial)
        -- The surface is held.
        T.bits_equal(ls:get("z"), z0, "held z")
        T.eq(ls.time, t0)
        -- Fixed by its seed.
        local again = ls:run_events{ years = 2e4, seed = 5 }
        T.eq(again.events, r.events)
        T.bits_equal(again.mean, r.mean, "same seed, same means")
    end
end

tests["landscape events: refused without a population, or as a transient"] = function()
    local plain = dfle.landscape{ nx = 10, ny = 8, dx = 20, router = dfle.router.empirical{} }
    T.raises_here(function() return plain:run_events{ years = 10 } end, "population")
    local pop = dfle.router.population{ router = dfle.router.empirical{},
                                        volume = { kind = "lognormal", sigma = 1 } }
    local ls = dfle.landscape{ nx = 10, ny = 8, dx = 20, router = pop }
    T.raises_here(function() return ls:run_events{ years = 10, hold = false } end, "hold must be true")
    T.raises_here(function() return ls:run_events{ years = -1 } end, "years must be > 0")
    T.raises_here(function() return ls:run_events{ dt = 1 } end, "'years' is required")
    T.raises_here(function() return ls:run_events{ years = 1, seeds = 1 } end, "unknown parameter 'seeds'")
end

tests["replicates through the ensemble driver: their mean is the expected rate"] = function()
    local dir, done = T.scratch()
    local R, years = 16, 2000
    local ens = dfle.ensemble{
        params = { seed = { values = (function()
            local v = {}
            for k = 1, R do v[k] = k end
            return v
        end)() } },
        n = R, seed = 1, out = dir .. "/replicates.csv", workers = 1,
        build = function()
            local pop = dfle.router.population{ router = dfle.router.empirical{}, order = 16,
                                                volume = { kind = "lognormal", sigma = 1.5 } }
            return dfle.model{ channel = dfle.channel{ dx = 20 }, U = 5e-4, router = pop,
                               law = dfle.law.power{} }
        end,
        measure = function(m, fit, p)
            local r = m:run_events{ years = years, seed = p.seed, hold = true }
            -- Node 5: on the debris-flow reach.
            return { E_expected = m:get("E_df")[5], E_mean = r.mean[5], E_se = r.se[5],
                     events = r.events }
        end,
        outputs = { "E_expected", "E_mean", "E_se", "events" },
    }
    T.eq(ens.ok, R)
    local d = ens.data
    local seen, s, s2, se2 = {}, 0, 0, 0
    for k = 1, R do
        seen[d.seed[k]] = true
        T.eq(d.E_expected[k], d.E_expected[1], "one expected rate")
        s, s2, se2 = s + d.E_mean[k], s2 + d.E_mean[k] ^ 2, se2 + d.E_se[k] ^ 2
    end
    local n_seen = 0
    for _ in pairs(seen) do n_seen = n_seen + 1 end
    T.eq(n_seen, R, "every replicate its own seed")
    local mean = s / R
    local sd = math.sqrt((s2 - R * mean ^ 2) / (R - 1))
    local E = d.E_expected[1]
    T.ok(E > 0, "node 5 is eroded")
    -- The replicates' mean, within its standard error.
    T.ok(math.abs(mean - E) <= 4 * sd / math.sqrt(R),
         ("mean of %d replicates %.6g, expected %.6g, se %.3g"):format(R, mean, E, sd / math.sqrt(R)))
    -- The spread between replicates is the error each one reports
    -- (a chi-square of 15 degrees of freedom lies within 0.3-2.2 of its
    -- mean with probability above 0.999).
    local ratio = sd ^ 2 / (se2 / R)
    T.ok(ratio > 0.3 and ratio < 2.2, "replicate variance over reported variance: " .. ratio)
    done()
end

return tests
