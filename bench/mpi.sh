#!/bin/sh
# mpi.sh - dfle-mpi against threads, for `make bench` (never asserts):
# the Table G5 ensemble (bench/g5.lua) on 1 rank x 1 thread, 2 ranks x 1
# thread and 1 rank x 2 threads, alternated REPS times.  The time is
# taken inside the script, on rank 0, from the call to its return (MPI's
# start-up is left out); the CPU time is every rank's over the ensemble.
# usage: bench/mpi.sh path/to/dfle-mpi [samples] [repetitions]
DFLE_MPI=$1
N=${2:-2000}
REPS=${3:-3}
here=$(dirname "$0")
MPIRUN="mpirun --oversubscribe"
[ "$(id -u)" -eq 0 ] && MPIRUN="$MPIRUN --allow-run-as-root"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# measure label command...: appends "seconds cpu" to $tmp/label
measure() {
    label=$1
    shift
    if ! "$@" --verbose "$here/mpi.lua" "$N" "$tmp/g5.csv" > "$tmp/out" 2>&1; then
        echo "mpi benchmark: $label failed: $(head -c 300 "$tmp/out")"
        return
    fi
    # rank 0's line, then the other ranks' "rank r (node): ..., c s of CPU"
    awk '/^[0-9.]+ [0-9.]+ [0-9]+$/ { t = $1; c += $2 }
         /s of CPU$/ { c += $(NF - 3) }
         END { if (t != "") printf "%s %.3f\n", t, c }' "$tmp/out" >> "$tmp/$label"
}

load0=$(cut -d' ' -f1 /proc/loadavg)
for _ in $(seq "$REPS"); do
    measure 1x1 $MPIRUN -n 1 "$DFLE_MPI" -j 1
    measure 2x1 $MPIRUN -n 2 "$DFLE_MPI" -j 1
    measure 1x2 $MPIRUN -n 1 --bind-to none "$DFLE_MPI" -j 2
done
load1=$(cut -d' ' -f1 /proc/loadavg)
for f in 1x1 2x1 1x2; do [ -s "$tmp/$f" ] || exit 0; done

# "best median" of column k of a file
stat() { sort -g -k"$2" "$1" | awk -v k="$2" '{ v[NR] = $k } END { printf "%.3f %.3f", v[1], v[int((NR + 1) / 2)] }'; }
set -- $(stat "$tmp/1x1" 1) $(stat "$tmp/2x1" 1) $(stat "$tmp/1x2" 1) \
       $(stat "$tmp/1x1" 2) $(stat "$tmp/2x1" 2) $(stat "$tmp/1x2" 2)
awk -v n="$N" -v reps="$REPS" -v c="$(nproc)" -v l0="$load0" -v l1="$load1" \
    -v b11="$1" -v m11="$2" -v b21="$3" -v m21="$4" -v b12="$5" -v m12="$6" \
    -v c11="$8" -v c21="${10}" -v c12="${12}" 'BEGIN {
    printf "dfle-mpi, Table G5 ensemble (empirical), n = %d, %d runs each: seconds inside the call (best, median), CPU seconds of all ranks over it (median)\n", n, reps
    printf "  1 rank  x 1 thread : %6.3f %6.3f   CPU %6.3f\n", b11, m11, c11
    printf "  2 ranks x 1 thread : %6.3f %6.3f   CPU %6.3f\n", b21, m21, c21
    printf "  1 rank  x 2 threads: %6.3f %6.3f   CPU %6.3f\n", b12, m12, c12
    printf "MPI 2 ranks x 1 thread vs 1 rank x 1 thread: %.2fx (median; best %.2fx) (target >= 1.8x on 2 cores)\n", m11 / m21, b11 / b21
    printf "  CPU: 2 ranks use %.2fx the CPU of 1 rank: at most %.2fx on 2 free cores\n", c21 / c11, 2 * c11 / c21
    printf "MPI 2 ranks x 1 thread vs 1 rank x 2 threads: %.2fx (median; best %.2fx) (target about 1; 0.40x when rank 0 only coordinated)\n", m12 / m21, b12 / b21
    if (l0 > c || l1 > c)
        printf "  (load average %s then %s on %d cores: other processes share the cores, and each MPI rank is a scheduling group of its own, which favours more ranks; trust the CPU line)\n", l0, l1, c
}'
