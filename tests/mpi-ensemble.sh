#!/bin/sh
# mpi-ensemble.sh - `make test-mpi`: build/dfle-mpi on 2 and 3 ranks
# (one machine) writes the same file as the plain build, resumes a run
# the plain build started, and records failed samples.  Needs mpirun
# (Debian: openmpi-bin).  `make test` runs it when mpicc is installed;
# the plain build needs no MPI.
BUILD=${BUILD:-build}
DFLE="$PWD/$BUILD/dfle"
DFLE_MPI="$PWD/$BUILD/dfle-mpi"
MPIRUN="mpirun --oversubscribe"
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
for k in 2 3; do
    $MPIRUN -n $k "$DFLE_MPI" -q sweep.lua mpi$k.csv > out$k.txt 2>&1
    s=$?
    [ $s -eq 0 ] && grep -q "ran=40 count=40 ok=40" out$k.txt && cmp -s plain.csv mpi$k.csv
    check "$k ranks write the file of the plain build" $?
done
"$DFLE" -q -j 1 sweep.lua resumed.csv "" 15 > /dev/null
$MPIRUN -n 3 "$DFLE_MPI" -q sweep.lua resumed.csv > outr.txt 2>&1 &&
    grep -q "ran=25 count=40" outr.txt && cmp -s plain.csv resumed.csv
check "3 ranks resume a run of the plain build" $?
$MPIRUN -n 3 "$DFLE_MPI" -q sweep.lua fail.csv "error('no model here')" > outf.txt 2>&1 &&
    grep -q "ran=40 count=40 ok=0" outf.txt && [ "$(grep -c ',error,".*no model here' fail.csv)" -eq 40 ]
check "3 ranks record failed samples as rows" $?
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
