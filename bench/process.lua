-- process.lua - the process-based router (Fig. 6 defaults, dx = 5 m):
-- one routing of the default flow over the default (Eq. 26) profile,
-- and a whole steady-state run.

local reps = tonumber(arg and arg[1]) or 5
local function model(rt)
  return dfle.model{
    channel = dfle.channel{ dx = 5, A_max = 8e6 }, U = 5e-4,
    fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
    router = rt, law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 },
  }
end

local rt = dfle.router.process{ M0 = 200, eta = 60, mu2 = 0.62, D = 5e-6 }
local m = model(rt)
local best, r = math.huge, nil
for _ = 1, reps do
  local t0 = os.clock()
  r = rt:route(m)
  best = math.min(best, os.clock() - t0)
end
local cells = m.n + rt.n_ghost
print(("process router, one routing: %.4f s CPU (best of %d), %d cells x %d steps, %.3g cell-steps per second, flow %s after %.0f s")
      :format(best, reps, cells, r.steps, cells * r.steps / best, r.ended, r.duration))

local sm = model(dfle.router.process{ M0 = 200, eta = 60, mu2 = 0.62, D = 5e-6 })
local t0 = os.clock()
local run = sm:run_to_steady{ tol = 1e-3, max_time = 2e7, method = "explicit" }
print(("process router, explicit steady state: %.2f s CPU, %d routings, %d landscape steps, %.4g simulated years, converged = %s")
      :format(os.clock() - t0, run.routings, run.steps, run.time, tostring(run.converged)))
