#!/bin/sh
# mpi-ensemble.sh - `make test-mpi`: build/dfle-mpi on one machine.  For
# any number of ranks and of threads per rank it writes the file of the
# plain build, byte for byte; it resumes a run the plain build started,
# records failed samples, reports a rank whose replay fails, runs
# dfle.invert on threads; and when a rank dies mid-job the job either
# stops (plain mpirun) or finishes without it (mpirun --enable-recovery),
# keeping every finished row, saying so, and resuming to the full file.
# Needs mpirun (Debian: openmpi-bin).  `make test` runs it when mpicc is
# installed; the plain build needs no MPI.
BUILD=${BUILD:-build}
DFLE="$PWD/$BUILD/dfle"
DFLE_MPI="$PWD/$BUILD/dfle-mpi"
# Every run is bounded: a hang fails its test instead of the suite.
MPIRUN="timeout 120 mpirun --oversubscribe"
[ "$(id -u)" -eq 0 ] && MPIRUN="$MPIRUN --allow-run-as-root"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failed=0
passed=0
check() { # name, status
    if [ "$2" -eq 0 ]; then
        echo "ok - $1"; passed=$((passed + 1))
    else
        echo "FAIL - $1"; failed=$((failed + 1))
    fi
}

cat > "$tmp/sweep.lua" <<'LUA'
local out, extra, limit = arg[1], arg[2] or "", tonumber(arg[3] or "0")
local slow = load(extra)
if dfle.worker() and os.getenv("FAIL_REPLAY_ON") == os.getenv("OMPI_COMM_WORLD_RANK") then
  error("this rank cannot replay the script")
end
local ens = dfle.ensemble{
  params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3}, alpha = {values = {2, 4, 6}} },
  n = 40, seed = 11, out = out, limit = limit,
  build = function(p)
    slow()
    return dfle.model{ channel = dfle.channel{ dx = 20 }, U = p.U,
                       law = dfle.law.power{ k_df = p.k_df, alpha = p.alpha } }
  end,
  outputs = { "S_df", "A_df", "r2", "S_max_minus_S_ch" },
}
print(("ran=%d count=%d ok=%d"):format(ens.ran, ens.count, ens.ok))
LUA
cd "$tmp" || exit 1
"$DFLE" -q -j 1 sweep.lua plain.csv > /dev/null

