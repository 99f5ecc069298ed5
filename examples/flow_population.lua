-- flow_population.lua - debris flows as a population (doc/model.md,
-- "Debris flows as a population"): how the steady channel changes as the
-- volume distribution widens from one characteristic flow (the paper's
-- Fig. 9 default) to the orders-of-magnitude spread of regional
-- inventories, in 1D and on a synthetic landscape, and how a population
-- of stiffer flows (tau_y = 1500 Pa, whose characteristic flow stops
-- half-way down the channel) spreads its runout: part of the population
-- reaches each node.
--
-- Volumes are log-normal factors f on M0, ln f ~ N(-sigma^2 / 2, sigma^2),
-- so that every population moves the same mean volume a year as the
-- characteristic flow (E[f] = 1, lambda = 1 flow a year): what changes is
-- only the spread, many small flows and a few large ones.  sigma = 2 is a
-- spread of a factor of about 50 between the 16th and the 84th
-- percentiles, the scale of the scatter of regional volume-area fits.
--
--   dfle examples/flow_population.lua [--quick] [output-directory]
--
-- Writes flow_population.csv (sigma, S_df, A_df, a2, R^2, in 1D and 2D),
-- flow_population_profiles.png (elevation near the head),
-- flow_population_slope_area.png (1D slope-area per sigma),
-- flow_population_E_df.png (E_df along the stiff flows' steady profiles),
-- flow_population_reach.png (the fraction of the stiff flows going on at
-- each node) and flow_population_landscape.png (binned slope-area of the
-- steady landscapes per sigma).
-- --quick: a 20 m channel, three widths and a small grid (for the test suite).

local opts = dfle.args{
  usage = "dfle examples/flow_population.lua [options] [output-directory]",
  about = "Debris flows as a population: steady channels and landscapes as the volume spread widens.",
  flags = { quick = "a coarse channel, two widths and a small grid (for the test suite)" },
  output = true,
}
local quick, outdir = opts.quick, opts.output
local function out(name) return outdir .. "/" .. name end

local sigmas = quick and { 0, 1, 2 } or { 0, 0.5, 1, 1.5, 2 }
local order = 16
-- Fig. 9's router (M0 = 3000, gamma = 0.5, mu = 500 Pa s, tau_y = 300 Pa),
-- and the same with stiffer flows.
local MOBILITY = { { name = "Fig. 9", tau_y = 300 }, { name = "stiff", tau_y = 1500 } }
local channel = dfle.channel{ dx = quick and 20 or 5 }
local DASHES = { "solid", "dash", "dot", "dashdot", "dashdotdot" }
local nan = 0 / 0

local function router_for(sigma, tau_y)
  local base = dfle.router.empirical{ tau_y = tau_y or 300 }
  if sigma == 0 then return base end
  return dfle.router.population{ router = base, frequency = 1, order = order,
                                 volume = { kind = "lognormal", sigma = sigma,
                                            median = math.exp(-sigma * sigma / 2) } }
end

local rows = {}
local profiles, slopes, erosion, reach = {}, {}, {}, {}
print(("%4s %7s %6s %10s %8s %10s %6s %7s %10s %10s"):format("dim", "tau_y", "sigma", "converged",
      "S_df", "A_df (m2)", "a2", "R^2", "half (m)", "all (m)"))
for _, mob in ipairs(MOBILITY) do
  for k, sigma in ipairs(sigmas) do
    local rt = router_for(sigma, mob.tau_y)
    local m = dfle.model{ channel = channel, U = 5e-4, router = rt, law = dfle.law.power{} }
    local run = m:run_to_steady{}
    local fit = dfle.fit_slope_area(m) or { S_df = nan, A_df = nan, a2 = nan, r2 = nan }
    -- reach / lambda: the fraction of the population going on at a node.
    local x, r = m:get("x"), rt:route(m).reach
    -- How far half the flows go, and the largest.
    local half, all = 0, 0
    for i = 1, m.n do
      if r[i] >= 0.5 then half = x[i] end
      if r[i] > 0 then all = x[i] end
    end
    print(("%4s %7g %6g %10s %8.3f %10.3g %6.2f %7.4f %10.0f %10.0f"):format("1D", mob.tau_y, sigma,
          tostring(run.converged), fit.S_df, fit.A_df, fit.a2, fit.r2, half, all))
    rows[#rows + 1] = { dim = "1D", tau_y = mob.tau_y, sigma = sigma, converged = run.converged,
                        S_df = fit.S_df, A_df = fit.A_df, a2 = fit.a2, r2 = fit.r2,
                        runout_half = half, runout_all = all }
    local label, dash = ("σ = %g"):format(sigma), DASHES[(k - 1) % #DASHES + 1]
    if mob.tau_y == 300 then
      profiles[#profiles + 1] = { x = x, y = m:get("z"), label = label, lines = true, dash = dash }
      slopes[#slopes + 1] = { x = m:get("A"), y = m:get("S"), label = label, lines = true, dash = dash }
    else
      erosion[#erosion + 1] = { x = x, y = m:get("E_df"), label = label, lines = true, dash = dash }
      reach[#reach + 1] = { x = x, y = r, label = label, lines = true, dash = dash }
    end
  end
end

-- The same populations on a synthetic landscape: per channel head the
-- volume scales with the head's area as for one flow, the spread on top.
local nx, ny = quick and 40 or 120, quick and 30 or 90
local bins = {}
for _, sigma in ipairs(sigmas) do
  local ls = dfle.landscape{
    nx = nx, ny = ny, dx = 30, A0 = 1e4, combine = "count", router = router_for(sigma),
    edges = { south = "base_level", north = "closed", east = "closed", west = "closed" },
    U = 5e-4, noise = { amplitude = 1, seed = 42 },
  }
  local run = ls:run_to_steady{ max_steps = quick and 30 or 100000, dt = 5e3 }
  local fit = dfle.fit_slope_area(ls)
  local f = fit or { S_df = nan, A_df = nan, a2 = nan, r2 = nan }
  print(("%4s %7g %6g %10s %8.3f %10.3g %6.2f %7.4f"):format("2D", 300, sigma,
        tostring(run.converged), f.S_df, f.A_df, f.a2, f.r2))
  if not run.converged then print("  " .. run.note) end
  rows[#rows + 1] = { dim = "2D", tau_y = 300, sigma = sigma, converged = run.converged,
                      S_df = f.S_df, A_df = f.A_df, a2 = f.a2, r2 = f.r2, runout_half = nan,
                      runout_all = nan }
  if fit then
    bins[#bins + 1] = { x = fit.bins.A, y = fit.bins.S, label = ("σ = %g"):format(sigma),
                        style = "linespoints", dash = DASHES[#bins % #DASHES + 1] }
  end
end

dfle.write_csv(out("flow_population.csv"), {
  about = "steady states under log-normal populations of debris-flow volume (E[f] = 1, lambda = "
          .. "1/yr, quadrature order " .. order .. ") of the Fig. 9 empirical router and a stiffer one; "
          .. "runout_half, runout_all: the farthest node half the flows, and any flow, reach (1D)",
  columns = { "dim", "tau_y", "sigma", "converged", "S_df", "A_df", "a2", "r2", "runout_half",
              "runout_all" },
  units = { tau_y = "Pa", sigma = "-", S_df = "-", A_df = "m^2", a2 = "-", r2 = "-",
            runout_half = "m", runout_all = "m" },
  rows = rows, params = { channel = channel:params() },
})
local lab = dfle.plot.label
dfle.plot.xy{
  path = out("flow_population_profiles.png"), series = profiles, xrange = { 0, 300 },
  title = "Steady profiles near the head: one flow against populations of spread σ",
  xlabel = lab("x"), ylabel = lab("z"),
}
dfle.plot.xy{
  path = out("flow_population_slope_area.png"), series = slopes, xlog = true, ylog = true,
  title = "Steady slope-area, log-normal volume populations of spread σ (same mean volume)",
  xlabel = lab("A"), ylabel = lab("S"),
}
dfle.plot.xy{
  path = out("flow_population_E_df.png"), series = erosion, ylog = true,
  title = "Debris-flow erosion along the steady profiles, stiff flows (τ_y = 1500 Pa)",
  xlabel = lab("x"),
  ylabel = "Debris-flow erosion rate E_{df} (m/yr)",
}
dfle.plot.xy{
  path = out("flow_population_reach.png"), series = reach, yrange = { 0, 1.05 },
  title = "Fraction of the flows going on at each node, stiff flows (τ_y = 1500 Pa, λ = 1/yr)",
  xlabel = lab("x"), ylabel = "Flows going on at the node (1/yr)",
}
if #bins > 0 then
  dfle.plot.xy{
    path = out("flow_population_landscape.png"), series = bins, xlog = true, ylog = true,
    title = "Steady landscapes: binned slope-area per volume spread σ",
    xlabel = lab("A"), ylabel = lab("S"),
  }
end
