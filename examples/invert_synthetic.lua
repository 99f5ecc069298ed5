-- invert_synthetic.lua - an inversion whose answer is known.
--
-- A steady-state profile is made with known parameters (the empirical
-- router, U = 0.4 mm/yr, k_df = 2e-4, gamma = 0.5, the Fig. 9 values for
-- the rest), reduced to binned slope-area data like a DEM's, given 10 %
-- log-normal noise, written to a CSV file, and inverted from that file
-- for U, k_df and gamma over their Table G5 ranges, with the noise scale
-- inferred too.  The point: does the posterior find the truth, and what
-- does it say about the parameters the data cannot separate?
--
--   dfle examples/invert_synthetic.lua [--quick] [output-directory]
--
-- Writes synthetic_bins.csv (the data: A, S), synthetic_chain.csv (every
-- walker at every step; resumable: run the command again after a kill),
-- synthetic_corner.png (the posterior: marginals and pairs, truth marked)
-- and synthetic_pp.png (the posterior-predictive slope-area bands over
-- the data).  --quick runs a short chain (the test suite and the figure
-- gallery run it; its figures only show that they are drawn); the full
-- run takes about a minute on two cores.

local opts = dfle.args{
  usage = "dfle examples/invert_synthetic.lua [options] [output-directory]",
  about = "An inversion whose answer is known: a synthetic profile inverted for U, k_df, gamma.",
  flags = { quick = "a short chain (for the test suite and the gallery); the full run takes "
                    .. "about a minute" },
  output = true,
}
local quick, outdir = opts.quick, opts.output

local truth = { U = 4e-4, k_df = 2e-4, gamma = 0.5 }
local sigma = 0.1 -- noise sd of ln S
local ch = dfle.channel{ dx = quick and 20 or 10, A_max = 8e6 }

-- The model as a function of the parameters: the one the data were
-- made with; dfle.invert calls it for every proposal.
local function build(p, channel)
  return dfle.model{
    channel = channel, U = p.U,
    fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
    router = dfle.router.empirical{ M0 = 3000, gamma = p.gamma, mu = 500, tau_y = 300 },
    law = dfle.law.power{ k_df = p.k_df, alpha = 6, beta = 1 },
  }
end

-- The synthetic data: the true steady profile, binned as a DEM profile
-- is (30 logarithmic bins, mean slope), times exp(sigma eps).  The noise
-- comes from Lua's generator with a fixed seed, so workers replaying the
-- script make the same data.
local m = build(truth, ch)
assert(m:run_to_steady{}.converged)
local bins = assert(dfle.fit_slope_area(m, { nbins = 30 })).bins
math.randomseed(42)
local S = {}
for i, s in ipairs(bins.S) do
  local u1, u2 = math.random(), math.random()
  S[i] = s * math.exp(sigma * math.sqrt(-2 * math.log(u1)) * math.cos(2 * math.pi * u2))
end
-- (workers replaying the script need not write it again)
if not dfle.worker() then
  dfle.write_csv(outdir .. "/synthetic_bins.csv", {
    columns = { "A", "S" }, data = { A = bins.A, S = S }, units = { A = "m^2", S = "-" },
    about = "synthetic binned slope-area data (mean slope of 30 log bins times exp(sigma eps))",
    params = { U = truth.U, k_df = truth.k_df, gamma = truth.gamma, sigma = sigma },
  })
end

local res = dfle.invert{
  data = outdir .. "/synthetic_bins.csv", -- binned data: columns A and S
  channel = ch, build = build,
  params = {
    U = { 1e-4, 1e-3, log = true },      -- Table G5: 0.1-1 mm/yr
    k_df = { 5e-5, 1e-3, log = true },
    gamma = { 0, 1 },
  },
  walkers = quick and 8 or 32, steps = quick and 60 or 3000, burn = quick and 20 or 500,
  seed = 1, out = outdir .. "/synthetic_chain.csv",
}
if dfle.worker() then return end

print(res)
-- Ctrl-C: the whole steps are in the chain file; a cut chain has no
-- posterior, and running the command again resumes it.
if res.reason == "interrupted" then return end
print(("%-8s %12s %12s %27s  %s"):format("", "truth", "median", "95 % interval", ""))
for _, k in ipairs{ "U", "k_df", "gamma", "sigma" } do
  local s, t = res.summary[k], k == "sigma" and sigma or truth[k]
  -- an interval that ends on a prior bound says so beside it
  print(("%-8s %12.4g %12.4g   [%11.4g, %11.4g]  %s%s"):format(k, t, s.median, s.lo95, s.hi95,
        (s.lo95 <= t and t <= s.hi95) and "inside" or "OUTSIDE",
        s.bounded and ("  (held by the " .. s.bounded .. " prior bound)") or ""))
end
-- What the data cannot separate: in the debris-flow reach the slope
-- depends on U / k_df and on gamma together (the analytical solution,
-- Eq. 19), so k_df and gamma trade off along a ridge.
local function corr(a, b)
  local x, y, n = res.samples[a], res.samples[b], res.nsamples
  local mx, my, sxy, sxx, syy = 0, 0, 0, 0, 0
  for i = 1, n do mx, my = mx + math.log(x[i]), my + y[i] end
  mx, my = mx / n, my / n
  for i = 1, n do
    local dx, dy = math.log(x[i]) - mx, y[i] - my
    sxy, sxx, syy = sxy + dx * dy, sxx + dx * dx, syy + dy * dy
  end
  return sxy / math.sqrt(sxx * syy)
end
print(("posterior correlation of ln k_df and gamma: %.2f; of ln U and gamma: %.2f")
      :format(corr("k_df", "gamma"), corr("U", "gamma")))

-- U in mm/yr (scale multiplies its samples and truth), the house labels.
local Ulabel, Ufactor = dfle.plot.label("U")
dfle.plot.corner(res, outdir .. "/synthetic_corner.png", {
  truth = { U = truth.U, k_df = truth.k_df, gamma = truth.gamma, sigma = sigma },
  params = { "U", "k_df", "gamma", "sigma" }, scale = { U = Ufactor },
  -- k_df in m^{1-beta} s^-1 yr^-1: with beta = 1, s^-1 yr^-1 (Eq. 6, E_df in m/yr)
  labels = { U = "{/:Italic U} (mm/yr)", k_df = "{/:Italic k}_{df} (s^{−1} yr^{−1})", gamma = "γ",
             sigma = "σ" },
  title = "Synthetic profile: the posterior (truth in vermillion)",
})
dfle.plot.posterior_predictive(res, outdir .. "/synthetic_pp.png", {
  truth = m, title = "Synthetic profile: posterior-predictive slope-area",
})
print("wrote " .. outdir .. "/synthetic_bins.csv, synthetic_chain.csv, synthetic_corner.png, " ..
      "synthetic_pp.png")
