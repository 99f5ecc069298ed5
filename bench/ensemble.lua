-- ensemble.lua - runs per second of the Table G5 ensemble (empirical
-- router, sensitivity analysis; paper channel, default direct method)
-- on all cores and on one.  arg[1]: number of samples (default 400).
-- Each measurement starts a fresh file (resume = false) in $TMPDIR.
-- Workers replay this script up to each dfle.ensemble call, so
-- everything before it is deterministic (no os.tmpname, no clock).

local n = tonumber(arg and arg[1]) or 400
local dir = os.getenv("TMPDIR") or "/tmp"

local here = (arg and arg[0] or ""):match("^(.*)/") or "."
local g5, wall = dofile(here .. "/g5.lua")

local h = io.popen("nproc")
local cores = tonumber(h:read("l")) or 1
h:close()
local rates = {}
for _, w in ipairs{ cores, 1 } do
  local t0 = wall()
  local out = dir .. "/dfle-bench-g5-" .. w .. ".csv"
  local ens = g5(n, w, out)
  os.remove(out)
  local dt = wall() - t0
  rates[w] = n / dt
  print(("ensemble Table G5 (empirical), n = %d: %2d worker(s) %7.1f runs/s  (%d ok, %d failed)")
        :format(n, w, n / dt, ens.ok, ens.failed))
end
if cores > 1 then
  print(("ensemble speed-up on %d cores: %.2fx"):format(cores, rates[cores] / rates[1]))
end
