-- mpi.lua - one timing for bench/mpi.sh: the Table G5 ensemble of
-- arg[1] samples written to arg[2], timed on rank 0 from the call to
-- its return (MPI's start-up is not in it).  Prints the seconds, rank
-- 0's CPU seconds over the call (all its threads) and the rows that are
-- ok; with --verbose dfle-mpi adds a line for every other rank's CPU.
-- Workers replay this script: they stop at the call.

local here = (arg and arg[0] or ""):match("^(.*)/") or "."
local g5, wall = dofile(here .. "/g5.lua")
local t0, c0 = not dfle.worker() and wall(), os.clock()
local ens = g5(tonumber(arg[1]), nil, arg[2])
os.remove(arg[2])
print(("%.4f %.4f %d"):format(wall() - t0, os.clock() - c0, ens.ok))
