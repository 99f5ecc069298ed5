-- invert_sbc.lua - simulation-based calibration of dfle.invert (Talts et
-- al. 2018): are its posteriors right on average over the prior?  And
-- how often do its intervals hold a fixed truth?
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
-- replicates.  A chi-square test of the rank histogram (8 bins) and the
-- coverages with their binomial bands are printed.
--
--   dfle examples/invert_sbc.lua [--quick] [--priors broad|narrow]
--        [--truths prior|fixed] [--walkers K] [--steps N] [--burn B]
--        [--replicates R] [output-directory]
--
-- broad (default): U log-uniform 1e-5 .. 1e-2 m/yr, k_df 1e-6 .. 1e-2,
-- gamma 0 .. 1, sigma log-uniform 0.005 .. 2 (the default noise prior);
-- narrow: U and k_df over Table G5 (1e-4 .. 1e-3, 5e-5 .. 1e-3).
-- --truths fixed: frequentist coverage instead, at four fixed truths not
-- drawn from the prior (FIXED below), each with R/4 noise draws; only
-- the coverages mean something there (no rank test).
--
-- The replicates run as a dfle.ensemble (one sample = one replicate, its
-- inversion in the sample's own worker), so all cores are used and an
-- interrupted study resumes.  Writes, with <run> = sbc_<priors> (or
-- fixed_<priors>, and a _w<K>_s<N>_b<B> tail for sampler settings
-- other than the defaults)
--   <run>.csv           one row per replicate: the truth, the ranks,
--                       whether the 50 and 90 % intervals hold it,
--                       tau, stranded walkers, bound flags
--   <run>_summary.csv   per parameter (and truth): chi-square, p,
--                       coverages and their bands
--   <run>_ranks.png     the rank histograms with the band that 99 % of
--                       uniform histograms stay in (truths from the prior)
-- The full study (200 replicates) takes 10-20 minutes on two cores.
-- --quick (the test suite) runs 40 small replicates of a coarse model
-- with short chains.  Either way the script fails (an error, after its
-- files are written) when, for truths from the prior, a parameter's
-- ranks are far from uniform (chi-square p < 0.001) or a 50 or 90 %
-- coverage count lies outside the binomial interval that holds 99.9 %
-- of the counts of calibrated intervals: able to catch a miscalibrated
-- sampler, rarely fooled by chance (the seeds are fixed).

local opts = dfle.args{
  usage = "dfle examples/invert_sbc.lua [options] [output-directory]",
  about = "Simulation-based calibration of dfle.invert: ranks of the truth and coverage.",
  flags = { quick = "40 small replicates (for the test suite)" },
  options = {
    priors = { "broad|narrow", "the priors of the inversion (default broad)" },
    truths = { "prior|fixed", "truths drawn from the priors (default) or four fixed ones" },
    walkers = { "K", "walkers of each inversion (default: dfle.invert's, 32)" },
    steps = { "N", "steps of each inversion (default: dfle.invert's, 2000)" },
    burn = { "B", "burn-in steps (default: dfle.invert's, steps / 4)" },
    replicates = { "R", "replicates (default 200; quick 40)" },
  },
  output = true,
}
local quick, outdir = opts.quick, opts.output
local which = opts.priors or "broad"
if which ~= "broad" and which ~= "narrow" then
  error("--priors must be broad or narrow, got " .. which)
end
local truths = opts.truths or "prior"
if truths ~= "prior" and truths ~= "fixed" then
  error("--truths must be prior or fixed, got " .. truths)
end
local function count_option(name, min)
  local s = opts[name]
  if s == nil then return nil end
  local v = math.tointeger(tonumber(s))
  if v == nil or v < min then
    error(("--%s must be a whole number >= %d, got %s"):format(name, min, s))
  end
  return v
end

local NREP = count_option("replicates", 1) or (quick and 40 or 200)
local NOBS = 25
local SAMPLER = quick and { walkers = 12, steps = 400, burn = 100 } or {} -- {}: the defaults
local tail = ""
for _, k in ipairs{ "walkers", "steps", "burn" } do
  local v = count_option(k, k == "burn" and 0 or 1)
  if v ~= nil then SAMPLER[k] = v end
end
if (opts.walkers or opts.steps or opts.burn) ~= nil then
  tail = ("_w%d_s%d_b%d"):format(SAMPLER.walkers or 32, SAMPLER.steps or 2000,
                                 SAMPLER.burn or (SAMPLER.steps or 2000) // 4)
end
local RUN = ("%s/%s_%s%s"):format(outdir, truths == "prior" and "sbc" or "fixed", which, tail)
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
local LEVELS = { 50, 90, 95 } -- the central intervals whose coverage is counted
local function prior_of(name) return name == "sigma" and SIGMA or PRIORS[name] end
-- The fixed truths (--truths fixed): inside both priors' supports but
-- not drawn from them; the first is the Fig. 9 set with 10 % noise.
local FIXED = {
  { U = 5e-4, k_df = 1e-4, gamma = 0.5, sigma = 0.1 },
  { U = 2e-4, k_df = 5e-4, gamma = 0.2, sigma = 0.05 },
  { U = 8e-4, k_df = 6e-5, gamma = 0.8, sigma = 0.2 },
  { U = 3e-4, k_df = 2e-4, gamma = 0.5, sigma = 0.02 },
}

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
  for _, o in ipairs{ "truth_", "median_", "rank_", "in50_", "in90_", "in95_", "bounded_" } do
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
  if truths == "fixed" then truth = FIXED[(rep - 1) % #FIXED + 1] end
  local out = { ok = 0, tau = 0, converged = 0, stranded = 0, moved = 0 }
  for _, name in ipairs(NAMES) do
    out["truth_" .. name], out["rank_" .. name] = truth[name], -1
    out["median_" .. name], out["bounded_" .. name] = 0, 0
    for _, c in ipairs(LEVELS) do out[("in%d_%s"):format(c, name)] = 0 end
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
    out["median_" .. name] = quantile(sorted, 0.5)
    for _, c in ipairs(LEVELS) do -- the central c % interval
      local q = (1 - c / 100) / 2
      out[("in%d_%s"):format(c, name)] =
        (quantile(sorted, q) <= t and t <= quantile(sorted, 1 - q)) and 1 or 0
    end
    local b = res.summary[name].bounded
    out["bounded_" .. name] = b == "lower" and 1 or b == "upper" and 2 or b == "both" and 3 or 0
  end
  return out
end

local t0 = os.time()
local ens = dfle.ensemble{
  params = { u = { 0, 1 } }, n = NREP, seed = 7, out = RUN .. ".csv",
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

-- The smallest k with P(X <= k) >= q, X ~ binomial(n, p); and the
-- central interval that holds 99.9 % of such counts.
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
local function band(n, p) return binom_quantile(n, p, 0.0005), binom_quantile(n, p, 0.9995) end

local d = ens.data
local ok = {}
for r = 1, ens.count do
  if d.status[r] == "ok" and d.ok[r] == 1 then ok[#ok + 1] = r end
end
local N = #ok
local L = DRAW_STEPS * (SAMPLER.walkers or 32) - 1
local per_bin = (L + 1) / NBINS
local stranded, moved, unconverged, taus = 0, 0, 0, {}
for _, r in ipairs(ok) do
  stranded = stranded + d.stranded[r]
  moved = moved + d.moved[r]
  unconverged = unconverged + (1 - d.converged[r])
  taus[#taus + 1] = d.tau[r]
end
table.sort(taus)
local walkers, steps = SAMPLER.walkers or 32, SAMPLER.steps or 2000
local burn = SAMPLER.burn or steps // 4
print(("%s priors, truths %s: %d replicates (%d left out: the model fails at the truth, or a " ..
       "row failed), %d walkers x %d steps (burn-in %d), %d s")
      :format(which, truths == "prior" and "drawn from them" or "fixed", N, ens.count - N,
              walkers, steps, burn, os.time() - t0))
if N == 0 then error("no replicate ran: nothing to summarise") end
print(("  median tau %.0f steps (the %d steps after burn-in are %.0f tau); %d chains shorter " ..
       "than 50 tau, %d stranded walkers after burn-in, %d moved in burn-in")
      :format(quantile(taus, 0.5), steps - burn, (steps - burn) / quantile(taus, 0.5),
              unconverged, stranded, moved))

local units = { replicates = "-", chi2 = "-", dof = "-", p = "-" }
local columns = { "parameter", "replicates" }
local function level_columns()
  for _, c in ipairs(LEVELS) do
    for _, f in ipairs{ "coverage%d", "lo%d", "hi%d" } do
      columns[#columns + 1] = f:format(c)
      units[f:format(c)] = "-"
    end
  end
end
-- Coverage counts of the replicates in `set` for one parameter: a row's
-- coverage<c> fields, with the 99.9 % binomial band of a calibrated
-- interval as lo<c> .. hi<c> (fractions); the text of the table's cells,
-- and whether a count lies outside its band.
local function coverages(set, name, row)
  local cells, outside = {}, false
  for _, c in ipairs(LEVELS) do
    local k = 0
    for _, r in ipairs(set) do k = k + d[("in%d_%s"):format(c, name)][r] end
    local lo, hi = band(#set, c / 100)
    row[("coverage%d"):format(c)] = k / #set
    row[("lo%d"):format(c)], row[("hi%d"):format(c)] = lo / #set, hi / #set
    local off = k < lo or k > hi
    outside = outside or off
    cells[#cells + 1] = ("%3d/%-3d %5.3f%s"):format(k, #set, k / #set, off and "*" or " ")
  end
  return table.concat(cells, "  "), outside
end

local rows, hist, bad = {}, {}, {}
if truths == "prior" then
  print(("%-8s %10s %8s   %-16s %-16s %-16s"):format("", "chi-square", "p", "50 %", "90 %",
                                                     "95 %"))
  columns[#columns + 1], columns[#columns + 2], columns[#columns + 3] = "chi2", "dof", "p"
  level_columns()
  for _, name in ipairs(NAMES) do
    local counts = {}
    for b = 1, NBINS do counts[b] = 0 end
    for _, r in ipairs(ok) do
      local b = math.floor(d["rank_" .. name][r] / per_bin) + 1
      counts[b] = counts[b] + 1
    end
    local E, chi2 = N / NBINS, 0
    for b = 1, NBINS do chi2 = chi2 + (counts[b] - E) ^ 2 / E end
    local p = chisq_sf(chi2, NBINS - 1)
    local row = { parameter = name, replicates = N, chi2 = chi2, dof = NBINS - 1, p = p }
    local cells, outside = coverages(ok, name, row)
    local off = p < 0.001 or outside
    print(("%-8s %10.2f %8.3f%s  %s%s"):format(name, chi2, p, p < 0.001 and "*" or " ", cells,
                                               off and "  <- off" or ""))
    rows[#rows + 1] = row
    hist[name] = counts
    if off then bad[#bad + 1] = name end
  end
  print("  * outside the interval that holds 99.9 % of calibrated results " ..
        "(chi-square p < 0.001, or a count outside its binomial 99.9 % band)")
else
  -- Frequentist coverage: per fixed truth, over its noise draws.
  table.insert(columns, 2, "truth")
  table.insert(columns, 3, "value")
  table.insert(columns, 4, "median")
  level_columns()
  print(("%-6s %-8s %10s %10s   %-16s %-16s %-16s"):format("truth", "", "value",
        "median", "50 %", "90 %", "95 %"))
  for t, truth in ipairs(FIXED) do
    local set = {}
    for _, r in ipairs(ok) do
      if (math.floor(d.u[r] * NREP)) % #FIXED + 1 == t then set[#set + 1] = r end
    end
    for _, name in ipairs(NAMES) do
      if #set > 0 then
        local med = {}
        for _, r in ipairs(set) do med[#med + 1] = d["median_" .. name][r] end
        table.sort(med)
        local row = { parameter = name, truth = t, value = truth[name], replicates = #set,
                      median = quantile(med, 0.5) }
        local cells = coverages(set, name, row)
        print(("%-6d %-8s %10.4g %10.4g   %s"):format(t, name, truth[name], row.median, cells))
        rows[#rows + 1] = row
      end
    end
  end
  units.truth, units.value, units.median = "-", "(the parameter's)", "(the parameter's)"
  print("  * outside the interval that holds 99.9 % of the counts of intervals that cover at " ..
        "their nominal rate (not expected at a fixed truth: see doc/inversion.md)")
  print("  median: the median over the noise draws of the posterior median")
end
dfle.write_csv(RUN .. "_summary.csv", {
  columns = columns, rows = rows, units = units,
  about = truths == "prior" and
    ("simulation-based calibration, %s priors: chi-square of the rank histogram (%d bins) " ..
     "and its p; coverage of the central 50, 90 and 95 %% intervals with the binomial " ..
     "band lo .. hi that holds 99.9 %% of the coverages of calibrated intervals")
    :format(which, NBINS) or
    ("frequentist coverage, %s priors, at %d fixed truths: coverage of the central 50, " ..
     "90 and 95 %% intervals over the noise draws, the binomial 99.9 %% band of nominal " ..
     "coverage lo .. hi, the median posterior median"):format(which, #FIXED),
  params = { replicates = NREP, draws = L, walkers = walkers, steps = steps, burn = burn },
})

-- The rank histograms, one panel per parameter, with the band that 99 %
-- of the bins of uniform histograms stay in (binomial, N draws of 1/B).
if truths == "prior" then
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
    path = RUN .. "_ranks.png", panels = panels,
    xlabel = ("Rank of the truth among %d posterior draws, as a fraction"):format(L),
    xrange = { 0, 1 },
    title = ("Simulation-based calibration, %s priors: %d replicates, %d walkers x %d steps")
            :format(which, N, walkers, steps),
  }
  print(("wrote %s.csv, %s_summary.csv, %s_ranks.png"):format(RUN, RUN, RUN))
else
  print(("wrote %s.csv, %s_summary.csv"):format(RUN, RUN))
end
if #bad > 0 then
  error(("the ranks or coverages of %s are outside what calibrated intervals give in 99.9 %% " ..
         "of studies: the inversion is miscalibrated (or the chains too short)")
        :format(table.concat(bad, ", ")))
end
