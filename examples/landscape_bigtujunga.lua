-- landscape_bigtujunga.lua - the Big Tujunga catchment evolved to steady
-- state by debris flows and rivers, and its slope-area against the real
-- network's (the paper's Sect. 4.4 step to 2D landscapes).
--
-- The catchment above the black outlet of the paper's Fig. 1 (396887 E,
-- 3799338 N, 10.2 km^2) is cut from the SRTM DEM (30 m, UTM 11N): cells
-- outside it are NoData and closed, its outlet the base level.  Starting
-- from the real surface, the model (Fig. 9 components: stochastic-
-- threshold rivers, the empirical router from every channel head, the
-- power law; threshold hillslopes at S_c = 0.8, about 39 degrees as in
-- the San Gabriels) is brought to steady state under U = 0.5 mm/yr by
-- the direct method.  Both surfaces go through the same analysis: the
-- network of every cell above the outlet, slope over 90 m of flow path
-- (dem:network, as examples/fig1_slope_area.lua), 100 log bins, Eq. (2)
-- with residuals in log S (doc/landscape.md: the tail of the model's curve
-- counts as much as its steep head).
-- Writes
--   bigtujunga_steady.tif        z, A, S, E_f, E_df, reach (GeoTIFF)
--   bigtujunga_map.png           shaded relief, channels, debris-flow reach
--   bigtujunga_slope_area.png    model and DEM slope-area, binned, with fits
--   bigtujunga_series.nc         a transient from the real surface (NetCDF)
--   bigtujunga_catchment.gpkg    the DEM's catchment and channels (GeoPackage)
--
--   dfle examples/landscape_bigtujunga.lua [--quick] [output-directory]
--
-- --quick (the test suite) skips the transient; the steady state itself
-- takes well under a second on the catchment's 11,355 cells of 30 m.  The DEM is read from --data DIR or $DFLE_DATA_DIR (the
-- directory holding dem/); without it the script says so and stops.

local opts = dfle.args{
  usage = "dfle examples/landscape_bigtujunga.lua [options] [output-directory]",
  about = "The Big Tujunga catchment evolved to steady state; its slope-area against the DEM's.",
  flags = { quick = "no transient (for the test suite)" },
  options = { data = { "DIR", "the data directory, holding dem/ (default: $DFLE_DATA_DIR)",
                       env = "DFLE_DATA_DIR",
                       needs = { "dem/srtm_bigtujunga30m_utm11.tif", "the Big Tujunga DEM" } } },
  output = true,
}
local quick, outdir = opts.quick, opts.output
local path = opts.data_file
local function out(name) return outdir .. "/" .. name end

local outlet = { 396887, 3799338 }
local dem = dfle.dem.read(path)

-- channel heads at 1 ha: about 11 cells of 30 m
local A0 = 1e4
local ls = dfle.landscape{
  dem = dem, outlet = outlet,
  U = 5e-4, A0 = A0, S_c = 0.8,
  router = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500, tau_y = 300 },
  law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 },
}
print(("%s: %d cells with data (%.1f km^2)"):format(tostring(ls), ls.data_cells,
      ls.data_cells * ls.dx * ls.dy / 1e6))

