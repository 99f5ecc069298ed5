-- routers.lua - the two debris-flow routers side by side.
--
-- 1. Routes one debris flow with the process-based router (Sect. 2.2:
--    depth-averaged two-phase flow, HLLC finite volumes) over the initial
--    profile and plots it at several times, like the paper's Fig. E1.
-- 2. Runs the same channel to steady state with each router (Fig. 6
--    defaults for the process-based one, gamma = 0 for the empirical one
--    so both route a flow of fixed volume) and plots both steady-state
--    slope-area curves and long profiles on one figure each.
--
--   dfle examples/routers.lua [--quick] [output-directory]

local opts = dfle.args{
  usage = "dfle examples/routers.lua [options] [output-directory]",
  about = "The two debris-flow routers side by side.",
  flags = { quick = "a 20 m grid (for the test suite)" },
  output = true,
}
local quick, outdir = opts.quick, opts.output

local channel = dfle.channel{ dx = quick and 20 or 5, A_max = 8e6 }
local fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 }
local law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 }
local routers = {
  process = dfle.router.process{ M0 = 200, eta = 60, mu2 = 0.62, D = 5e-6 },
  empirical = dfle.router.empirical{ M0 = 200, gamma = 0, mu = 500, tau_y = 300 },
}

-- 1. One flow over the initial (Eq. 26) profile.
local m = dfle.model{ channel = channel, U = 5e-4, fluvial = fluvial,
                      router = routers.process, law = law }
local flow = routers.process:route(m, { snapshots = { 2, 10, 30, 90 } })
print(("one flow: %s after %.1f s (%d steps); reached %d of %d nodes; volume in %.1f, out %.3g, left %.1f m^3")
      :format(flow.ended, flow.duration, flow.steps, flow.runout_end, m.n,
              flow.volume_in, flow.volume_out, flow.volume_left))
dfle.plot.flow(m, flow, outdir .. "/routed_flow.png",
               { title = "A debris flow on the initial profile" })

-- 2. Steady states with both routers.
local sa, prof = {}, {}
for _, name in ipairs{ "empirical", "process" } do
  local model = dfle.model{ channel = channel, U = 5e-4, fluvial = fluvial,
                            router = routers[name], law = law }
  local t0 = os.clock()
  local run = model:run_to_steady{ tol = 1e-3, max_time = 2e7 }
  local fit = assert(dfle.fit_slope_area(model))
  print(("%-9s: %s (%s method), %d steps, %d routings, %.2f s; S_df = %.3f, A_df = %.3g m^2, a2 = %.2f, R^2 = %.3f, S_max - S_ch = %.3f")
        :format(name, run.converged and "steady" or run.reason, run.method, run.steps,
                run.routings, os.clock() - t0, fit.S_df, fit.A_df, fit.a2, fit.r2,
                fit.S_max_minus_S_ch))
  model:write_csv(("%s/steady_%s.csv"):format(outdir, name))
  local A, S = model:get("A"), model:get("S")
  table.remove(A); table.remove(S)
  local look = name == "empirical" and { rgb = "blue", marker = "circle" }
                                     or { rgb = "vermillion", marker = "open square" }
  sa[#sa + 1] = { x = fit.bins.A, y = fit.bins.S, label = name .. " router (bin means)",
                  rgb = look.rgb, marker = look.marker }
  prof[#prof + 1] = { x = model:get("x"), y = model:get("z"), label = name .. " router", lines = true,
                      rgb = look.rgb, dash = name == "process" }
end
dfle.plot.xy{ path = outdir .. "/routers_slope_area.png", series = sa, xlog = true, ylog = true,
              title = "Steady state with each router", xlabel = dfle.plot.label("A"),
              ylabel = dfle.plot.label("S") }
dfle.plot.xy{ path = outdir .. "/routers_profiles.png", series = prof,
              title = "Steady-state long profiles", xlabel = dfle.plot.label("x"),
              ylabel = dfle.plot.label("z") }
print("wrote routed_flow.png, routers_slope_area.png, routers_profiles.png and steady_*.csv in " .. outdir)
