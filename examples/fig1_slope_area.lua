-- fig1_slope_area.lua - the paper's Fig. 1 from a real DEM.
--
-- McGuire et al. (2023), Fig. 1: slope and drainage area extracted from
-- the channel networks of San Gabriel Mountains catchments, put into 100
-- logarithmically spaced area bins (mean slope per bin), fitted with
-- Eq. (2), S = S_df / (1 + (A/A_df)^a2), with A_df marked.  This script
-- does that on the Big Tujunga SRTM DEM (30 m, UTM 11N) for the Fig. 1
-- outlets it contains:
--
--   black  396887 E 3799338 N   (paper: R^2 = 0.95)
--   blue   384971 E 3799277 N   (paper: R^2 = 0.97)
--   orange 417896 E 3792642 N   (paper: R^2 = 0.97) - east of this DEM
--                                (E 376314..412224 m): reported, skipped
--
-- For each catchment: the network of every cell above the outlet (with
-- 30 m cells there is nothing finer than one cell to call a channel
-- head), slope over 90 m of flow path (3 cells) centred on each cell;
-- the main-stem profile too, for comparison.  Writes
--   fig1_fits.csv            one row per catchment and data set
--   fig1_<name>.csv          the main-stem profile (x, z, A, S, ...)
--   fig1_<name>.png          binned slope-area, fit, A_df (dfle.plot)
--   fig1_slope_area.png      all catchments on one plot, like Fig. 1
--   fig1_<name>_chi.csv      chi and k_sn of the channels (A >= 0.1 km^2)
--   fig1_<name>_chi.png      the binned slope-area and Eq. (2) beside chi-z
--   fig1_<name>_ksn.png      a map of k_sn on the fluvial reach (A >= 1 km^2)
--
-- chi and k_sn (Perron and Royden 2013) with theta_ref = 0.45 and A0 =
-- 1 m^2, on the channels of 0.1 km^2 and more; the chi-z line and both
-- concavity estimates (chi-z collinearity, slope-area regression) on the
-- fluvial reach only, A >= 1 km^2, well above A_df (about 0.2 km^2): below
-- it debris flows set the slope (Eq. 2), and no power law of area holds.
-- k_sn is each cell's chi-z slope over 300 m of flow path (10 cells), so
-- that the map shows reaches rather than the 1 m steps of SRTM elevations.
--
--   dfle examples/fig1_slope_area.lua [--quick] [output-directory]
--
-- --quick is the same run (a few seconds either way; every example takes
-- it, for the test suite and the figure gallery).  The DEM
-- is read from --data DIR or $DFLE_DATA_DIR (the directory holding
-- dem/); the script says so and stops when it is missing.

local opts = dfle.args{
  usage = "dfle examples/fig1_slope_area.lua [options] [output-directory]",
  about = "The paper's Fig. 1 from a real DEM.",
  flags = { quick = "the same run: it takes seconds either way (for the test suite)" },
  options = { data = { "DIR", "the data directory, holding dem/ (default: $DFLE_DATA_DIR)",
                       env = "DFLE_DATA_DIR",
                       needs = { "dem/srtm_bigtujunga30m_utm11.tif", "the Big Tujunga DEM" } } },
  output = true,
}
local outdir = opts.output

local dem_file = opts.data_file
local path = dem_file

