-- invert.lua - the inversion's throughput: 32 walkers x 3000 steps of the
-- empirical model (Fig. 9 defaults, paper channel, dx = 5 m, the direct
-- steady-state solver), U, k_df and gamma free with the noise scale, on
-- 2 workers.  Prints forward runs per second, and the share of the time
-- spent outside the forward model (the sampler, priors, the parameter
-- table, the chain file, the barriers between half-steps): of the CPU
-- time (what the inversion itself costs) and of the workers' wall time
-- (which also counts waiting, and on a machine shared with other jobs
-- the time the threads were not running).
--
--   dfle bench/invert.lua [steps [walkers [workers]]]
--
-- The chain goes to $TMPDIR and is removed.  Workers replay this script
-- up to dfle.invert, so everything before it is deterministic.

local steps = tonumber(arg and arg[1]) or 3000
local walkers = tonumber(arg and arg[2]) or 32
local workers = tonumber(arg and arg[3]) or 2
local dir = os.getenv("TMPDIR") or "/tmp"

local ch = dfle.channel{ dx = 5, A_max = 8e6 }
local function build(p, channel)
  return dfle.model{
    channel = channel, U = p.U,
    fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
    router = dfle.router.empirical{ M0 = 3000, gamma = p.gamma, mu = 500, tau_y = 300 },
    law = dfle.law.power{ k_df = p.k_df, alpha = 6, beta = 1 },
  }
end

-- Data: the model at U = 5e-4 m/yr, k_df = 1e-4, gamma = 0.5, binned,
-- with a fixed 10 % pattern of noise (no random numbers needed).
local m = build({ U = 5e-4, k_df = 1e-4, gamma = 0.5 }, ch)
m:run_to_steady{}
local fit = dfle.fit_slope_area(m, { nbins = 30 })
local S = {}
for i, s in ipairs(fit.bins.S) do S[i] = s * math.exp(0.1 * math.sin(2.3 * i)) end

local out = dir .. "/dfle-bench-invert.csv"
local cpu0 = os.clock() -- CPU time of the process: all threads
local res = dfle.invert{
  data = { A = fit.bins.A, S = S }, channel = ch, build = build,
  params = { U = { 1e-4, 1e-3, log = true }, k_df = { 5e-5, 1e-3, log = true }, gamma = { 0, 1 } },
  walkers = walkers, steps = steps, seed = 1, workers = workers, lsq = false,
  out = out, resume = false,
}
local cpu = os.clock() - cpu0
os.remove(out)

-- The workers replay this script up to dfle.invert: their data set-up
-- (one steady state and a fit, milliseconds) is in cpu, and so is any
-- time the process spends on other threads.
local busy = res.elapsed * workers
print(("inversion (empirical, %d nodes, dx = 5 m): %d walkers x %d steps on %d workers")
      :format(ch.n, walkers, steps, workers))
print(("  %d forward runs in %.1f s: %.0f runs/s (target: 10^5 runs in < 60 s)")
      :format(res.evaluations, res.elapsed, res.evaluations / res.elapsed))
print(("  CPU: %.1f s in all, %.3f ms of forward model per run; %.1f %% outside the forward model" ..
       " (target: < 10 %%); %.1f s on %d idle cores")
      :format(cpu, 1e3 * res.forward_seconds / res.evaluations,
              100 * math.max(0, 1 - res.forward_seconds / cpu), cpu / workers, workers))
print(("  wall: %.1f %% of the workers' time outside the forward model (waiting included)")
      :format(100 * math.max(0, 1 - res.forward_seconds / busy)))
print(("  U = %.3g [%.3g, %.3g] m/yr (95 %%), tau = %.0f steps, acceptance %.2f")
      :format(res.summary.U.median, res.summary.U.lo95, res.summary.U.hi95, res.tau_max,
              res.acceptance))
