-- invert_sbc.lua - simulation-based calibration of dfle.invert (Talts et
-- al. 2018): are its posteriors right on average over the prior?
--
-- Each replicate draws a truth from the priors the inversion then uses
-- (U, k_df, gamma and the noise scale sigma), makes the model's steady
-- slopes at 25 nodes of its channel, multiplies them by exp(sigma eps)
-- (exactly the likelihood's noise), and inverts them with dfle.invert's
-- default sampler settings (32 walkers, 2000 steps, burn-in 500).  The
-- rank of the truth among L posterior draws (thinned: a few steps far
-- apart, every walker) is then uniform on 0 .. L for every parameter if
-- the sampler, the likelihood and the priors agree, and the central
-- 50 % and 90 % intervals hold the truth in 50 % and 90 % of the
-- replicates.  A chi-square test of the rank histogram (8 bins) at the
-- 1 % level and the coverages with their binomial sd are printed.
--
--   dfle examples/invert_sbc.lua [--quick] [--priors broad|narrow] [output-directory]
--
-- broad (default): U log-uniform 1e-5 .. 1e-2 m/yr, k_df 1e-6 .. 1e-2,
-- gamma 0 .. 1, sigma log-uniform 0.005 .. 2 (the default noise prior);
-- narrow: U and k_df over Table G5 (1e-4 .. 1e-3, 5e-5 .. 1e-3).
--
-- The replicates run as a dfle.ensemble (one sample = one replicate, its
-- inversion in the sample's own worker), so all cores are used and an
-- interrupted study resumes.  Writes
--   sbc_<priors>.csv          one row per replicate: the truth, the ranks,
--                             whether the 50 and 90 % intervals hold it,
--                             tau, stranded walkers, bound flags
--   sbc_<priors>_summary.csv  per parameter: chi-square, p, coverages
--   sbc_<priors>_ranks.png    the rank histograms with the band that 99 %
--                             of uniform histograms stay in
-- The full study (200 replicates) takes 5-10 minutes on two cores.
-- --quick (the test suite) runs 24 small replicates of a coarse model
-- with short chains and fails (an error) when the ranks are far from
-- uniform (p < 0.001) or a 90 % interval covers fewer than half the
-- truths: small, but able to catch a sampler that is badly off.

local opts = dfle.args{
  usage = "dfle examples/invert_sbc.lua [options] [output-directory]",
  about = "Simulation-based calibration of dfle.invert: ranks of the truth and coverage.",
  flags = { quick = "24 small replicates (for the test suite)" },
  options = { priors = { "broad|narrow", "the priors the truths are drawn from (default broad)" } },
  output = true,
}
local quick, outdir = opts.quick, opts.output
local which = opts.priors or "broad"
if which ~= "broad" and which ~= "narrow" then
  error("--priors must be broad or narrow, got " .. which)
end

local NREP = quick and 24 or 200
local NOBS = 25
local SAMPLER = quick and { walkers = 8, steps = 300, burn = 100 } or {} -- {}: the defaults
local DRAW_STEPS = 2    -- posterior draws: every walker at DRAW_STEPS steps far apart
local NBINS = quick and 4 or 8
local PRIORS = which == "broad" and {
  U = { 1e-5, 1e-2, log = true },
  k_df = { 1e-6, 1e-2, log = true },
  gamma = { 0, 1 },
} or {
  U = { 1e-4, 1e-3, log = true },
  k_df = { 5e-5, 1e-3, log = true },
  gamma = { 0, 1 },
}
local SIGMA = { 0.005, 2, log = true } -- dfle.invert's default prior of sigma
local NAMES = { "U", "gamma", "k_df", "sigma" } -- res.names' order
local function prior_of(name) return name == "sigma" and SIGMA or PRIORS[name] end

local ch = dfle.channel{ dx = quick and 50 or 20, A_max = 8e6 }
local function build(p, channel)
  return dfle.model{
    channel = channel, U = p.U,
    fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
    router = dfle.router.empirical{ M0 = 3000, gamma = p.gamma, mu = 500, tau_y = 300 },
    law = dfle.law.power{ k_df = p.k_df, alpha = 6, beta = 1 },
  }
end

-- The data's nodes: NOBS nodes spread evenly in ln A over the channel
-- (the likelihood interpolates the model's slope at a datum's area, which
-- at a node is the node's own slope: the data are the likelihood's model).
local A_ch = ch:get("A")
local nodes = {}
do
  local n = #A_ch
  local lo, hi = math.log(A_ch[2]), math.log(A_ch[n])
  local k = 2
  for i = 1, NOBS do
    local target = lo + (hi - lo) * (i - 1) / (NOBS - 1)
    while k < n and math.log(A_ch[k]) < target do k = k + 1 end
    if nodes[#nodes] ~= k then nodes[#nodes + 1] = k end
  end
end

local outputs = { "ok", "tau", "converged", "stranded", "moved" }
for _, name in ipairs(NAMES) do
  for _, o in ipairs{ "truth_", "rank_", "in50_", "in90_", "bounded_" } do
    outputs[#outputs + 1] = o .. name
  end
end

-- A value drawn from a prior ({lo, hi} or {lo, hi, log = true}) with u in (0, 1).
local function draw(prior, u)
  if prior.log then
    return math.exp(math.log(prior[1]) + u * (math.log(prior[2]) - math.log(prior[1])))
  end
  return prior[1] + u * (prior[2] - prior[1])
end

local function quantile(sorted, p)
  local h = (#sorted - 1) * p + 1
  local i = math.floor(h)
  if i >= #sorted then return sorted[#sorted] end
  return sorted[i] + (h - i) * (sorted[i + 1] - sorted[i])
end

-- One replicate: rep 1 .. NREP (from the ensemble's stratified u: every
-- stratum once), its truth and noise from Lua's generator seeded by rep.
local function replicate(rep)
  math.randomseed(rep, 20180410)
  local truth = {}
  for _, name in ipairs(NAMES) do truth[name] = draw(prior_of(name), math.random()) end
  local out = { ok = 0, tau = 0, converged = 0, stranded = 0, moved = 0 }
  for _, name in ipairs(NAMES) do
    out["truth_" .. name], out["rank_" .. name] = truth[name], -1
    out["in50_" .. name], out["in90_" .. name], out["bounded_" .. name] = 0, 0, 0
  end
  local m = build(truth, ch)
  if not m:run_to_steady{}.converged then return out end -- the model fails there: left out
  local A, S = m:get("A"), m:get("S")
  local dA, dS = {}, {}
  for i, k in ipairs(nodes) do
    local u1, u2 = math.random(), math.random()
    dA[i] = A[k]
    dS[i] = S[k] * math.exp(truth.sigma * math.sqrt(-2 * math.log(u1)) *
                            math.cos(2 * math.pi * u2))
  end
  local spec = { data = { A = dA, S = dS }, channel = ch, build = build, params = PRIORS,
                 sigma = SIGMA, seed = rep, lsq = false }
  for k, v in pairs(SAMPLER) do spec[k] = v end
  local res = dfle.invert(spec)
  if not res.summary then return out end -- interrupted: no result
  local K, n = res.walkers, res.nsamples
  local post = n // K -- steps after burn-in
  out.ok, out.tau, out.converged = 1, res.tau_max, res.converged and 1 or 0
  out.stranded, out.moved = #(res.stranded or {}), #(res.moved or {})
  for _, name in ipairs(NAMES) do
    local x = res.samples[name]
    -- L = DRAW_STEPS x K - 1 draws: every walker at steps far apart
    local rank, L = 0, 0
    for s = 1, DRAW_STEPS do
      local step = math.floor((s - 0.5) * post / DRAW_STEPS)
      for w = 1, K do
        if L < DRAW_STEPS * K - 1 then
          L = L + 1
          if x[step * K + w] < truth[name] then rank = rank + 1 end
        end
      end
    end
    local sorted = table.move(x, 1, n, 1, {})
    table.sort(sorted)
    local t = truth[name]
    out["rank_" .. name] = rank
    out["in50_" .. name] = (quantile(sorted, 0.25) <= t and t <= quantile(sorted, 0.75)) and 1 or 0
    out["in90_" .. name] = (quantile(sorted, 0.05) <= t and t <= quantile(sorted, 0.95)) and 1 or 0
    local b = res.summary[name].bounded
    out["bounded_" .. name] = b == "lower" and 1 or b == "upper" and 2 or b == "both" and 3 or 0
  end
  return out
end

local t0 = os.time()
local ens = dfle.ensemble{
  params = { u = { 0, 1 } }, n = NREP, seed = 7, out = ("%s/sbc_%s.csv"):format(outdir, which),
  build = function() return dfle.model{ channel = dfle.channel{ dx = 100 } } end, -- a stand-in
  measure = function(_, _, p) return replicate(math.floor(p.u * NREP) + 1) end,
  outputs = outputs,
}
if dfle.worker() then return end

-- ln Gamma (Lanczos) and the chi-square survival function.
local function lgamma(z)
  local c = { 676.5203681218851, -1259.1392167224028, 771.32342877765313, -176.61502916214059,
              12.507343278686905, -0.13857109526572012, 9.9843695780195716e-6,
              1.5056327351493116e-7 }
  if z < 0.5 then return math.log(math.pi / math.abs(math.sin(math.pi * z))) - lgamma(1 - z) end
  z = z - 1
  local x, t = 0.99999999999980993, z + 7.5
  for i = 1, 8 do x = x + c[i] / (z + i) end
  return 0.5 * math.log(2 * math.pi) + (z + 0.5) * math.log(t) - t + math.log(x)
end
local function chisq_sf(x, k) -- P(X > x), X ~ chi-square with k dof
  local a, y = k / 2, x / 2
  if y <= 0 then return 1 end
  if y < a + 1 then
    local sum, del, ap = 1 / a, 1 / a, a
    for _ = 1, 10000 do
      ap = ap + 1
      del = del * y / ap
      sum = sum + del
      if math.abs(del) < math.abs(sum) * 1e-15 then break end
    end
    return 1 - sum * math.exp(-y + a * math.log(y) - lgamma(a))
  end
  local b, c, d = y + 1 - a, 1 / 1e-300, 1 / (y + 1 - a)
  local h = d
  for i = 1, 10000 do
    local an = -i * (i - a)
    b = b + 2
    d = an * d + b
    if math.abs(d) < 1e-300 then d = 1e-300 end
    c = b + an / c
    if math.abs(c) < 1e-300 then c = 1e-300 end
    d = 1 / d
    local del = d * c
    h = h * del
    if math.abs(del - 1) < 1e-15 then break end
  end
  return math.exp(-y + a * math.log(y) - lgamma(a)) * h
end

local d = ens.data
local ok = {}
for r = 1, ens.count do
  if d.status[r] == "ok" and d.ok[r] == 1 then ok[#ok + 1] = r end
end
local N = #ok
local L = DRAW_STEPS * (SAMPLER.walkers or 32) - 1
local per_bin = (L + 1) / NBINS
local stranded, moved, unconverged = 0, 0, 0
for _, r in ipairs(ok) do
  stranded = stranded + d.stranded[r]
  moved = moved + d.moved[r]
  unconverged = unconverged + (1 - d.converged[r])
end
print(("%s priors: %d replicates (%d left out: the model fails at the truth, or a row failed), " ..
       "%d draws each, %d s"):format(which, N, ens.count - N, L, os.time() - t0))
print(("  %d chains shorter than 50 tau, %d stranded walkers after burn-in, %d moved in burn-in")
      :format(unconverged, stranded, moved))
print(("%-8s %10s %8s %10s %10s %s"):format("", "chi-square", "p", "50 %", "90 %", ""))
local rows, hist, bad = {}, {}, {}
for _, name in ipairs(NAMES) do
  local counts = {}
  for b = 1, NBINS do counts[b] = 0 end
  local c50, c90 = 0, 0
  for _, r in ipairs(ok) do
    local b = math.floor(d["rank_" .. name][r] / per_bin) + 1
    counts[b] = counts[b] + 1
    c50, c90 = c50 + d["in50_" .. name][r], c90 + d["in90_" .. name][r]
  end
  local E, chi2 = N / NBINS, 0
  for b = 1, NBINS do chi2 = chi2 + (counts[b] - E) ^ 2 / E end
  local p = chisq_sf(chi2, NBINS - 1)
  c50, c90 = c50 / N, c90 / N
  local verdict = (p >= 0.01 and c90 >= 0.85 and c90 <= 0.95) and "" or "  <- off"
  print(("%-8s %10.2f %8.3f %10.3f %10.3f%s"):format(name, chi2, p, c50, c90, verdict))
  rows[#rows + 1] = { parameter = name, replicates = N, chi2 = chi2, dof = NBINS - 1, p = p,
                      coverage50 = c50, coverage90 = c90,
                      sd50 = math.sqrt(0.25 / N), sd90 = math.sqrt(0.09 / N) }
  hist[name] = counts
  if p < 0.001 or c90 < 0.5 then bad[#bad + 1] = name end
end
print(("binomial sd of the coverages: %.3f (50 %%), %.3f (90 %%)")
      :format(math.sqrt(0.25 / N), math.sqrt(0.09 / N)))
dfle.write_csv(("%s/sbc_%s_summary.csv"):format(outdir, which), {
  columns = { "parameter", "replicates", "chi2", "dof", "p", "coverage50", "coverage90", "sd50",
              "sd90" },
  rows = rows,
  units = { replicates = "-", chi2 = "-", dof = "-", p = "-", coverage50 = "-", coverage90 = "-",
            sd50 = "-", sd90 = "-" },
  about = ("simulation-based calibration, %s priors: chi-square of the rank histogram " ..
           "(%d bins), its p, coverage of the central 50 and 90 %% intervals"):format(which, NBINS),
  params = { replicates = NREP, draws = L, walkers = SAMPLER.walkers or 32,
             steps = SAMPLER.steps or 2000, burn = SAMPLER.burn or 500 },
})

-- The rank histograms, one panel per parameter, with the band that 99 %
-- of the bins of uniform histograms stay in (binomial, N draws of 1/B).
do
  local function binom_quantile(n, p, q)
    local cdf, k, pk = 0, 0, (1 - p) ^ n
    while k <= n do
      cdf = cdf + pk
      if cdf >= q then return k end
      pk = pk * (n - k) / (k + 1) * p / (1 - p)
      k = k + 1
    end
    return n
  end
  local lo = binom_quantile(N, 1 / NBINS, 0.005)
  local hi = binom_quantile(N, 1 / NBINS, 0.995)
  local labels = { U = "{/:Italic U}", k_df = "{/:Italic k}_{df}", gamma = "γ", sigma = "σ" }
  local panels = {}
  for _, name in ipairs(NAMES) do
    local x, y = {}, {}
    for b = 1, NBINS do
      x[#x + 1], y[#y + 1] = (b - 1) / NBINS, hist[name][b]
      x[#x + 1], y[#y + 1] = b / NBINS, hist[name][b]
    end
    panels[#panels + 1] = {
      ylabel = labels[name] .. ": replicates", yrange = { 0, math.max(hi, table.unpack(hist[name])) * 1.25 },
      series = {
        { x = { 0, 1 }, lo = { lo, lo }, hi = { hi, hi }, rgb = "grey",
          label = #panels == 0 and "99 % of uniform histograms" or nil },
        { x = x, y = y, lines = true, rgb = "blue", width = 2,
          label = #panels == 0 and "rank of the truth" or nil },
      },
    }
  end
  dfle.plot.panels{
    path = ("%s/sbc_%s_ranks.png"):format(outdir, which), panels = panels,
    xlabel = ("Rank of the truth among %d posterior draws, as a fraction"):format(L),
    xrange = { 0, 1 },
    title = ("Simulation-based calibration, %s priors: %d replicates"):format(which, N),
  }
end
print(("wrote %s/sbc_%s.csv, sbc_%s_summary.csv, sbc_%s_ranks.png"):format(outdir, which, which,
                                                                           which))
if #bad > 0 then
  error(("the ranks of %s are far from uniform (p < 0.001) or their 90 %% intervals hold " ..
         "fewer than half the truths: the inversion is miscalibrated"):format(table.concat(bad, ", ")))
end
