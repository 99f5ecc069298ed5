-- uplift_step.lua - a transient experiment: the steady-state channel of
-- the Fig. 9 defaults responds to a doubling of the uplift rate.
--
-- The steady state is found directly; then U doubles and the profile is
-- recorded at chosen times with the implicit (adaptive, error-controlled)
-- stepper, until the new steady state.  Plots the profiles
-- (uplift_step_profiles.png) and the binned slope-area data
-- (uplift_step_slope_area.png) at those times and at the new steady state.
--
--   dfle examples/uplift_step.lua [--quick] [output-directory]

local opts = dfle.args{
  usage = "dfle examples/uplift_step.lua [options] [output-directory]",
  about = "A transient: the steady-state channel of the Fig. 9 defaults responds to a doubling of the uplift rate.",
  flags = { quick = "a 20 m grid (for the test suite)" },
  output = true,
}
local quick, outdir = opts.quick, opts.output

local m = dfle.model{ channel = dfle.channel{ dx = quick and 20 or 5 }, U = 5e-4 }
local r0 = m:run_to_steady{}
local f0 = assert(dfle.fit_slope_area(m))
print(("steady state at U = 0.5 mm/yr (%s method): S_df = %.3f, A_df = %.3g m^2")
      :format(r0.method, f0.S_df, f0.A_df))

m:set_U(1e-3)
local times = { 0, 1e4, 3e4, 1e5, 3e5 }
local r = m:run{ years = times[#times], method = "implicit", record = times }
print(("after the step: %d implicit steps over %.3g yr"):format(r.steps, r.time))

local x, A = m:get("x"), m:get("A")
local tlabel, kyr = dfle.plot.label("t")
local profiles, slope_area = {}, {}
for j, rec in ipairs(r.records) do
  local label = ("{/:Italic t} = %g kyr"):format(rec.t * kyr)
  profiles[j] = { x = x, y = rec.z, label = label, lines = true }
  local z, S, Au = rec.z, {}, {}
  for i = 1, #z - 1 do S[i], Au[i] = (z[i] - z[i + 1]) / (x[i + 1] - x[i]), A[i] end
  local f = dfle.fit_slope_area{ A = Au, S = S }
  if f then
    print(("t = %6g yr: head at %.1f m, S_df = %.3f, A_df = %.3g m^2"):format(rec.t, z[1], f.S_df, f.A_df))
    -- the binned means, as dfle.fit_slope_area saw them
    slope_area[#slope_area + 1] = { x = f.bins.A, y = f.bins.S, label = label, lines = true }
  end
end
local r1 = m:run_to_steady{}
local f1 = assert(dfle.fit_slope_area(m))
print(("new steady state at U = 1 mm/yr: S_df = %.3f, A_df = %.3g m^2"):format(f1.S_df, f1.A_df))
slope_area[#slope_area + 1] = { x = f1.bins.A, y = f1.bins.S, label = "new steady state",
                                lines = true, rgb = "black", dash = true }

dfle.plot.xy{ path = outdir .. "/uplift_step_profiles.png", series = profiles,
              title = "Response to doubling the uplift rate (0.5 to 1 mm/yr)",
              xlabel = dfle.plot.label("x"), ylabel = dfle.plot.label("z") }
dfle.plot.xy{ path = outdir .. "/uplift_step_slope_area.png", series = slope_area,
              xlog = true, ylog = true,
              title = "Slope-area during the response (binned means)",
              xlabel = dfle.plot.label("A"), ylabel = dfle.plot.label("S") }
print("wrote " .. outdir .. "/uplift_step_profiles.png, uplift_step_slope_area.png")
