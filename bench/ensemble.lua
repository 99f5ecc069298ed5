-- ensemble.lua - runs per second of the Table G5 ensemble (empirical
-- router, sensitivity analysis; paper channel, default direct method)
-- on all cores and on one.  arg[1]: number of samples (default 400).
-- Each measurement starts a fresh file (resume = false) in $TMPDIR.
-- Workers replay this script up to each dfle.ensemble call, so
-- everything before it is deterministic (no os.tmpname, no clock).
-- Then (issue 15) PAWN of the ensemble's A_df and S_df with 1000
-- bootstrap replicates, on one thread and on every core, beside the time
-- the runs took: the bootstrap once took as long as the runs.

local n = tonumber(arg and arg[1]) or 400
local dir = os.getenv("TMPDIR") or "/tmp"

local here = (arg and arg[0] or ""):match("^(.*)/") or "."
local g5, wall = dofile(here .. "/g5.lua")

local h = io.popen("nproc")
local cores = tonumber(h:read("l")) or 1
h:close()
local rates, ens1, t_runs = {}, nil, nil
for _, w in ipairs{ cores, 1 } do
  local t0 = wall()
  local out = dir .. "/dfle-bench-g5-" .. w .. ".csv"
  local ens = g5(n, w, out)
  os.remove(out)
  local dt = wall() - t0
  if w == 1 then ens1, t_runs = ens, dt end
  rates[w] = n / dt
  print(("ensemble Table G5 (empirical), n = %d: %2d worker(s) %7.1f runs/s  (%d ok, %d failed)")
        :format(n, w, n / dt, ens.ok, ens.failed))
end
if cores > 1 then
  print(("ensemble speed-up on %d cores: %.2fx"):format(cores, rates[cores] / rates[1]))
end

local pawn_t, pawn_ci = {}, {}
for _, t in ipairs{ 1, cores } do
  local t0 = wall()
  local si = dfle.pawn(ens1, { outputs = { "A_df", "S_df" }, S = 10, bootstrap = 1000, threads = t })
  pawn_t[t] = wall() - t0
  pawn_ci[t] = string.format("%a %a", si.A_df.k_df.ci.median.lo, si.S_df.U.ci.CV.hi)
end
print(("PAWN of A_df and S_df with 1000 bootstrap replicates (S = 10, %d runs): 1 thread %.2f s, "
       .. "%d threads %.2f s (%.2fx), same intervals: %s; the runs took %.2f s on 1 worker "
       .. "(target: the bootstrap well under the runs' time; issue 15: as long as them)")
      :format(ens1.ok, pawn_t[1], cores, pawn_t[cores], pawn_t[1] / pawn_t[cores],
              pawn_ci[1] == pawn_ci[cores] and "yes" or "NO", t_runs))
