-- ensemble_sensitivity.lua - the paper's global sensitivity analyses
-- (Sect. 2.5.2, Tables G4-G5, Figs. 5-10): Latin hypercube ensembles
-- with the process-based router (Table G4, 1500 samples) and the
-- empirical router (Table G5, 4000 samples), alpha = 6, beta = 1; PAWN
-- indices of every input for A_df and S_df; scatter plots.
--
--   dfle examples/ensemble_sensitivity.lua [--quick] [--router empirical|process] [output-directory]
--
-- Writes, per router:
--   sensitivity_<router>.csv       one row per sample (doc/ensembles.md;
--                                  resumable: run again after an interruption)
--   pawn_<router>.csv              PAWN indices (S = 10) of each input for
--                                  A_df and S_df, with 95% bootstrap intervals
--   sens_<router>_<param>_A_df.png, ..._S_df.png
--                                  A_df and S_df against the parameter,
--                                  coloured by U (mm/yr); parameters sampled
--                                  over a decade or more on a log axis
--   sens_<router>_U_A_df.png, ..._S_df.png
--                                  A_df and S_df against U with power-law fits
-- --quick: 32 samples per router on a coarse channel (dx = 20 m), 50
-- bootstrap replicates.  Uses all cores (-j N); `dfle --shard i/n` and
-- build/dfle-mpi work too.

local opts = dfle.args{
  usage = "dfle examples/ensemble_sensitivity.lua [options] [output-directory]",
  about = "The paper's sensitivity analyses (doc/ensembles.md).",
  flags = { quick = "32 samples per router on a 20 m grid (for the test suite)" },
  options = { router = { "NAME", "run only this router's ensemble: empirical or process" } },
  output = true,
}
local quick, outdir, only = opts.quick, opts.output, opts.router
if only ~= nil and only ~= "empirical" and only ~= "process" then
  error(("--router must be empirical or process (got %q)"):format(only))
end

local dx = quick and 20 or 5
local experiments = {
  empirical = {                                    -- Table G5
    n = quick and 32 or 4000,
    params = {
      M0 = { 1000, 5000 }, gamma = { 0, 1 }, mu = { 100, 1000 }, tau_y = { 100, 600 },
      k_df = { 5e-5, 1e-3 }, k_e = { 2e-14, 8e-14 }, U = { 1e-4, 1e-3 },
    },
    router = function(p)
      return dfle.router.empirical{ M0 = p.M0, gamma = p.gamma, mu = p.mu, tau_y = p.tau_y }
    end,
  },
  process = {                                      -- Table G4
    n = quick and 32 or 1500,
    params = {
      k_e = { 2e-14, 8e-14 }, U = { 2e-4, 1e-3 }, mu2 = { 0.532, 0.869 }, D = { 1e-6, 1e-5 },
      eta = { 30, 90 }, k_df = { 3e-5, 1.2e-4 },
    },
    router = function(p)
      return dfle.router.process{ M0 = 200, gamma = 0, mu2 = p.mu2, D = p.D, eta = p.eta }
    end,
  },
}

-- Units of the sampled parameters, for the file's "# units:" line (dfle
-- knows those of its own outputs).
local UNITS = { M0 = "m^(3-2 gamma)", gamma = "-", mu = "Pa s", tau_y = "Pa", U = "m/yr",
                k_df = "m^(1-beta) s^-1 yr^-1", k_e = "m^2.5 s^2 kg^-1.5", mu2 = "-",
                D = "m^2/s", eta = "Pa s", alpha = "-", beta = "-" }
local function units_of(params)
  local u = {}
  for name in pairs(params) do u[name] = UNITS[name] end
  return u
end

local results = {}
for _, name in ipairs{ "empirical", "process" } do
  if only == nil or only == name then
    local e = experiments[name]
    results[name] = dfle.ensemble{
      params = e.params, n = e.n, seed = 1,
      out = outdir .. "/sensitivity_" .. name .. ".csv",
      units = units_of(e.params),
      build = function(p)
        return dfle.model{
          channel = dfle.channel{ dx = dx }, U = p.U,
          fluvial = dfle.fluvial.stochastic_threshold{ k_e = p.k_e },
          router = e.router(p),
          law = dfle.law.power{ k_df = p.k_df, alpha = 6, beta = 1 },
        }
      end,
      outputs = { "S_df", "A_df", "r2", "S_max_minus_S_ch" },
    }
  end
end

-- Least squares of log y on log x: y = c x^k.
local function power_fit(xs, ys)
  local n, sx, sy, sxx, sxy = 0, 0, 0, 0, 0
  for j = 1, #xs do
    if xs[j] > 0 and ys[j] > 0 then
      local lx, ly = math.log(xs[j]), math.log(ys[j])
      n, sx, sy, sxx, sxy = n + 1, sx + lx, sy + ly, sxx + lx * lx, sxy + lx * ly
    end
  end
  if n < 2 or n * sxx - sx * sx == 0 then return nil end
  local k = (n * sxy - sx * sy) / (n * sxx - sx * sx)
  return math.exp((sy - k * sx) / n), k
end

