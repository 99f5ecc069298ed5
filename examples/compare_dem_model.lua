-- compare_dem_model.lua - a modelled steady state next to a real
-- catchment, on the real channel's geometry.
--
-- The comparison the paper's framework is for: does a debris-flow +
-- fluvial steady state reproduce the slope-area form of a real
-- debris-flow-prone catchment?  Here:
--   1. the Big Tujunga SRTM DEM is filled and routed; the blue Fig. 1
--      catchment (outlet 384971 E 3799277 N) gives its channel network's
--      slope-area data and its main stem's drainage area A(x);
--   2. a model channel follows that A(x) (resampled to uniform dx; width
--      w = k_w A^b as in the paper) and the model runs to steady state
--      with the Fig. 9 defaults;
--   3. both are binned and fitted with Eq. (2) the same way, printed,
--      written as CSV and drawn on one slope-area plot.
-- The defaults are not tuned to this catchment: changing U, k_df, alpha
-- or beta and watching S_df and A_df move towards the data's is the
-- point of the exercise.
--
--   dfle examples/compare_dem_model.lua [--quick] [output-directory]
--
-- --quick uses a 20 m model grid (for the test suite); the default is
-- the paper's 5 m.  The DEM is read from --data DIR or $DFLE_DATA_DIR
-- (the directory holding dem/); the script says so and stops when it is
-- missing.

local opts = dfle.args{
  usage = "dfle examples/compare_dem_model.lua [options] [output-directory]",
  about = "A modelled steady state next to a real catchment, on the real channel's geometry.",
  flags = { quick = "a 20 m model grid (for the test suite); the default is 5 m" },
  options = { data = { "DIR", "the data directory, holding dem/ (default: $DFLE_DATA_DIR)",
                       env = "DFLE_DATA_DIR",
                       needs = { "dem/srtm_bigtujunga30m_utm11.tif", "the Big Tujunga DEM" } } },
  output = true,
}
local quick, outdir = opts.quick, opts.output

local dem_file = opts.data_file
local outlet = { 384971, 3799277 }   -- Fig. 1, blue line

-- 1. The real catchment.
local dem = dfle.dem.read(dem_file)
dem:fill()
local net = dem:network{ A_min = dem.dx * dem.dy, outlet = outlet }
local main = dem:profile{ outlet = outlet }
print(("real: catchment %.2f km^2 (%d cells), main stem %.2f km from %.0f m^2 to %.3g m^2")
      :format(net.A_max / 1e6, net.n, main.length / 1e3, main.A_min, main.A_max))

-- 2. The model on the main stem's A(x).
local channel = main:channel{ dx = quick and 20 or 5 }
local model = dfle.model{
  channel = channel,
  U       = 5e-4,                                        -- m/yr
  fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
  router  = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500, tau_y = 300 },
  law     = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 },
}
model:init_fluvial_steady()
local run = model:run_to_steady{ tol = 1e-3, max_time = 2e7 }
print(("model: %d nodes at dx = %g m; %s after %.3g yr")
      :format(channel.n, channel.dx, run.converged and "steady" or run.reason, run.time))
if not run.converged then
  io.stderr:write("compare_dem_model: the model did not reach steady state\n")
  os.exit(1)
end

-- 3. The same analysis for both.
local rows, series = {}, {}
local function curve(fit, lo, hi)
  local A, S = {}, {}
  for i = 0, 100 do
    A[i + 1] = lo * (hi / lo) ^ (i / 100)
    S[i + 1] = fit.S_df / (1 + (A[i + 1] / fit.A_df) ^ fit.a2)
  end
  return A, S
end
for _, src in ipairs{ { "catchment (DEM network)", net, "blue", "circle" },
                      { "model steady state", model, "vermillion", "open square" } } do
  local fit, why = dfle.fit_slope_area(src[2])
  if not fit then
    io.stderr:write("compare_dem_model: " .. src[1] .. ": " .. why .. "\n")
    os.exit(1)
  end
  print(("%-24s S_df = %.3f  A_df = %.3g m^2  a2 = %.2f  R^2 = %.3f  S_max - S_ch = %.3f")
        :format(src[1], fit.S_df, fit.A_df, fit.a2, fit.r2, fit.S_max_minus_S_ch))
  rows[#rows + 1] = { source = src[1], S_df = fit.S_df, A_df = fit.A_df, a2 = fit.a2, r2 = fit.r2,
                      S_max_minus_S_ch = fit.S_max_minus_S_ch }
  local A, S = curve(fit, fit.bins.A[1], fit.bins.A[#fit.bins.A])
  series[#series + 1] = { x = fit.bins.A, y = fit.bins.S, label = src[1] .. ", binned",
                          rgb = src[3], marker = src[4] }
  series[#series + 1] = { x = A, y = S, lines = true, rgb = src[3],
                          label = ("%s: Eq. (2), {/:Italic A}_{df} = %s m^2"):format(src[1],
                                   dfle.plot.number(fit.A_df)) }
end

local csv = outdir .. "/compare_fits.csv"
dfle.write_csv(csv, {
  about = "Eq. (2) fitted to the DEM network of the catchment and to the model on its A(x)",
  columns = { "source", "S_df", "A_df", "a2", "r2", "S_max_minus_S_ch" },
  units = { S_df = "-", A_df = "m^2", a2 = "-", r2 = "-", S_max_minus_S_ch = "-" },
  rows = rows,
  params = { model = model, dem = { file = dem_file } },
})
model:write_csv(outdir .. "/compare_model.csv")
main:write_csv(outdir .. "/compare_main_stem.csv")
local png = outdir .. "/compare_dem_model.png"
dfle.plot.xy{ path = png, series = series, xlog = true, ylog = true,
              title = "Blue Fig. 1 catchment (SRTM 30 m) and a model on its A(x)",
              xlabel = dfle.plot.label("A"), ylabel = dfle.plot.label("S") }
print("wrote " .. csv .. ", " .. png .. ", compare_model.csv, compare_main_stem.csv")
