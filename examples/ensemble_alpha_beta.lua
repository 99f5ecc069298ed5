-- ensemble_alpha_beta.lua - the paper's alpha-beta experiments (Sect.
-- 2.5.1, Figs. 2-4): Latin hypercube ensembles over the exponents of the
-- debris-flow incision law, Eq. (6), and the other parameters of Table
-- G2 (process-based router, 500 samples) and Table G3 (empirical router,
-- 4000 samples), scored by R^2 of the Eq. (2) fit and S_max - S_ch.
--
--   dfle examples/ensemble_alpha_beta.lua [--quick] [--router empirical|process] [output-directory]
--
-- Writes, per router, alpha_beta_<router>.csv (one row per sample, see
-- doc/ensembles.md; resumable: run again after an interruption) and
-- plots of S_max - S_ch and R^2 against alpha, coloured by beta on a
-- continuous scale.  --quick: 24 samples per router on
-- a coarse channel (dx = 20 m).  Uses all cores (-j N to choose);
-- `dfle --shard i/n` and build/dfle-mpi work too (doc/ensembles.md).

local opts = dfle.args{
  usage = "dfle examples/ensemble_alpha_beta.lua [options] [output-directory]",
  about = "The paper's alpha-beta experiments (doc/ensembles.md).",
  flags = { quick = "24 samples per router on a 20 m grid (for the test suite)" },
  options = { router = { "NAME", "run only this router's ensemble: empirical or process" } },
  output = true,
}
local quick, outdir, only = opts.quick, opts.output, opts.router
if only ~= nil and only ~= "empirical" and only ~= "process" then
  error(("--router must be empirical or process (got %q)"):format(only))
end

local dx = quick and 20 or 5
local experiments = {
  empirical = {                               -- Table G3
    n = quick and 24 or 4000,
    params = {
      M0 = { 500, 3000 }, gamma = { 0, 1 }, mu = { 100, 500 }, tau_y = { 100, 600 },
      alpha = { 2, 8 }, beta = { 0.5, 3 }, k_df = { 8e-5, 2e-4 },
    },
    router = function(p)
      return dfle.router.empirical{ M0 = p.M0, gamma = p.gamma, mu = p.mu, tau_y = p.tau_y }
    end,
    k_e = function() return 4.5e-14 end,
  },
  process = {                                 -- Table G2
    n = quick and 24 or 500,
    params = {
      alpha = { 2, 8 }, beta = { 0.5, 3 }, k_e = { 4e-14, 6e-14 }, mu2 = { 0.625, 0.781 },
      D = { 1e-6, 5e-6 }, eta = { 40, 80 }, k_df = { 4e-5, 6e-5 },
    },
    router = function(p)
      return dfle.router.process{ M0 = 200, gamma = 0, mu2 = p.mu2, D = p.D, eta = p.eta }
    end,
    k_e = function(p) return p.k_e end,
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
    local ens = dfle.ensemble{
      params = e.params, n = e.n, seed = 1,
      out = outdir .. "/alpha_beta_" .. name .. ".csv",
      units = units_of(e.params),
      build = function(p)
        return dfle.model{
          channel = dfle.channel{ dx = dx }, U = 5e-4,
          fluvial = dfle.fluvial.stochastic_threshold{ k_e = e.k_e(p) },
          router = e.router(p),
          law = dfle.law.power{ k_df = p.k_df, alpha = p.alpha, beta = p.beta },
        }
      end,
      outputs = { "S_df", "A_df", "r2", "S_max_minus_S_ch" },
    }
    results[name] = ens
  end
end

-- Scatter of y against x over the successful runs, each point coloured
-- by `color` on a continuous scale (dfle.plot.xy draws the colour box).
local function colored(ens, x, y, color)
  local d, s = ens.data, { x = {}, y = {}, color = {} }
  for r = 1, ens.count do
    if d.status[r] == "ok" then
      s.x[#s.x + 1], s.y[#s.y + 1], s.color[#s.color + 1] = d[x][r], d[y][r], d[color][r]
    end
  end
  return { s }
end

for name, ens in pairs(results) do
  print(("%s router: %d samples, %d ok, %d failed -> %s"):format(name, ens.count, ens.ok,
        ens.failed, ens.file))
  if ens.ok > 0 then
    dfle.plot.xy{
      path = outdir .. "/alpha_beta_" .. name .. "_smax.png",
      title = "S_{max} − S_{ch} against α (" .. name .. " router), coloured by β",
      xlabel = dfle.plot.label("alpha"), ylabel = dfle.plot.label("S_max_minus_S_ch"),
      series = colored(ens, "alpha", "S_max_minus_S_ch", "beta"), clabel = dfle.plot.label("beta"),
    }
    dfle.plot.xy{
      path = outdir .. "/alpha_beta_" .. name .. "_r2.png",
      title = "R^2 of the Eq. (2) fit against α (" .. name .. " router), coloured by β",
      xlabel = dfle.plot.label("alpha"), ylabel = dfle.plot.label("r2"),
      series = colored(ens, "alpha", "r2", "beta"), clabel = dfle.plot.label("beta"),
    }
  end
end