-- The ok rows of an ensemble column.
local function column(ens, name)
  local v = {}
  for r = 1, ens.count do
    if ens.data.status[r] == "ok" then v[#v + 1] = ens.data[name][r] end
  end
  return v
end

-- Scatter of y against x, each point coloured by `color` (times the
-- factor of its axis unit: U in mm/yr) on a continuous scale
-- (dfle.plot.xy draws the colour box).
local function colored(ens, x, y, color, factor)
  local c = column(ens, color)
  for i = 1, #c do c[i] = c[i] * factor end
  return { { x = column(ens, x), y = column(ens, y), color = c } }
end

-- A parameter sampled log-uniformly, or over a decade or more, reads
-- best on a log axis (gamma from 0 to 1 does not).
local function wide(range)
  return range.log == true or (range[1] > 0 and range[2] / range[1] >= 10)
end

-- A name as a title shows it: gamma as γ, k_df as k_{df}.
local SYMBOLS = { gamma = "γ", mu = "μ", mu2 = "μ_2", eta = "η", tau_y = "τ_y", M0 = "M_0" }
local function symbol(name)
  return (SYMBOLS[name] or name):gsub("_(%w+)", "_{%1}")
end

-- The axis of a parameter spans the range it was sampled from (times
-- `factor`), padded 4 % so no point sits on the frame: the figure shows
-- where in its range each sample lies, and the range's round ends
-- (10^{-6}, 10^{-5}) are labelled.
local function sampled_range(range, log, factor)
  local lo, hi = range[1] * factor, range[2] * factor
  if log then
    local r = (hi / lo) ^ 0.04
    return { lo / r, hi * r }
  end
  local pad = 0.04 * (hi - lo)
  return { lo - pad, hi + pad }
end

local STATS = { "minimum", "mean", "median", "maximum", "CV", "stdev" }
for _, name in ipairs{ "empirical", "process" } do
  local ens = results[name]
  if ens then
    print(("%s router: %d samples, %d ok, %d failed -> %s"):format(name, ens.count, ens.ok,
          ens.failed, ens.file))
    if ens.ok >= 10 then
      local si = dfle.pawn(ens, { outputs = { "A_df", "S_df" }, S = 10,
                                  bootstrap = quick and 50 or 1000 })
      local rows = {}
      print(("  PAWN median index (S = 10), %s router:"):format(name))
      print(("  %-8s %8s %8s"):format("input", "A_df", "S_df"))
      for _, x in ipairs(ens.inputs) do
        for _, o in ipairs{ "A_df", "S_df" } do
          local r = si[o][x]
          local row = { output = o, input = x, median_lo = r.ci.median.lo,
                        median_hi = r.ci.median.hi }
          for _, st in ipairs(STATS) do row[st] = r[st] end
          rows[#rows + 1] = row
        end
        print(("  %-8s %8.3f %8.3f"):format(x, si.A_df[x].median, si.S_df[x].median))
      end
      local columns, units = { "output", "input" }, { median_lo = "-", median_hi = "-" }
      for _, st in ipairs(STATS) do columns[#columns + 1], units[st] = st, "-" end
      columns[#columns + 1], columns[#columns + 2] = "median_lo", "median_hi"
      dfle.write_csv(outdir .. "/pawn_" .. name .. ".csv", {
        about = ("PAWN indices (S = 10) of each input for A_df and S_df, %s router, from %s; "
                 .. "median_lo, median_hi: 95 %% bootstrap interval of the median"):format(name, ens.file),
        columns = columns, units = units, rows = rows,
        params = { pawn = { S = 10, bootstrap = quick and 50 or 1000, ok_rows = ens.ok } },
      })
      -- A_df and S_df against each parameter, coloured by U (Figs. 5-8).
      local Ulabel, Ufactor = dfle.plot.label("U")
      local params = experiments[name].params
      for _, x in ipairs(ens.inputs) do
        if x ~= "U" then
          for _, o in ipairs{ "A_df", "S_df" } do
            dfle.plot.xy{
              path = ("%s/sens_%s_%s_%s.png"):format(outdir, name, x, o),
              title = ("%s against %s (%s router), coloured by U"):format(
                symbol(o), symbol(x), name),
              xlabel = dfle.plot.label(x), ylabel = dfle.plot.label(o), clabel = Ulabel,
              xlog = wide(params[x]), ylog = o == "A_df",
              xrange = sampled_range(params[x], wide(params[x]), 1),
              series = colored(ens, x, o, "U", Ufactor),
            }
          end
        end
      end
      -- A_df and S_df against U with power-law fits (Figs. 9-10), U in mm/yr.
      local U = column(ens, "U")
      local Umm = {}
      for i, u in ipairs(U) do Umm[i] = u * Ufactor end
      for _, o in ipairs{ "A_df", "S_df" } do
        local y = column(ens, o)
        local sym = symbol(o)
        local series = { { x = Umm, y = y, label = "samples", rgb = "grey" } }
        local c, k = power_fit(U, y)
        if c then
          local lo, hi = math.huge, -math.huge
          for _, u in ipairs(Umm) do lo, hi = math.min(lo, u), math.max(hi, u) end
          local xs, ys = {}, {}
          for j = 0, 20 do
            xs[j + 1] = lo * (hi / lo) ^ (j / 20)
            ys[j + 1] = c * (xs[j + 1] / Ufactor) ^ k
          end
          series[2] = { x = xs, y = ys, lines = true, rgb = "vermillion",
                        label = ("%s = %s U^{%.3g} (U in mm/yr)"):format(sym,
                          dfle.plot.number(c / Ufactor ^ k), k) }
          print(("  power-law fit: %s = %.4g U^%.4g (U in m/yr)"):format(o, c, k))
        end
        dfle.plot.xy{
          path = ("%s/sens_%s_U_%s.png"):format(outdir, name, o), xlog = true, ylog = true,
          title = ("%s against uplift rate (%s router)"):format(sym, name),
          xlabel = Ulabel, ylabel = dfle.plot.label(o), series = series,
          xrange = sampled_range(params.U, true, Ufactor),
        }
      end
    end
  end
end