-- Each catchment is drawn in the colour the paper names it by (the
-- colour-blind-safe palette's black, blue and orange), with its own marker.
local catchments = {
  { name = "black",  E = 396887, N = 3799338, paper_r2 = 0.95, marker = "circle" },
  { name = "blue",   E = 384971, N = 3799277, paper_r2 = 0.97, marker = "open square" },
  { name = "orange", E = 417896, N = 3792642, paper_r2 = 0.97, marker = "triangle" },
}

local dem = dfle.dem.read(path)
print(tostring(dem))
local t0 = os.clock()
local filled = dem:fill()
dem:flow()
print(("filled %d cells (largest rise %.0f m), routed %d cells in %.2f s; %d on flats")
      :format(filled.raised, filled.max_raise, dem.n, os.clock() - t0, dem.flats))

local ext = dem.extent
local fits = {}      -- rows of fig1_fits.csv
local series = {}    -- the combined plot

for _, c in ipairs(catchments) do
  if c.E < ext.E_min or c.E >= ext.E_max or c.N < ext.N_min or c.N >= ext.N_max then
    print(("%s: outlet (%d E, %d N) lies outside this DEM (E %.0f..%.0f, N %.0f..%.0f); skipped")
          :format(c.name, c.E, c.N, ext.E_min, ext.E_max, ext.N_min, ext.N_max))
  else
    local outlet = { c.E, c.N }
    local net = dem:network{ A_min = dem.dx * dem.dy, outlet = outlet }
    local main = dem:profile{ outlet = outlet }
    main:write_csv(("%s/fig1_%s.csv"):format(outdir, c.name))
    print(("%s: outlet snapped %.0f m to (%.0f E, %.0f N), catchment %.2f km^2, %d cells; " ..
           "main stem %.2f km")
          :format(c.name, main.snap_distance, main.outlet.E, main.outlet.N, net.A_max / 1e6,
                  net.n, main.length / 1e3))
    for _, set in ipairs{ { "network", net }, { "main stem", main } } do
      local fit, why = dfle.fit_slope_area(set[2])
      if fit then
        print(("  %-9s S_df = %.3f  A_df = %.3g m^2  a2 = %.2f  R^2 = %.3f  S_max - S_ch = %.3f" ..
               "  (%d bins, %d empty)")
              :format(set[1], fit.S_df, fit.A_df, fit.a2, fit.r2, fit.S_max_minus_S_ch,
                      fit.n_points, fit.bins.n_empty))
        fits[#fits + 1] = { c, set[1], set[2], fit }
      else
        print(("  %-9s no fit: %s"):format(set[1], why))
      end
    end
    print(("  paper's R^2 for this catchment: %.2f"):format(c.paper_r2))

    -- chi and k_sn of the channels; concavity of the fluvial reach
    local channels = dem:network{ A_min = 1e5, outlet = outlet }
    local A_fluvial = 1e6
    local chi = dfle.chi(channels, { theta_ref = 0.45, A_min = A_fluvial, window = 300 })
    chi:write_csv(("%s/fig1_%s_chi.csv"):format(outdir, c.name))
    print(("  chi (theta_ref = 0.45, A >= %.0f km^2): k_sn = %.1f m^0.9, R^2 = %.3f on %d cells")
          :format(A_fluvial / 1e6, chi.k_sn, chi.r2, chi.n_fit))
    for _, method in ipairs{ "chi", "slope_area" } do
      local k, why = dfle.concavity(method == "chi" and channels or net,
                                    { method = method, A_min = A_fluvial })
      if k then
        print(("  concavity by %-10s theta = %.2f (k_s = %.3g m^%.2f, R^2 = %.3f, %d %s)%s")
              :format(method, k.theta, k.k_s, 2 * k.theta, k.r2, k.n,
                      method == "chi" and "cells" or "bins", k.at_bound and " AT THE BOUND" or ""))
      else
        print("  concavity by " .. method .. ": " .. why)
      end
    end
    local fit_net = fits[#fits - 1] and fits[#fits - 1][2] == "network" and fits[#fits - 1][4]
    dfle.plot.slope_area_chi(net, chi, ("%s/fig1_%s_chi.png"):format(outdir, c.name), fit_net,
      { title = ("Big Tujunga, %s outlet: slope-area of every cell, chi of the channels")
                :format(c.name) })
    dfle.plot.ksn_map(chi, ("%s/fig1_%s_ksn.png"):format(outdir, c.name), { dem = dem,
      title = ("Big Tujunga, %s outlet: k_{sn} of the channels of 1 km^2 and more")
              :format(c.name) })

    local fit = fits[#fits - 1] and fits[#fits - 1][2] == "network" and fits[#fits - 1][4]
    if fit then
      dfle.plot.slope_area(net, ("%s/fig1_%s.png"):format(outdir, c.name), fit,
                           { title = ("Big Tujunga, %s outlet: channel network"):format(c.name) })
      -- Fig. 1 style: binned means, the fitted curve, A_df marked.
      local Af, Sf = {}, {}
      local lo, hi = fit.bins.A[1], fit.bins.A[#fit.bins.A]
      for i = 0, 100 do
        Af[i + 1] = lo * (hi / lo) ^ (i / 100)
        Sf[i + 1] = fit.S_df / (1 + (Af[i + 1] / fit.A_df) ^ fit.a2)
      end
      series[#series + 1] = { x = fit.bins.A, y = fit.bins.S, label = c.name .. " (binned)",
                              rgb = c.name, marker = c.marker }
      series[#series + 1] = { x = Af, y = Sf, lines = true, rgb = c.name,
                              label = ("%s: Eq. (2), {/:Italic R}^2 = %.2f"):format(c.name, fit.r2) }
      -- A_df as a short vertical tick through the curve (where S = S_df / 2).
      series[#series + 1] = { x = { fit.A_df, fit.A_df }, y = { fit.S_df / 3, fit.S_df * 3 / 4 },
                              lines = true, rgb = c.name, width = 2.5,
                              label = ("%s: {/:Italic A}_{df} = %s m^2"):format(c.name,
                                                                               dfle.plot.number(fit.A_df)) }
    end
  end
end

-- The fits as CSV.
local csv = outdir .. "/fig1_fits.csv"
local rows = {}
for _, r in ipairs(fits) do
  local c, what, p, fit = r[1], r[2], r[3], r[4]
  rows[#rows + 1] = { catchment = c.name, data = what, outlet_E = c.E, outlet_N = c.N,
                      snapped_E = p.outlet.E, snapped_N = p.outlet.N, A_outlet = p.A_max,
                      cells = p.n, slope_interval = p.ds, S_df = fit.S_df, A_df = fit.A_df,
                      a2 = fit.a2, r2 = fit.r2, S_max_minus_S_ch = fit.S_max_minus_S_ch,
                      bins = fit.n_points, empty_bins = fit.bins.n_empty }
end
dfle.write_csv(csv, {
  about = "Eq. (2) fitted to the channel network and to the main stem of each catchment",
  columns = { "catchment", "data", "outlet_E", "outlet_N", "snapped_E", "snapped_N", "A_outlet",
              "cells", "slope_interval", "S_df", "A_df", "a2", "r2", "S_max_minus_S_ch", "bins",
              "empty_bins" },
  units = { outlet_E = "m", outlet_N = "m", snapped_E = "m", snapped_N = "m", A_outlet = "m^2",
            slope_interval = "m", S_df = "-", A_df = "m^2", a2 = "-", r2 = "-",
            S_max_minus_S_ch = "-" },
  rows = rows,
  params = { dem = { file = dem_file, dx = dem.dx, dy = dem.dy, crs = dem.crs } },
})

local png = outdir .. "/fig1_slope_area.png"
if #series > 0 then
  dfle.plot.xy{ path = png, series = series, xlog = true, ylog = true,
                title = "Big Tujunga (SRTM 30 m): binned slope-area, Eq. (2) fits, A_{df}",
                xlabel = dfle.plot.label("A"), ylabel = dfle.plot.label("S") }
end
print("wrote " .. csv .. ", " .. png .. ", fig1_<name>.png, fig1_<name>.csv, " ..
      "fig1_<name>_chi.csv, fig1_<name>_chi.png, fig1_<name>_ksn.png")
