-- invert_fig1.lua - erosion rates from the two Fig. 1 catchments of the
-- Big Tujunga DEM: the posterior of the uplift (= steady erosion) rate U
-- with the debris-flow erodibility k_df (which carries the debris-flow
-- frequency) and the volume-area exponent gamma free over their Table G5
-- ranges.
--
-- The question of the paper's Sect. 4.3: can the shape of a channel
-- network's slope-area curve tell the erosion rate?  For each catchment
-- (outlets black 396887 E 3799338 N and blue 384971 E 3799277 N, UTM
-- 11N) the network of every cell above the outlet is binned into 30
-- area bins (mean slope, as Fig. 1) and compared with the steady profile
-- of the empirical model on the catchment's own main stem (its A(x)).
-- The other parameters keep the Fig. 9 values (M0 = 3000 m^3, mu = 500
-- Pa s, tau_y = 300 Pa, alpha = 6, beta = 1, k_e = 5e-14): the posterior
-- of U is conditional on them, and on k_e above all, which sets the
-- fluvial reach that pins U down (doc/inversion.md, "What the posterior
-- does and does not tell you").  In the debris-flow reach U trades off
-- with k_df and gamma: the corner plots show the ridge.
--
--   dfle examples/invert_fig1.lua [--quick] [output-directory]
--
-- A third inversion frees k_e as well (black catchment), to show what
-- fixing it bought.  Writes, per run (black, blue, black_ke),
-- fig1_invert_<run>_chain.csv (resumable), fig1_invert_<run>_corner.png
-- and fig1_invert_<run>_pp.png, and fig1_invert.csv (the posterior
-- summaries).  The full run takes 10-20 minutes on two cores.  --quick (the test
-- suite, the figure gallery) runs a very short chain on a coarse channel,
-- whose figures only show that they are drawn.  The DEM is read from
-- --data DIR or $DFLE_DATA_DIR (the directory holding dem/); without it
-- the script says so and stops.

local opts = dfle.args{
  usage = "dfle examples/invert_fig1.lua [options] [output-directory]",
  about = "The posterior of U for the two Fig. 1 catchments of the Big Tujunga DEM.",
  flags = { quick = "a very short chain on a coarse channel (for the test suite and the gallery)" },
  options = { data = { "DIR", "the data directory, holding dem/ (default: $DFLE_DATA_DIR)",
                       env = "DFLE_DATA_DIR",
                       needs = { "dem/srtm_bigtujunga30m_utm11.tif", "the Big Tujunga DEM" } } },
  output = true,
}
local quick, outdir = opts.quick, opts.output

local path = opts.data_file

local catchments = {
  { name = "black", E = 396887, N = 3799338 },
  { name = "blue", E = 384971, N = 3799277 },
}
-- The inversions: U, k_df and gamma free in both catchments; then the
-- black one again with the fluvial erodibility k_e free too (Table G5:
-- 2e-14 to 8e-14), to see what fixing it bought.
local runs = {
  { c = catchments[1], tag = "black" },
  { c = catchments[2], tag = "blue" },
  { c = catchments[1], tag = "black_ke", free_ke = true },
}

local dem = dfle.dem.read(path)
dem:fill()

local function build(p, channel)
  return dfle.model{
    channel = channel, U = p.U,
    fluvial = dfle.fluvial.stochastic_threshold{ k_e = p.k_e },
    router = dfle.router.empirical{ M0 = 3000, gamma = p.gamma, mu = 500, tau_y = 300 },
    law = dfle.law.power{ k_df = p.k_df, alpha = 6, beta = 1 },
  }
end

local rows = {}
local nets = {}
for _, run in ipairs(runs) do
  local c = run.c
  nets[c.name] = nets[c.name] or dem:network{ A_min = dem.dx * dem.dy, outlet = { c.E, c.N } }
  local net = nets[c.name]
  local params = {
    U = { 1e-4, 1e-3, log = true },        -- Table G5: 0.1-1 mm/yr
    k_df = { 5e-5, 1e-3, log = true },
    gamma = { 0, 1 },
  }
  if run.free_ke then params.k_e = { 2e-14, 8e-14, log = true } end
  local res = dfle.invert{
    data = net, nbins = 30,
    channel = { dx = quick and 60 or 10 }, -- the main stem's A(x)
    build = build, params = params, fixed = not run.free_ke and { k_e = 5e-14 } or nil,
    walkers = quick and 10 or 32, steps = quick and 12 or 8000, burn = quick and 4 or 2000,
    seed = 1, lsq = not quick,
    out = ("%s/fig1_invert_%s_chain.csv"):format(outdir, run.tag),
  }
  -- Ctrl-C: the whole steps are in the chain file; a cut chain has no
  -- posterior, and running the command again resumes it.
  if res.reason == "interrupted" then print(res) return end
  if not dfle.worker() then
    print(("%s catchment%s: %d cells, %.2f km^2, %d bins"):format(c.name,
          run.free_ke and " (k_e free)" or "", net.n, net.A_max / 1e6, #res.data.A))
    print(res)
    -- the trade-off in numbers: correlations of the posterior (in ln for
    -- the log-scaled parameters)
    local function col(name)
      local v = {}
      for i, x in ipairs(res.samples[name]) do v[i] = name == "gamma" and x or math.log(x) end
      return v
    end
    local function corr(a, b)
      local x, y, n = col(a), col(b), res.nsamples
      local mx, my, sxy, sxx, syy = 0, 0, 0, 0, 0
      for i = 1, n do mx, my = mx + x[i], my + y[i] end
      mx, my = mx / n, my / n
      for i = 1, n do
        sxy = sxy + (x[i] - mx) * (y[i] - my)
        sxx, syy = sxx + (x[i] - mx) ^ 2, syy + (y[i] - my) ^ 2
      end
      return sxy / math.sqrt(sxx * syy)
    end
    local s = res.summary.U
    print(("  U = %.2f mm/yr (68 %%: %.2f-%.2f, 95 %%: %.2f-%.2f); correlations: " ..
           "ln U - ln k_df %.2f, ln U - gamma %.2f, ln k_df - gamma %.2f%s")
          :format(s.median * 1e3, s.lo68 * 1e3, s.hi68 * 1e3, s.lo95 * 1e3, s.hi95 * 1e3,
                  corr("U", "k_df"), corr("U", "gamma"), corr("k_df", "gamma"),
                  run.free_ke and (", ln U - ln k_e %.2f"):format(corr("U", "k_e")) or ""))
    -- A marginal piled against a prior bound is the prior's, not the data's.
    for _, name in ipairs(res.names) do
      local b = res.summary[name].bounded
      if b ~= nil then
        print(("  %s: held by the %s prior bound%s (the interval is the prior's there)")
              :format(name, b == "both" and "lower and upper" or b, b == "both" and "s" or ""))
      end
    end
    rows[#rows + 1] = { run, res }
    dfle.plot.corner(res, ("%s/fig1_invert_%s_corner.png"):format(outdir, run.tag), {
      params = run.free_ke and { "U", "k_e", "k_df", "gamma", "sigma" }
               or { "U", "k_df", "gamma", "sigma" },
      scale = { U = 1e3 }, -- mm/yr
      -- k_df in m^{1-beta} s^-1 yr^-1: with beta = 1, s^-1 yr^-1 (Eq. 6, E_df in m/yr)
      labels = { U = "{/:Italic U} (mm/yr)", k_df = "{/:Italic k}_{df} (s^{−1} yr^{−1})",
                 k_e = "{/:Italic k}_e (m^{2.5} s^2 kg^{−1.5})", gamma = "γ", sigma = "σ" },
      title = ("Big Tujunga, %s outlet: posterior%s"):format(c.name,
               run.free_ke and " with k_e free" or " (k_e = 5×10^{-14})"),
    })
    dfle.plot.posterior_predictive(res, ("%s/fig1_invert_%s_pp.png"):format(outdir, run.tag), {
      title = ("Big Tujunga, %s outlet: posterior-predictive slope-area%s"):format(c.name,
               run.free_ke and " (k_e free)" or ""),
    })
  end
end

if dfle.worker() then return end
local csv = outdir .. "/fig1_invert.csv"
local table_rows = {}
for _, r in ipairs(rows) do
  for _, name in ipairs(r[2].names) do
    local s = r[2].summary[name]
    table_rows[#table_rows + 1] = { run = r[1].tag, parameter = name, median = s.median,
                                    lo68 = s.lo68, hi68 = s.hi68, lo95 = s.lo95, hi95 = s.hi95,
                                    tau = r[2].tau[name], steps = r[2].steps,
                                    walkers = r[2].walkers }
  end
end
dfle.write_csv(csv, {
  columns = { "run", "parameter", "median", "lo68", "hi68", "lo95", "hi95", "tau", "steps",
              "walkers" },
  rows = table_rows,
  units = { tau = "steps" },
  about = "posterior summaries per run and parameter (each in the unit of its prior: U in " ..
          "m/yr); 68 and 95 % central intervals",
})
print("wrote " .. csv .. ", fig1_invert_<run>_chain.csv, fig1_invert_<run>_corner.png, " ..
      "fig1_invert_<run>_pp.png")
