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

local results = {}
for _, name in ipairs{ "empirical", "process" } do
  if only == nil or only == name then
    local e = experiments[name]
    results[name] = dfle.ensemble{
      params = e.params, n = e.n, seed = 1,
      out = outdir .. "/sensitivity_" .. name .. ".csv",
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

-- A parameter sampled over a decade or more reads best on a log axis.
local function wide(range) return range[2] / range[1] >= 10 end

local STATS = { "minimum", "mean", "median", "maximum", "CV", "stdev" }
for _, name in ipairs{ "empirical", "process" } do
  local ens = results[name]
  if ens then
    print(("%s router: %d samples, %d ok, %d failed -> %s"):format(name, ens.count, ens.ok,
          ens.failed, ens.file))
    if ens.ok >= 10 then
      local si = dfle.pawn(ens, { outputs = { "A_df", "S_df" }, S = 10,
                                  bootstrap = quick and 50 or 1000 })
      local f = assert(io.open(outdir .. "/pawn_" .. name .. ".csv", "w"))
      f:write("output,input," .. table.concat(STATS, ",") .. ",median_lo,median_hi\n")
      print(("  PAWN median index (S = 10), %s router:"):format(name))
      print(("  %-8s %8s %8s"):format("input", "A_df", "S_df"))
      for _, x in ipairs(ens.inputs) do
        for _, o in ipairs{ "A_df", "S_df" } do
          local r = si[o][x]
          local row = { o, x }
          for _, st in ipairs(STATS) do row[#row + 1] = ("%.6g"):format(r[st]) end
          row[#row + 1] = ("%.6g"):format(r.ci.median.lo)
          row[#row + 1] = ("%.6g"):format(r.ci.median.hi)
          f:write(table.concat(row, ","), "\n")
        end
        print(("  %-8s %8.3f %8.3f"):format(x, si.A_df[x].median, si.S_df[x].median))
      end
      f:close()
      -- A_df and S_df against each parameter, coloured by U (Figs. 5-8).
      local Ulabel, Ufactor = dfle.plot.label("U")
      local params = experiments[name].params
      for _, x in ipairs(ens.inputs) do
        if x ~= "U" then
          for _, o in ipairs{ "A_df", "S_df" } do
            dfle.plot.xy{
              path = ("%s/sens_%s_%s_%s.png"):format(outdir, name, x, o),
              title = ("%s against %s (%s router), coloured by U"):format(
                o:gsub("_(%w+)", "_{%1}"), x:gsub("_(%w+)", "_{%1}"), name),
              xlabel = dfle.plot.label(x), ylabel = dfle.plot.label(o), clabel = Ulabel,
              xlog = wide(params[x]), ylog = o == "A_df",
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
        local sym = o:gsub("_(%w+)", "_{%1}")
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
                        label = ("%s = %.3g U^{%.3g} (U in mm/yr)"):format(sym, c / Ufactor ^ k, k) }
          print(("  power-law fit: %s = %.4g U^%.4g (U in m/yr)"):format(o, c, k))
        end
        dfle.plot.xy{
          path = ("%s/sens_%s_U_%s.png"):format(outdir, name, o), xlog = true, ylog = true,
          title = ("%s against uplift rate (%s router)"):format(sym, name),
          xlabel = Ulabel, ylabel = dfle.plot.label(o), series = series,
        }
      end
    end
  end
end
