-- invert_coverage.lua - does the inversion's 95 % interval contain the
-- truth 95 % of the time?  And does the posterior narrow as noise falls?
--
-- A calibration study of dfle.invert on synthetic data.  60 true
-- parameter sets (U, k_df, gamma) are drawn from the priors themselves
-- (a Latin hypercube over the Table G5 ranges, log-uniform for U and
-- k_df), each gives a steady profile of the empirical model, binned into
-- 25 area bins; each profile is given log-normal noise of three sizes
-- (sigma = 0.2, 0.1, 0.05 in ln S) and inverted for U, k_df, gamma and
-- sigma.  When the truth is drawn from the prior and the data from the
-- likelihood, a correct sampler's 95 % intervals contain the truth in
-- 95 % of the cases, up to binomial noise (about +-3 % for 60 cases);
-- too short chains or a wrong likelihood show up as less.
--
--   dfle examples/invert_coverage.lua [--quick] [output-directory]
--
-- The 60 data sets run as a dfle.ensemble (one sample = one truth, its
-- three inversions in the sample's own worker), so all cores are used
-- and an interrupted study resumes.  Writes
--   coverage.csv           one row per truth: the truth, and per noise
--                          level whether each parameter's 95 % interval
--                          holds it, U's interval and median, tau
--   coverage_summary.csv   coverage and median interval width per level
--   coverage_U.png         U's 95 % intervals against the truth
-- The full study takes 5-10 minutes on two cores.  --quick (the test
-- suite, the figure gallery) runs 4 truths with short chains: its
-- coverage numbers and figure are not meaningful.

local opts = dfle.args{
  usage = "dfle examples/invert_coverage.lua [options] [output-directory]",
  about = "Coverage of the inversion's 95 % intervals over synthetic data sets.",
  flags = { quick = "4 truths, short chains (for the test suite and the gallery)" },
  output = true,
}
local quick, outdir = opts.quick, opts.output

local NSETS = quick and 4 or 60
local LEVELS = { 0.2, 0.1, 0.05 }
local SAMPLER = quick and { walkers = 8, steps = 30, burn = 10 }
                       or { walkers = 16, steps = 1000, burn = 300 }
local PRIORS = {
  U = { 1e-4, 1e-3, log = true },
  k_df = { 5e-5, 1e-3, log = true },
  gamma = { 0, 1 },
}

local ch = dfle.channel{ dx = 20, A_max = 8e6 }
local function build(p, channel)
  return dfle.model{
    channel = channel, U = p.U,
    fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
    router = dfle.router.empirical{ M0 = 3000, gamma = p.gamma, mu = 500, tau_y = 300 },
    law = dfle.law.power{ k_df = p.k_df, alpha = 6, beta = 1 },
  }
end

local outputs = {}
for k = 1, #LEVELS do
  for _, o in ipairs{ "U_in", "kdf_in", "gamma_in", "sigma_in", "U_lo", "U_hi", "U_med",
                      "tau" } do
    outputs[#outputs + 1] = o .. "_" .. k
  end
end

-- One truth: its binned profile comes in `fit` (the ensemble's slope-area
-- fit); noise from Lua's generator seeded by the truth, so any worker
-- makes the same data.
local function measure(m, fit, p)
  local out = {}
  for k, sigma in ipairs(LEVELS) do
    math.randomseed(math.floor(p.U * 1e13) % 2147483647, k)
    local S = {}
    for i, s in ipairs(fit.bins.S) do
      local u1, u2 = math.random(), math.random()
      S[i] = s * math.exp(sigma * math.sqrt(-2 * math.log(u1)) * math.cos(2 * math.pi * u2))
    end
    local res = dfle.invert{
      data = { A = fit.bins.A, S = S }, channel = ch, build = build, params = PRIORS,
      walkers = SAMPLER.walkers, steps = SAMPLER.steps, burn = SAMPLER.burn, seed = k,
      lsq = false,
    }
    local function inside(name, t)
      local s = res.summary[name]
      return (s.lo95 <= t and t <= s.hi95) and 1 or 0
    end
    out["U_in_" .. k] = inside("U", p.U)
    out["kdf_in_" .. k] = inside("k_df", p.k_df)
    out["gamma_in_" .. k] = inside("gamma", p.gamma)
    out["sigma_in_" .. k] = inside("sigma", sigma)
    out["U_lo_" .. k] = res.summary.U.lo95
    out["U_hi_" .. k] = res.summary.U.hi95
    out["U_med_" .. k] = res.summary.U.median
    out["tau_" .. k] = res.tau_max
  end
  return out
end

local t0 = os.time()
local ens = dfle.ensemble{
  params = PRIORS, n = NSETS, seed = 11, out = outdir .. "/coverage.csv",
  build = function(p) return build(p, ch) end,
  fit = { nbins = 25 }, measure = measure, outputs = outputs,
}
if dfle.worker() then return end

local d = ens.data
local ok = {}
for r = 1, ens.count do
  if d.status[r] == "ok" then ok[#ok + 1] = r end
end
print(("%d synthetic data sets (%d failed: %s), %d walkers x %d steps each, %d s")
      :format(#ok, ens.failed, ens.failed > 0 and "see coverage.csv" or "none",
              SAMPLER.walkers, SAMPLER.steps, os.time() - t0))
print(("%-8s %8s %8s %8s %8s %14s %10s"):format("sigma", "U", "k_df", "gamma", "sigma",
                                                 "U width (dex)", "tau"))
local summary, widths = {}, {}
for k, sigma in ipairs(LEVELS) do
  local function mean(col)
    local s = 0
    for _, r in ipairs(ok) do s = s + d[col .. "_" .. k][r] end
    return s / #ok
  end
  local function median(f)
    local v = {}
    for _, r in ipairs(ok) do v[#v + 1] = f(r) end
    table.sort(v)
    return v[math.floor((#v + 1) / 2)]
  end
  local w = median(function(r) return math.log(d["U_hi_" .. k][r] / d["U_lo_" .. k][r], 10) end)
  local tau = median(function(r) return d["tau_" .. k][r] end)
  widths[k] = w
  print(("%-8.2f %8.3f %8.3f %8.3f %8.3f %14.3f %10.1f"):format(sigma, mean("U_in"),
        mean("kdf_in"), mean("gamma_in"), mean("sigma_in"), w, tau))
  summary[#summary + 1] = { sigma = sigma, sets = #ok, coverage_U = mean("U_in"),
                            coverage_k_df = mean("kdf_in"), coverage_gamma = mean("gamma_in"),
                            coverage_sigma = mean("sigma_in"), median_width_U_dex = w,
                            median_tau = tau }
end
dfle.write_csv(outdir .. "/coverage_summary.csv", {
  columns = { "sigma", "sets", "coverage_U", "coverage_k_df", "coverage_gamma", "coverage_sigma",
              "median_width_U_dex", "median_tau" },
  rows = summary,
  units = { sigma = "-", sets = "-", coverage_U = "-", coverage_k_df = "-", coverage_gamma = "-",
            coverage_sigma = "-", median_width_U_dex = "dex", median_tau = "steps" },
  about = "coverage of the 95 % intervals and median width of U's, per noise level (sd of ln S)",
  params = { walkers = SAMPLER.walkers, steps = SAMPLER.steps, burn = SAMPLER.burn },
})

-- The acceptance criteria of the study (meaningful for the full run).
local cov = 0
for _, r in ipairs(ok) do cov = cov + d.U_in_2[r] end
cov = cov / #ok
local se = math.sqrt(0.95 * 0.05 / #ok)
print(("coverage of U's 95 %% interval at sigma = 0.1: %.3f (binomial sd %.3f): %s")
      :format(cov, se, (cov >= 0.9 and cov <= 0.99) and "within 0.90-0.99" or "OUTSIDE 0.90-0.99"))
print(("median width of U's 95 %% interval: %.3f, %.3f, %.3f dex for sigma = 0.2, 0.1, 0.05: %s")
      :format(widths[1], widths[2], widths[3],
              (widths[1] > widths[2] and widths[2] > widths[3]) and "narrows as noise falls"
              or "does NOT narrow"))
if quick then
  print("(--quick: 4 data sets and short chains; the numbers above are not a calibration)")
end

-- U's 95 % intervals against the truth (sigma = 0.1), in mm/yr: blue
-- when they hold it, vermillion when not; the 1:1 line.
do
  local Ulabel, f = dfle.plot.label("U")
  local series = { { x = { 1e-4 * f, 1e-3 * f }, y = { 1e-4 * f, 1e-3 * f }, lines = true,
                     rgb = "grey", label = "1:1" } }
  local mx, my = {}, {}
  local lab_in, lab_out = "95 % interval holds the truth", "95 % interval misses it"
  for _, r in ipairs(ok) do
    local t, inside = d.U[r] * f, d.U_in_2[r] == 1
    local label -- one legend entry per kind
    if inside then label, lab_in = lab_in, nil else label, lab_out = lab_out, nil end
    series[#series + 1] = { x = { t, t }, y = { d.U_lo_2[r] * f, d.U_hi_2[r] * f }, lines = true,
                            rgb = inside and "blue" or "vermillion", label = label }
    mx[#mx + 1], my[#my + 1] = t, d.U_med_2[r] * f
  end
  series[#series + 1] = { x = mx, y = my, rgb = "black", label = "posterior median" }
  dfle.plot.xy{ path = outdir .. "/coverage_U.png", series = series, xlog = true, ylog = true,
                title = ("Recovery of U from %d synthetic profiles (σ = 0.1): coverage %.2f")
                        :format(#ok, cov),
                xlabel = "True " .. Ulabel:gsub("^Uplift rate", "uplift rate"),
                ylabel = "Inferred " .. Ulabel:gsub("^Uplift rate", "uplift rate") }
end
print("wrote " .. outdir .. "/coverage.csv, coverage_summary.csv, coverage_U.png")
