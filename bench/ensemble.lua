-- ensemble.lua - runs per second of the Table G5 ensemble (empirical
-- router, sensitivity analysis; paper channel, default direct method)
-- on all cores and on one.  arg[1]: number of samples (default 400).
-- Each measurement starts a fresh file (resume = false) in $TMPDIR.
-- Workers replay this script up to each dfle.ensemble call, so
-- everything before it is deterministic (no os.tmpname, no clock).

local n = tonumber(arg and arg[1]) or 400
local dir = os.getenv("TMPDIR") or "/tmp"

local function g5(workers, out)
  return dfle.ensemble{
    params = {                                   -- Table G5
      M0 = { 1000, 5000 }, gamma = { 0, 1 }, mu = { 100, 1000 }, tau_y = { 100, 600 },
      k_df = { 5e-5, 1e-3 }, k_e = { 2e-14, 8e-14 }, U = { 1e-4, 1e-3 },
    },
    n = n, seed = 1, out = out, workers = workers, resume = false,
    build = function(p)
      return dfle.model{
        U = p.U,
        fluvial = dfle.fluvial.stochastic_threshold{ k_e = p.k_e },
        router = dfle.router.empirical{ M0 = p.M0, gamma = p.gamma, mu = p.mu, tau_y = p.tau_y },
        law = dfle.law.power{ k_df = p.k_df, alpha = 6, beta = 1 },
      }
    end,
    outputs = { "S_df", "A_df", "r2", "S_max_minus_S_ch" },
  }
end

local function wall()
  local h = io.popen("date +%s.%N")
  local t = tonumber(h:read("l"))
  h:close()
  return t
end

local h = io.popen("nproc")
local cores = tonumber(h:read("l")) or 1
h:close()
local rates = {}
for _, w in ipairs{ cores, 1 } do
  local t0 = wall()
  local out = dir .. "/dfle-bench-g5-" .. w .. ".csv"
  local ens = g5(w, out)
  os.remove(out)
  local dt = wall() - t0
  rates[w] = n / dt
  print(("ensemble Table G5 (empirical), n = %d: %2d worker(s) %7.1f runs/s  (%d ok, %d failed)")
        :format(n, w, n / dt, ens.ok, ens.failed))
end
if cores > 1 then
  print(("ensemble speed-up on %d cores: %.2fx"):format(cores, rates[cores] / rates[1]))
end
