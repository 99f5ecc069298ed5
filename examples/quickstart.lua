-- quickstart.lua - the default dfle experiment.
--
-- A 1D channel from a 1000 m^2 channel head to an 8 km^2 outlet, shaped
-- by rivers (stochastic-threshold stream power, Table G1) and debris
-- flows (empirical router, power law alpha = 6, beta = 1): the Fig. 9
-- defaults of McGuire et al. (2023).  Runs to steady state, writes the
-- profile as CSV, plots the slope-area data with the fitted Eq. (2) and
-- the long profile, and prints the fit.
--
--   dfle examples/quickstart.lua [--quick] [output-directory]
--
-- --quick uses a 10 m grid (for the test suite); the default is 5 m.

local opts = dfle.args{
  usage = "dfle examples/quickstart.lua [options] [output-directory]",
  about = "The default dfle experiment.",
  flags = { quick = "a 10 m grid (for the test suite); the default is 5 m" },
  output = true,
}
local quick, outdir = opts.quick, opts.output

local channel = dfle.channel{ dx = quick and 10 or 5, A_max = 8e6 }
local model = dfle.model{
  channel = channel,
  U       = 5e-4,                                       -- m/yr (0.5 mm/yr)
  fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
  router  = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500, tau_y = 300 },
  law     = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 },
}

print(("channel: %d nodes, dx = %g m, outlet at x = %g m, A = %.3g m^2")
      :format(channel.n, channel.dx, channel.length, channel.A_max))
print("fluvial law: " .. tostring(model.fluvial))

model:init_fluvial_steady()                          -- Eq. (26)
local run = model:run_to_steady{ tol = 1e-3, max_time = 2e7 }
print(("run: %s by the %s method (max|dz/dt|/U = %.2e)")
      :format(run.converged and "steady state" or ("stopped (" .. run.reason .. ")"),
              run.method, run.rate_ratio))
if not run.converged then
  io.stderr:write("quickstart: no steady state reached\n")
  os.exit(1)
end

local csv = outdir .. "/profile.csv"
model:write_csv(csv)

local fit, why = dfle.fit_slope_area(model)        -- Eq. (2), 100 log bins
if not fit then
  io.stderr:write("quickstart: " .. why .. "\n")
  os.exit(1)
end
print(("fit of Eq. (2): S_df = %.4f   A_df = %.4g m^2   a2 = %.3f   R^2 = %.4f")
      :format(fit.S_df, fit.A_df, fit.a2, fit.r2))
print(("S_max - S_ch = %.4f   (%d bins, %d empty)")
      :format(fit.S_max_minus_S_ch, fit.n_points, fit.bins.n_empty))

dfle.plot.slope_area(model, outdir .. "/slope_area.png", fit,
                     { title = "Steady state, Fig. 9 defaults" })
dfle.plot.profile(model, outdir .. "/profile.png", { title = "Steady-state long profile" })
print("wrote " .. csv .. ", " .. outdir .. "/slope_area.png, " .. outdir .. "/profile.png")
