-- test_population_params.lua - the width of a population as a parameter
-- like any other: sampled by an ensemble and ranked by PAWN, inferred by
-- dfle.invert, each checked against the closed form where Theta = 1
-- (tau_y = 0: the steady slope is Eq. (19) with k_df lambda E[f^kappa]);
-- and through the CLI, an ensemble of populations and of their events
-- gives the same file on 1 and 2 workers.
local T = ...
local tests = {}

local q = T.shquote
local U = 5e-4
-- Eqs. (6), (15), (16) with Theta = 1: one flow erodes ~ M^kappa.
local KAPPA = 1 - 0.78 + 0.78 / 3
local CH = dfle.channel{ dx = 20 }

-- A log-normal population of spread `spread` (median 1) behind the
-- Theta = 1 router.
local function router()
    return dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500, tau_y = 0 }
end
local function law(p) return dfle.law.power{ k_df = p.k_df or 1e-4, alpha = 6, beta = 1 } end
local function build(p)
    local pop = dfle.router.population{ router = router(), order = 16,
                                        volume = { kind = "lognormal", sigma = p.spread } }
    return dfle.model{ channel = CH, U = U, router = pop, law = law(p) }
end

-- The steady state under a population of spread s is the profile on
-- which U = E_f + E[f^kappa] E_df,1 at every node (E_df,1: one flow's
-- rate on that profile; E[f^kappa] = exp(kappa^2 s^2 / 2)).  The largest
-- relative miss over the nodes above the outlet.
local function steady_residual(m, p)
    local one = dfle.model{ channel = CH, U = U, router = router(), law = law(p) }
    one:set_z(m:get("z"))
    local Ef, Edf = one:get("E_f"), one:get("E_df")
    local c = math.exp(0.5 * KAPPA ^ 2 * p.spread ^ 2)
    local worst = 0
    for i = 1, one.n - 1 do
        worst = math.max(worst, math.abs(Ef[i] + c * Edf[i] - U) / U)
    end
    return worst, Edf[1] * c / U
end

tests["ensemble and PAWN: the spread sampled as a parameter, each sample its population's steady state"] = function()
    local dir, done = T.scratch()
    local ens = dfle.ensemble{
        params = { spread = { 0, 2.5 }, unused = { 0, 1 } },
        n = 60, seed = 3, out = dir .. "/spread.csv", workers = 1, build = build,
        measure = function(m, fit, p)
            local miss, df_share = steady_residual(m, p)
            return { miss = miss, df_share = df_share }
        end,
        outputs = { "S_df", "A_df", "miss", "df_share" },
    }
    T.eq(ens.ok, 60, "every sample ran")
    local lo, hi = math.huge, -math.huge
    for k = 1, 60 do
        T.ok(ens.data.miss[k] < 1e-8, ("sample %d: steady state missed by %.3g"):format(k, ens.data.miss[k]))
        T.ok(ens.data.df_share[k] > 0.99, "debris flows erode the head")
        lo, hi = math.min(lo, ens.data.spread[k]), math.max(hi, ens.data.spread[k])
    end
    T.ok(lo < 0.1 and hi > 2.4, "the design spans the spreads")
    -- The spread moves S_df (a wider population erodes more: a gentler
    -- debris-flow reach), the unused parameter does not: PAWN ranks
    -- them so.
    local si = dfle.pawn(ens, { outputs = { "S_df" }, S = 5 })
    T.ok(si.S_df.spread.median > 2 * si.S_df.unused.median,
         ("PAWN median: spread %.3f, unused %.3f"):format(si.S_df.spread.median,
                                                          si.S_df.unused.median))
    done()
end

tests["invert: the spread inferred from a steady profile, the truth inside 95 %"] = function()
    local truth = { spread = 2 }
    local m = build(truth)
    T.ok(m:run_to_steady{}.converged, "truth converged")
    local bins = assert(dfle.fit_slope_area(m, { nbins = 20 })).bins
    local data = { A = bins.A, S = bins.S }
    local res = dfle.invert{
        data = data, channel = CH, workers = 1,
        build = function(p) return build(p) end,
        params = { spread = { 0, 3 } }, sigma = 0.01,
        walkers = 8, steps = 120, burn = 40, seed = 4,
    }
    local s = res.summary.spread
    T.ok(s.lo95 < truth.spread and truth.spread < s.hi95,
         ("spread 95 %%: [%.3f, %.3f]"):format(s.lo95, s.hi95))
    -- The data tell the spread: no population (spread 0) and half the
    -- spread lie outside the interval.
    T.ok(s.lo95 > 1, ("the interval excludes spreads below 1: lo95 %.3f"):format(s.lo95))
end

-- Through the CLI (a worker replays its script): spreads and seeds as
-- parameters, each sample a transient of events from its steady state.
local SCRIPT = [[
local out = arg[1]
local ens = dfle.ensemble{
  params = { spread = { 0.2, 2 }, seed = { values = { 1, 2, 3, 4, 5, 6 } } },
  n = 12, seed = 5, out = out,
  build = function(p)
    local pop = dfle.router.population{ router = dfle.router.empirical{}, order = 8,
                                        volume = { kind = "lognormal", sigma = p.spread } }
    return dfle.model{ channel = dfle.channel{ dx = 20 }, U = 5e-4, router = pop,
                       law = dfle.law.power{} }
  end,
  measure = function(m, fit, p)
    local r = m:run_events{ years = 300, dt = 1, seed = p.seed }
    return { z_head = m:get("z")[1], z_5 = m:get("z")[5], events = r.events,
             mean_5 = r.mean[5] }
  end,
  outputs = { "S_df", "z_head", "z_5", "events", "mean_5" },
}
print(("ok=%d"):format(ens.ok))
]]

local function rows(path)
    local text = assert(T.read_file(path), path)
    return (text:gsub("\n# date: [^\n]*", ""):gsub("\n# command: [^\n]*", ""))
end

tests["CLI: an ensemble of populations and their events, the same file on 1 and 2 workers"] = function()
    local dir, done = T.scratch()
    T.write_file(dir .. "/pop.lua", SCRIPT)
    for _, j in ipairs{ 1, 2 } do
        local out, ok = T.sh("cd " .. q(dir) .. " && " .. q(T.dfle) .. " -q -j " .. j ..
                             " pop.lua e" .. j .. ".csv")
        T.ok(ok, "dfle failed: " .. out)
        T.ok(out:find("ok=12", 1, true), "every sample ran: " .. out)
    end
    local c = T.read_csv(dir .. "/e1.csv")
    T.eq(#c.rows, 12)
    T.eq(rows(dir .. "/e2.csv"), rows(dir .. "/e1.csv"))
    done()
end

return tests
