-- analytical_check.lua - the numerical model against the analytical
-- solution of Sect. 2.4 (Eqs. 19-24).
--
-- Eq. (19) assumes no fluvial erosion and Theta = 1 (tau >> tau_y), so
-- the model is run with fluvial = false and tau_y = 0; its steady-state
-- slopes should then follow S = C A^N at every node.  The script prints
-- the largest relative difference and plots both on slope-area axes.
--
--   dfle examples/analytical_check.lua [--quick] [output-directory]

local opts = dfle.args{
  usage = "dfle examples/analytical_check.lua [options] [output-directory]",
  about = "The numerical model against the analytical solution of Sect. 2.4 (Eqs. 19-24).",
  flags = { quick = "a 10 m grid (for the test suite)" },
  output = true,
}
local quick, outdir = opts.quick, opts.output

local U = 5e-4
local router = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500, tau_y = 0 }
local law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 }
local model = dfle.model{
  channel = dfle.channel{ dx = quick and 10 or 5, A_max = 8e6 },
  U = U, fluvial = false, router = router, law = law,
}

local run = model:run_to_steady{ tol = 1e-4, max_time = 2e7 }
assert(run.converged, "no steady state: " .. run.reason)

local A, S = model:get("A"), model:get("S")
table.remove(A); table.remove(S)          -- the outlet is held at base level
local S19 = dfle.analytical_slope(router, law, { U = U, A = A })
local worst, at = 0, 1
for i = 1, #A do
  local d = math.abs(S[i] / S19[i] - 1)
  if d > worst then worst, at = d, i end
end
print(("Eq. (20): N = %.6f (check value: -0.024706)")
      :format(dfle.analytical_exponent(router, law, { U = U })))
print(("Eq. (19) at A = 1e4 m^2: S = %.5f (check value: 0.73834)")
      :format(dfle.analytical_slope(router, law, { U = U, A = 1e4 })))
print(("steady state (%s method); largest |S_model/S_Eq19 - 1| = %.2e at A = %.3g m^2")
      :format(run.method, worst, A[at]))

-- The model's nodes as markers at about 40 log-spaced areas (all of them
-- would merge into a thick line), Eq. (19) as a line through them.
local Am, Sm, next_A = {}, {}, A[1]
for i = 1, #A do
  if A[i] >= next_A then
    Am[#Am + 1], Sm[#Sm + 1] = A[i], S[i]
    next_A = A[i] * (A[#A] / A[1]) ^ (1 / 40)
  end
end
dfle.plot.xy{
  path = outdir .. "/analytical_check.png",
  title = "Debris flows only (τ_y = 0): model and Eq. (19)",
  xlabel = dfle.plot.label("A"), ylabel = dfle.plot.label("S"),
  xlog = true, ylog = true,
  series = {
    { x = A, y = S19, label = "Eq. (19)", lines = true, rgb = "vermillion" },
    { x = Am, y = Sm, label = "model, steady state", marker = "open circle", rgb = "black",
      marker_size = 5 },
  },
}
print("wrote " .. outdir .. "/analytical_check.png")
if worst > 5e-3 then
  io.stderr:write("analytical_check: model and Eq. (19) differ by more than 0.5 %\n")
  os.exit(1)
end
