-- process.lua - the process-based router from Lua (Fig. 6 defaults,
-- dx = 5 m): one routing of the default flow over the initial (Eq. 26)
-- profile, and a whole explicit steady-state run.  The issue-15 figures
-- (the Fig. 6 steady profile's flow, the direct steady state, growth
-- with the domain, each beside the full-domain path) come from the C
-- driver bench/process.c.

local reps = tonumber(arg and arg[1]) or 5
local function model(rt)
  return dfle.model{
    channel = dfle.channel{ dx = 5, A_max = 8e6 }, U = 5e-4,
    fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
    router = rt, law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 },
  }
end

-- A router of its own, not the model's, so that the model's cached flow
-- stays as it is (rt:route(m) with the model's own router marks it
-- stale; either way each call routes once: it reads the model's slopes
-- without evaluating the model).
local m = model(dfle.router.process{ M0 = 200, eta = 60, mu2 = 0.62, D = 5e-6 })
m:get("S")
local rt = dfle.router.process{ M0 = 200, eta = 60, mu2 = 0.62, D = 5e-6 }
local best, r = math.huge, nil
for _ = 1, reps do
  local t0 = os.clock()
  r = rt:route(m)
  best = math.min(best, os.clock() - t0)
end
local cells = m.n + rt.n_ghost
print(("process router, one routing from Lua: %.4f s CPU (best of %d), %d cells x %d steps, wet window %.0f cells on average, flow %s after %.0f s")
      :format(best, reps, cells, r.steps, r.cell_steps / r.steps, r.ended, r.duration))

local sm = model(dfle.router.process{ M0 = 200, eta = 60, mu2 = 0.62, D = 5e-6 })
local t0 = os.clock()
local run = sm:run_to_steady{ tol = 1e-3, max_time = 2e7, method = "explicit" }
print(("process router, explicit steady state: %.2f s CPU, %d routings, %d landscape steps, %.4g simulated years, converged = %s")
      :format(os.clock() - t0, run.routings, run.steps, run.time, tostring(run.converged)))
