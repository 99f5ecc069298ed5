-- landscape_routers.lua - one synthetic landscape at steady state with
-- each of the paper's debris-flow routers: the empirical one (Sect. 2.3,
-- the Fig. 9 defaults) and the process-based one (Sect. 2.2, depth-
-- averaged two-phase flow from every channel head, the Fig. 6 defaults),
-- their slope-area curves and maps side by side: the 2D counterpart of
-- the paper's Figs. 6 and 9 (doc/landscape.md, "The process-based
-- router").
--
-- A 1.8 x 1.35 km block of 30 m cells (quick: 900 x 720 m), base level
-- on the south edge, uplift 0.5 mm/yr, channel heads at 1 ha, the same
-- seeded noise for both.  Writes landscape_routers_<router>.png (maps),
-- landscape_routers_<router>.tif (z, A, S, E_f, E_df, reach), landscape_routers_maps.png
-- (the two maps side by side) and landscape_routers_slope_area.png.
--
--   dfle examples/landscape_routers.lua [--quick] [output-directory]

local opts = dfle.args{
  usage = "dfle examples/landscape_routers.lua [options] [output-directory]",
  about = "One synthetic landscape at steady state with the empirical and the process router.",
  flags = { quick = "a 900 x 720 m block (for the test suite)" },
  output = true,
}
local quick, outdir = opts.quick, opts.output
local function out(name) return outdir .. "/" .. name end
local nx, ny = quick and 30 or 60, quick and 24 or 45
local routers = {
  { name = "empirical", router = dfle.router.empirical{} },
  { name = "process", router = dfle.router.process{} },
}
local series, maps, titles = {}, {}, {}
for _, r in ipairs(routers) do
  local ls = dfle.landscape{
    nx = nx, ny = ny, dx = 30, A0 = 1e4, router = r.router, law = dfle.law.power{},
    edges = { south = "base_level", north = "closed", east = "closed", west = "closed" },
    U = 5e-4, noise = { amplitude = 1, seed = 7 },
  }
  local t0 = os.clock()
  local run = ls:run_to_steady{}
  print(("%-9s: %s in %.2f s (%s, %d %s); %d heads; %.2f%% of the %d channel cells above "
         .. "tol U (max |dz/dt|/U %.2g), volume balance %.2g")
        :format(r.name, run.converged and "steady" or "NOT steady", os.clock() - t0, run.method,
                run.steps, run.method == "direct" and "rounds" or "steps", run.heads,
                100 * run.channel_frac_above, run.channel_cells, run.channel_max_ratio,
                run.volume_balance))
  print("  " .. run.note)
  local count = r.router:routings()
  if count then
    print(("  %d flows routed in all (%d heads): the re-routing rule kept the rest"):format(
      count.total, count.heads))
  end
  local fit = dfle.fit_slope_area(ls)
  if fit then
    print(("  slope-area: S_df = %.3f, A_df = %.3g m^2, a2 = %.2f, R^2 = %.3f"):format(
      fit.S_df, fit.A_df, fit.a2, fit.r2))
    series[#series + 1] = { x = fit.bins.A, y = fit.bins.S, label = r.name .. " router" }
  end
  ls:write_geotiff(out("landscape_routers_" .. r.name .. ".tif"), { "z", "A", "S", "E_f", "E_df", "reach" })
  local map = out("landscape_routers_" .. r.name .. ".png")
  ls:plot(map, { title = ("Steady state, %s router"):format(r.name),
                  channels = false }) -- the reach alone: the two maps then lay out alike
  maps[#maps + 1] = map
  titles[#titles + 1] = r.name .. " router"
end
dfle.plot.sheet{ path = out("landscape_routers_maps.png"), images = maps, titles = titles, columns = 2,
                 title = "The same landscape at steady state with each debris-flow router" }
if #series > 0 then
  dfle.plot.xy{ path = out("landscape_routers_slope_area.png"), series = series, xlog = true, ylog = true,
                title = "Steady-state slope-area (binned means) by debris-flow router",
                xlabel = dfle.plot.label("A"), ylabel = dfle.plot.label("S") }
end
