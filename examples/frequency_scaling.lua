-- frequency_scaling.lua - the paper's Appendix D (Fig. D1): steady-state
-- profiles with the process-based router when debris-flow frequency
-- grows with drainage area, k_df scaled by 1000 (1e-6 A)^gamma / M0
-- (`frequency_scaling = true`), for a sweep of gamma; Table G4's central
-- values otherwise (alpha = 6, beta = 1, M0 = 200 m^3).
--
--   dfle examples/frequency_scaling.lua [--quick] [output-directory]
--
-- Writes frequency_scaling.csv (gamma, S_df, A_df, R^2, S_max - S_ch),
-- frequency_scaling_profiles.png (elevation against distance, the
-- first 400 m, where the profiles part) and
-- frequency_scaling_slope_area.png (slope against area, log-log).
-- --quick: three values of gamma on a coarse channel (dx = 20 m).

local opts = dfle.args{
  usage = "dfle examples/frequency_scaling.lua [options] [output-directory]",
  about = "The paper's Appendix D (Fig. D1): steady states when debris-flow frequency grows with drainage area.",
  flags = { quick = "three values of gamma on a 20 m grid (for the test suite)" },
  output = true,
}
local quick, outdir = opts.quick, opts.output

local gammas = quick and { 0, 0.5, 1 } or { 0, 0.25, 0.5, 0.75, 1 }
local channel = dfle.channel{ dx = quick and 20 or 5 }
local profiles, slopes = {}, {}
local DASHES = { "solid", "dash", "dot", "dashdot", "dashdotdot" }
local rows = {} -- of frequency_scaling.csv
print(("%6s %10s %8s %10s %7s %9s"):format("gamma", "converged", "S_df", "A_df (m2)", "R^2", "Smax-Sch"))
for _, g in ipairs(gammas) do
  local m = dfle.model{
    channel = channel, U = 5e-4,
    fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
    router = dfle.router.process{ M0 = 200, frequency_scaling = true, gamma = g },
    law = dfle.law.power{ k_df = 7.5e-5, alpha = 6, beta = 1 },
  }
  local run = m:run_to_steady{}
  local fit = dfle.fit_slope_area(m)
  local nan = 0 / 0
  local f = fit or { S_df = nan, A_df = nan, r2 = nan, S_max_minus_S_ch = nan }
  print(("%6g %10s %8.3f %10.3g %7.4f %9.4f"):format(g, tostring(run.converged), f.S_df, f.A_df,
        f.r2, f.S_max_minus_S_ch))
  rows[#rows + 1] = { gamma = g, converged = run.converged, S_df = f.S_df, A_df = f.A_df,
                      r2 = f.r2, S_max_minus_S_ch = f.S_max_minus_S_ch }
  -- Above about 10^5 m^2 rivers set the slope and the curves coincide:
  -- a dash pattern per gamma keeps each visible there.
  local label, dash = ("γ = %g"):format(g), DASHES[#profiles % #DASHES + 1]
  profiles[#profiles + 1] = { x = m:get("x"), y = m:get("z"), label = label, lines = true, dash = dash }
  slopes[#slopes + 1] = { x = m:get("A"), y = m:get("S"), label = label, lines = true, dash = dash }
end
dfle.write_csv(outdir .. "/frequency_scaling.csv", {
  about = "steady states with the debris-flow frequency scaled with area (Appendix D): process "
          .. "router, M0 = 200 m^3, k_df = 7.5e-5, alpha = 6, beta = 1, U = 5e-4 m/yr",
  columns = { "gamma", "converged", "S_df", "A_df", "r2", "S_max_minus_S_ch" },
  units = { gamma = "-", S_df = "-", A_df = "m^2", r2 = "-", S_max_minus_S_ch = "-" },
  rows = rows, params = { channel = channel:params() },
})
-- The profiles part only near the head, where debris flows set the
-- slope: the figure shows that reach.
dfle.plot.xy{
  path = outdir .. "/frequency_scaling_profiles.png", series = profiles,
  title = "Steady-state profiles near the head, debris-flow frequency scaled with area (Appendix D)",
  xlabel = dfle.plot.label("x"), ylabel = dfle.plot.label("z"), xrange = { 0, 400 },
}
dfle.plot.xy{
  path = outdir .. "/frequency_scaling_slope_area.png", series = slopes, xlog = true, ylog = true,
  title = "Slope-area, debris-flow frequency scaled with area (Appendix D)",
  xlabel = dfle.plot.label("A"), ylabel = dfle.plot.label("S"),
}
