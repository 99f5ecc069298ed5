-- steady_state.lua - wall time of the paper's explicit steady-state run (Fig. 9
-- defaults: empirical router, power law alpha = 6, beta = 1, Table G1
-- fluvial law, dx = 5 m, A_max = 8 km^2), best of several repetitions.

local reps = tonumber(arg and arg[1]) or 5

local function build()
  return dfle.model{
    channel = dfle.channel{ dx = 5, A_max = 8e6 },
    U = 5e-4,
    fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
    router = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500, tau_y = 300 },
    law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 },
  }
end

local best, result, n = math.huge, nil, nil
for _ = 1, reps do
  local m = build()
  local t0 = os.clock()
  result = m:run_to_steady{ tol = 1e-3, max_time = 2e7, method = "explicit" }
  local dt = os.clock() - t0
  if dt < best then best = dt end
  n = m.n
end

print(("steady state (explicit, Fig. 9 defaults): %.3f s CPU (best of %d)"):format(best, reps))
print(("  %d nodes, %d steps, %.4g simulated years, %d routings, converged = %s")
      :format(n, result.steps, result.time, result.routings, tostring(result.converged)))
print(("  %.3g node-steps per second, %.3g simulated years per second")
      :format(n * result.steps / best, result.time / best))