-- the real network, measured as fig1_slope_area.lua does
local real_dem = ls:dem()
real_dem:fill() -- the SRTM surface has pits; dem:network needs none
local ds = 3 * ls.dx
local real = real_dem:network{ A_min = ls.dx * ls.dy, outlet = outlet, ds = ds }
-- the catchment as a polygon and its channels (1 ha and up) as lines, for QGIS
real_dem:write_gpkg(out("bigtujunga_catchment.gpkg"), { outlet = outlet, A_min = 1e4 })
-- Eq. (2) with residuals in log S, on each bin's geometric-mean slope
-- (doc/landscape.md, "Big Tujunga"): every decade of slope counts
-- alike, so the fit follows the gentle large-area bins as well as the
-- steep head; residuals in S (the paper's) let the steep bins dominate
-- and the line fell far below the model's own bins above A = 2e6 m^2.
local LOG = { residuals = "log" }
local fit_real = dfle.fit_slope_area(real, LOG)
local lin_real = dfle.fit_slope_area(real)

if not quick then
  -- a transient from the real surface, recorded in a NetCDF time series
  local tr = ls:run{ years = 2e4, dt = 1e3, record = { 0, 1e4, 2e4 },
                     netcdf = out("bigtujunga_series.nc"), fields = { "z", "E_df", "reach" } }
  print(("transient: %s, %d records"):format(tr.note, tr.recorded))
end

local t0 = os.clock()
local run = ls:run_to_steady{ max_time = 5e7, dt = 2e3, max_steps = 100000 }
local reached = 0
for _, v in ipairs(ls:get("reach")) do reached = reached + (v > 0 and 1 or 0) end
print(("steady state: %s (%s, %d steps, %.2f s); %.2f%% of the %d channel cells above tol U "
       .. "(max |dz/dt|/U %.3g), volume balance %.2g; %d channel heads, %d cells reached by "
       .. "debris flows"):format(run.converged and "reached" or "NOT reached", run.method,
       run.steps, os.clock() - t0, 100 * run.channel_frac_above, run.channel_cells,
       run.channel_max_ratio, run.volume_balance, run.heads, reached))
print("  " .. run.note)

local model_dem = ls:dem()
model_dem:fill() -- (a steady landscape has no pits: this changes nothing)
local model = model_dem:network{ A_min = ls.dx * ls.dy, outlet = outlet, ds = ds }
local fit_model = dfle.fit_slope_area(model, LOG)
local lin_model = dfle.fit_slope_area(model)
for _, p in ipairs{ { "DEM", fit_real, lin_real }, { "model", fit_model, lin_model } } do
  local fit, lin = p[2], p[3]
  if fit and lin then
    print(("%-5s log residuals:    S_df = %.3f, A_df = %.3g m^2, a2 = %.2f, R^2 in log S = %.3f, "
           .. "rmse %.3f decades"):format(p[1], fit.S_df, fit.A_df, fit.a2, fit.r2_log,
           fit.rmse_log))
    print(("%-5s linear residuals: S_df = %.3f, A_df = %.3g m^2, a2 = %.2f, R^2 in S = %.3f "
           .. "(in log S: %.3f, rmse %.3f decades)"):format(p[1], lin.S_df, lin.A_df, lin.a2,
           lin.r2, lin.r2_log, lin.rmse_log))
  else
    print(p[1] .. ": no fit")
  end
end

ls:write_geotiff(out("bigtujunga_steady.tif"), { "z", "A", "S", "E_f", "E_df", "reach" })
-- the title names what the map shows: the catchment as cut, its area
ls:plot(out("bigtujunga_map.png"), {
  title = ("Big Tujunga above the black Fig. 1 outlet (%.1f km^2): steady state, U = 0.5 mm/yr")
          :format(ls.data_cells * ls.dx * ls.dy / 1e6) })
local series = {}
local function add(fit, label, colour)
  if fit then
    series[#series + 1] = { x = fit.bins.A, y = fit.bins.S_geomean, label = label .. " (binned geometric mean)",
                            rgb = colour }
    local A, S = {}, {}
    for k = 0, 100 do
      A[k + 1] = fit.bins.A[1] * (fit.bins.A[#fit.bins.A] / fit.bins.A[1]) ^ (k / 100)
      S[k + 1] = fit.S_df / (1 + (A[k + 1] / fit.A_df) ^ fit.a2)
    end
    series[#series + 1] = { x = A, y = S, lines = true, rgb = colour,
                            label = ("%s, Eq. (2), log residuals: S_{df} = %.2f, R^2 = %.2f"):format(label, fit.S_df,
                                                                                   fit.r2_log) }
  end
end
add(fit_real, "DEM", "black")
add(fit_model, "model", "vermillion")
if #series > 0 then
  dfle.plot.xy{ path = out("bigtujunga_slope_area.png"), series = series,
    title = "Slope-area of the Big Tujunga network: SRTM DEM and steady-state model",
    xlabel = dfle.plot.label("A"), ylabel = dfle.plot.label("S"),
    xlog = true, ylog = true }
end
