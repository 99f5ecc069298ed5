-- landscape_synthetic.lua - a synthetic landscape carved by debris flows
-- and rivers from a random start (doc/landscape.md).
--
-- A 6 x 4.5 km block of 30 m cells (quick: 3 x 2.25 km), placed in UTM
-- zone 11N (crs =, so QGIS puts its files where the San Gabriels are),
-- base level on the south edge, the other edges closed, uplift 0.5 mm/yr
-- faster in the north (a function of y), channel heads at 1 ha.  It runs a transient
-- from 1 m of seeded noise (recorded to NetCDF), then the direct steady
-- state, under both rules for joined debris flows ("any", the 1D rule,
-- and "count", frequencies adding up), and compares their slope-area
-- fits.  Writes synthetic_<rule>.png (map), synthetic_<rule>.tif
-- (z, A, S, E_f, E_df, reach), synthetic_series.nc, synthetic_slope_area.png.
--
--   dfle examples/landscape_synthetic.lua [--quick] [output-directory]

local opts = dfle.args{
  usage = "dfle examples/landscape_synthetic.lua [options] [output-directory]",
  about = "A synthetic landscape carved by debris flows and rivers from a random start.",
  flags = { quick = "a 3 x 2.25 km block (for the test suite)" },
  output = true,
}
local quick, outdir = opts.quick, opts.output
local function out(name) return outdir .. "/" .. name end
local nx, ny = quick and 100 or 200, quick and 75 or 150
local x0, y0 = 390000, 3800000 -- north-west corner, UTM 11N [m]
local series = {}
for _, rule in ipairs{ "any", "count" } do
  local ls = dfle.landscape{
    nx = nx, ny = ny, dx = 30, A0 = 1e4, S_c = 0.8, combine = rule,
    x0 = x0, y0 = y0, crs = "EPSG:32611",
    edges = { south = "base_level", north = "closed", east = "closed", west = "closed" },
    U = function(x, y) return 5e-4 * (1 + (y - (y0 - ny * 30)) / (ny * 30)) end,
    noise = { amplitude = 1, seed = 42 },
  }
  if rule == "any" then
    local tr = ls:run{ years = quick and 2e4 or 1e5, dt = 5e3, record = { 0, quick and 2e4 or 1e5 },
                       netcdf = out("synthetic_series.nc"), fields = { "z", "E_df", "channel" },
                       float32 = true }
    print(("transient (%s): %s; mass balance dV - (V_U - V_f - V_df - V_h) = %.3g m^3"):format(
      rule, tr.note, tr.dV - (tr.V_uplift - tr.V_fluvial - tr.V_df - tr.V_hillslope)))
  end
  local t0 = os.clock()
  local run = ls:run_to_steady{ max_steps = quick and 40 or 100000, dt = 5e3 }
  print(("combine = %-5s: %s in %.2f s (%s, %d rounds); %d heads; %.2f%% of the %d channel "
         .. "cells above tol U (max |dz/dt|/U %.2g), volume balance %.2g")
        :format(rule, run.converged and "steady" or "NOT steady", os.clock() - t0, run.method,
                run.steps, run.heads, 100 * run.channel_frac_above, run.channel_cells,
                run.channel_max_ratio, run.volume_balance))
  print("  " .. run.note)
  local fit = dfle.fit_slope_area(ls)
  if fit then
    print(("  slope-area: S_df = %.3f, A_df = %.3g m^2, a2 = %.2f, R^2 = %.3f"):format(
      fit.S_df, fit.A_df, fit.a2, fit.r2))
    series[#series + 1] = { x = fit.bins.A, y = fit.bins.S, label = "combine = " .. rule }
  end
  ls:write_geotiff(out("synthetic_" .. rule .. ".tif"), { "z", "A", "S", "E_f", "E_df", "reach" })
  ls:plot(out("synthetic_" .. rule .. ".png"),
          { title = ("Synthetic steady state, joined debris flows: %s"):format(rule) })
end
if #series > 0 then
  dfle.plot.xy{ path = out("synthetic_slope_area.png"), series = series, xlog = true, ylog = true,
                title = "Steady-state slope-area (binned means) by combine rule",
                xlabel = dfle.plot.label("A"), ylabel = dfle.plot.label("S") }
end