# Ranks x threads per rank (-j): the same rows, byte for byte.
for rj in 1:1 1:2 2:1 3:1 2:2 3:2; do
    r=${rj%:*} j=${rj#*:}
    $MPIRUN -n "$r" "$DFLE_MPI" -q -j "$j" sweep.lua "mpi$r-$j.csv" > "out$r-$j.txt" 2>&1
    s=$?
    [ $s -eq 0 ] && grep -q "ran=40 count=40 ok=40" "out$r-$j.txt" && cmp -s plain.csv "mpi$r-$j.csv"
    check "$r ranks, $j thread(s) each, write the file of the plain build" $?
done
$MPIRUN -n 2 "$DFLE_MPI" -q sweep.lua mpi-default.csv > outd.txt 2>&1 &&
    grep -q "ran=40 count=40" outd.txt && cmp -s plain.csv mpi-default.csv
check "2 ranks with their default threads write the file of the plain build" $?

"$DFLE" -q -j 1 sweep.lua resumed.csv "" 15 > /dev/null
$MPIRUN -n 3 "$DFLE_MPI" -q sweep.lua resumed.csv > outr.txt 2>&1 &&
    grep -q "ran=25 count=40" outr.txt && cmp -s plain.csv resumed.csv
check "3 ranks resume a run of the plain build" $?
$MPIRUN -n 3 "$DFLE_MPI" -q sweep.lua fail.csv "error('no model here')" > outf.txt 2>&1 &&
    grep -q "ran=40 count=40 ok=0" outf.txt && [ "$(grep -c ',error,".*no model here' fail.csv)" -eq 40 ]
check "3 ranks record failed samples as rows" $?

# A rank whose replay of the script fails stops the ensemble with its
# message; rows written are kept and the next run resumes.  Each sample
# takes 20 ms of CPU, so that rank 0 alone cannot finish all 40 before
# rank 1's failure reaches it (a finished ensemble is a success).
FAIL_REPLAY_ON=1 $MPIRUN -x FAIL_REPLAY_ON -n 2 "$DFLE_MPI" -q -j 1 sweep.lua replay.csv \
    "local t = os.clock() while os.clock() - t < 0.02 do end" > outx.txt 2>&1
s=$?
[ $s -ne 0 ] && grep -q "dfle.ensemble: rank 1 (.*this rank cannot replay the script" outx.txt &&
    grep -q "rows written are kept; run again to resume" outx.txt &&
    $MPIRUN -n 2 "$DFLE_MPI" -q sweep.lua replay.csv > /dev/null 2>&1 && cmp -s plain.csv replay.csv
check "a rank that cannot replay the script stops the ensemble with its message" $?

# Inversions run on rank 0's threads (the other ranks wait): the chain
# of the plain build.
cat > inv.lua <<'LUA'
local ch = dfle.channel{ dx = 20 }
local function build(p, c)
  return dfle.model{ channel = c, U = p.U, router = dfle.router.empirical{ gamma = p.gamma } }
end
local m = build({ U = 4e-4, gamma = 0.5 }, ch)
m:run_to_steady{}
local fit = dfle.fit_slope_area(m, { nbins = 20 })
local res = dfle.invert{
  data = { A = fit.bins.A, S = fit.bins.S }, channel = ch, build = build, lsq = false,
  params = { U = { 1e-4, 1e-3, log = true }, gamma = { 0, 1 } },
  walkers = 8, steps = 20, burn = 5, seed = 2, out = arg[1],
}
print(("ran=%d median=%.17g"):format(res.ran, res.summary.U.median))
LUA
"$DFLE" -q -j 1 inv.lua chain-plain.csv > inv-plain.txt 2> inv-plain.err
$MPIRUN -n 2 "$DFLE_MPI" -q -j 2 inv.lua chain-mpi.csv > inv-mpi.txt 2> inv-mpi.err &&
    cmp -s inv-plain.txt inv-mpi.txt &&
    # the chains, without the lines saying when and by which command
    grep -v '^# date: \|^# command: ' chain-plain.csv > chain-plain.rows &&
    grep -v '^# date: \|^# command: ' chain-mpi.csv > chain-mpi.rows &&
    cmp -s chain-plain.rows chain-mpi.rows
check "dfle.invert under dfle-mpi gives the chain of the plain build" $?

# A rank lost mid-job.  At its third sample the victim waits (a bounded
# minute) until the file holds a finished row, so that there is always
# one to keep whatever the timing, then writes its process id and spins
# (a bounded minute) until this script kills it, as the kernel or a
# crash would: no child process of it is alive then.  It holds at least
# that third sample, and samples take 30 ms of CPU each, so the others
# are still at work.
VICTIM='n = (n or 0) + 1
if os.getenv("OMPI_COMM_WORLD_RANK") == os.getenv("VICTIM_RANK") and n == 3 then
  local rows, t = 0, os.time() + 60
  while rows < 1 and os.time() < t do
    local f = io.open(arg[1])
    if f then rows = select(2, f:read("a"):gsub("\n%d[^\n]*%f[\n]", "")); f:close() end
  end
  local f = io.open("/proc/self/stat"); local pid = f:read("n"); f:close()
  f = io.open("victim.tmp", "w"); f:write(pid); f:close(); os.rename("victim.tmp", "victim.pid")
  local t = os.time() + 60; while os.time() < t do end
end
local t = os.clock() + 0.03; while os.clock() < t do end'
# lose_rank rank out log "mpirun options" "dfle-mpi options": 3 ranks
# (RANKS), one thread each; kill `rank` at its third sample.
lose_rank() {
    rm -f victim.pid
    VICTIM_RANK=$1 $MPIRUN $4 -x VICTIM_RANK -n "${RANKS:-3}" "$DFLE_MPI" -q -j 1 $5 sweep.lua "$2" \
        "$VICTIM" > "$3" 2>&1 &
    job=$!
    k=0
    while [ ! -s victim.pid ] && [ $k -lt 600 ] && kill -0 $job 2>/dev/null; do
        sleep 0.1
        k=$((k + 1))
    done
    [ -s victim.pid ] && kill -KILL "$(cat victim.pid)"
    wait $job
}
# Every data row of file $1 is a row of the plain run.
rows_of_plain() { [ "$(grep "^[0-9]" "$1" | grep -cvxFf plain.csv)" -eq 0 ]; }

lose_rank 2 lost.csv lost.txt
s=$?
kept=$(grep -c "^[0-9]" lost.csv)
[ $s -ne 0 ] && grep -q "rank 2 .*exited on signal 9" lost.txt && rows_of_plain lost.csv &&
    [ "$kept" -ge 1 ] &&
    $MPIRUN -n 3 "$DFLE_MPI" -q sweep.lua lost.csv > lost-again.txt 2>&1 &&
    grep -q "ran=$((40 - kept)) count=40" lost-again.txt && cmp -s plain.csv lost.csv
check "plain mpirun, a rank killed mid-job: the job stops, $kept finished rows kept, the rest resumes" $?
# mpirun kills rank 0 a moment after its SIGTERM: it says at once.
[ $s -ne 0 ] && grep -q "rank 0 got SIGTERM .*: stopping; the ensemble rows written so far are kept" lost.txt
check "plain mpirun, a rank killed mid-job: rank 0 says the rows are kept" $?

# With --enable-recovery mpirun lets the others go on: rank 0 takes the
# silent rank as lost after --rank-timeout and hands its samples on.
if $MPIRUN --help all 2>/dev/null | grep -q -- --enable-recovery; then
    lose_rank 2 recovered.csv recovered.txt --enable-recovery "--rank-timeout 3"
    s=$?
    [ $s -eq 0 ] && grep -q "ran=40 count=40 ok=40" recovered.txt &&
        grep -q "warning: rank 2 (.*) has been silent for [0-9]* s: taken as lost; its [0-9]* samples* go.* to the other ranks" recovered.txt &&
        cmp -s plain.csv recovered.csv
    check "mpirun --enable-recovery, a rank killed mid-job: the others run its samples, the job finishes" $?
    # The only other rank lost: rank 0's own workers run its samples,
    # started again if they had run out of samples meanwhile.
    RANKS=2 lose_rank 1 alone.csv alone.txt --enable-recovery "--rank-timeout 3"
    s=$?
    [ $s -eq 0 ] && grep -q "ran=40 count=40 ok=40" alone.txt &&
        grep -q "warning: rank 1 (.*) has been silent for [0-9]* s: taken as lost; its [0-9]* samples* go.* to rank 0's own workers" alone.txt &&
        cmp -s plain.csv alone.csv
    check "mpirun --enable-recovery, the only other rank killed mid-job: rank 0 runs its samples, the job finishes" $?
    # Rank 0 lost: the others stop the job rather than wait for ever.
    # (mpirun's own status is 0 then: it lets ranks fail.)
    lose_rank 0 orphan.csv orphan.txt --enable-recovery "--rank-timeout 3"
    grep -q "rank [12] (.*): no word from rank 0 for [0-9]* s; stopping the job" orphan.txt &&
        rows_of_plain orphan.csv && [ "$(grep -c "^[0-9]" orphan.csv)" -ge 1 ]
    check "mpirun --enable-recovery, rank 0 killed mid-job: the others stop with a message, rows kept" $?
else
    echo "ok - # skip mpirun has no --enable-recovery"
fi
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
