#!/bin/sh
# run.sh - runs the API fuzzer (tests/fuzz/fuzz.lua), one child process
# per seed, each in a scratch directory of its own, under a watchdog.
#
#   sh tests/fuzz/run.sh [short|long] [DFLE]
#
#   short  the fixed seeds 1-3, 1000 calls each, one after the other: the
#          same calls on every run; part of `make test` and `make check`
#   long   `make fuzz`: 25 seeds of 2000 calls (50,000 calls) two at a time,
#          every other pair sharing one scratch directory (two processes
#          writing the same files and locking the same ensembles), then a
#          seed stopped by SIGINT at a random moment (it must exit 130
#          with one line), a second SIGINT (it must end at once), a
#          seed under a 64 KB file-size limit, and a seed killed with
#          SIGKILL at a random moment (every output it wrote must be
#          whole) followed by another in its directory
#
# DFLE is the binary (default build/dfle; `make fuzz` gives build/san/dfle).
# FUZZ_SEEDS="4 5" and FUZZ_CALLS=N override the seeds and calls of either
# mode; FUZZ_STALL=S (default 120) is how long a call may run; FUZZ_KEEP=1
# keeps the scratch directories.
#
# A finding is reported with its seed and call, and the command that
# replays it.  A child that crashes, trips a sanitizer, leaks, or makes
# no progress for FUZZ_STALL seconds (killed: a hang) is reported with the
# call it was in.  The last line is the summary:
#   fuzz: N calls in S s (C calls/s), ok A, errors B, findings F, crashes X, hangs H
# and the exit status is 0 only when F, X and H are all 0.
mode=${1:-short}
DFLE=${2:-build/dfle}
here=$(cd "$(dirname "$0")" && pwd)
case "$DFLE" in /*) ;; *) DFLE="$PWD/$DFLE" ;; esac
[ -x "$DFLE" ] || { echo "fuzz: no binary $DFLE (make first)"; exit 2; }
# The shared data (DEMs, SALib cases), as tests/run-tests.sh finds them.
if [ -z "${DFLE_DATA_DIR:-}" ]; then
    DFLE_DATA_DIR="$(cd "$here/../../.." && pwd)/shared/data"
fi
export DFLE_DATA_DIR

case "$mode" in
short) seeds=${FUZZ_SEEDS:-"1 2 3"}; calls=${FUZZ_CALLS:-1000}; jobs=1 ;;
long)  seeds=${FUZZ_SEEDS:-$(seq 1 25)}; calls=${FUZZ_CALLS:-2000}; jobs=2 ;;
*) echo "usage: sh tests/fuzz/run.sh [short|long] [DFLE]"; exit 2 ;;
esac
stall=${FUZZ_STALL:-120}

# Memory: a sanitizer build refuses allocations past these limits (malloc
# returns NULL, which dfle must handle); a plain build gets an address-
# space limit for the same effect.  Neither lets a hostile size take the
# machine's memory.
if ASAN_OPTIONS=help=1 "$DFLE" -v 2>&1 | grep -q allocator_may_return_null; then
    san=1
    export ASAN_OPTIONS="allocator_may_return_null=1:max_allocation_size_mb=2048:soft_rss_limit_mb=3000:hard_rss_limit_mb=6000:detect_leaks=1:exitcode=86"
    export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:exitcode=87"
else
    san=0
fi

top=$(mktemp -d "${TMPDIR:-/tmp}/dfle-fuzz.XXXXXX")
cleanup() {
    for p in "$top"/*.pid; do
        [ -f "$p" ] && kill -KILL -"$(cat "$p")" 2>/dev/null
    done
    [ "${FUZZ_KEEP:-0}" = 1 ] || rm -rf "$top"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# A scratch directory with its device nodes: never /dev itself.
make_scratch() { # dir
    mkdir -p "$1/dev"
    if [ "$(id -u)" = 0 ]; then
        mknod "$1/dev/null" c 1 3 2>/dev/null
        mknod "$1/dev/full" c 1 7 2>/dev/null
        mknod "$1/dev/zero" c 1 5 2>/dev/null
    fi
    mkfifo "$1/dev/fifo" 2>/dev/null
    : # nodes that cannot be made are simply missing (the calls then fail cleanly)
}

now() { date +%s.%N 2>/dev/null || date +%s; }

# Start one child: seed, scratch dir, tag, calls; extra shell setup in
# $pre.  Writes $top/<tag>.{out,err,prog,pid}.
start_child() { # seed dir tag calls [pre]
    seed=$1 dir=$2 tag=$3 n=$4 pre=${5:-:}
    : > "$top/$tag.prog"
    (
        cd "$dir" || exit 2
        eval "$pre"
        [ "$san" = 1 ] || ulimit -v 4194304 2>/dev/null
        exec setsid "$DFLE" -q -j 1 "$here/fuzz.lua" seed="$seed" calls="$n" \
            scratch="$dir" progress="$top/$tag.prog" > "$top/$tag.out" 2> "$top/$tag.err"
    ) &
    echo $! > "$top/$tag.pid"
}

total_calls=0 ok=0 errors=0 findings=0 crashes=0 hangs=0 failed_seeds=

# Every output in dir/out must be whole: an image ends as its format
# says, a CSV with a newline.  (An ensemble's own file is streamed: a
# kill may cut its last line, which a resume drops.)
check_outputs() { # dir seed
    for f in "$1"/out/* "$1"/out/.[!.]*; do
        [ -f "$f" ] && [ ! -L "$f" ] && [ -s "$f" ] || continue
        case "$(basename "$f")" in .*.[0-9]*.[0-9]*) continue ;; esac # a killed writer's temporary file
        head=$(head -c 16 "$f" | od -An -c | tr -d ' \n')
        whole=1
        case "$head" in
        211PNG*) [ "$(tail -c 8 "$f" | head -c 4)" = IEND ] || whole=0 ;;
        \<\?xml*|\<svg*) tail -c 16 "$f" | grep -q '</svg>' || whole=0 ;;
        \#dfle.ensemble*|\#dfle.invert*) ;;
        # GeoTIFF and NetCDF (GDAL and libnetcdf write them; their
        # wholeness is the rename's): the header is enough here
        II\*\\0*|MM\\0\**|CDF00[12]*|211HDF*) ;;
        *) [ "$(tail -c 1 "$f" | od -An -c | tr -d ' ')" = '\n' ] || whole=0 ;;
        esac
        if [ "$whole" = 0 ]; then
            crashes=$((crashes + 1)); failed_seeds="$failed_seeds $2"
            echo "TORN seed=$2: $f is not whole"
        fi
    done
}

# Wait for the child of tag, killing it if its progress file stops
# growing; then read its outcome.  $expect is the exit status it should
# have (0, or 130 for an interrupted child).
finish_child() { # tag seed [expect]
    tag=$1 seed=$2 expect=${3:-0}
    pid=$(cat "$top/$tag.pid")
    last=-1 idle=0 hung=0
    while kill -0 "$pid" 2>/dev/null; do
        size=$(wc -c < "$top/$tag.prog")
        if [ "$size" = "$last" ]; then idle=$((idle + 1)); else idle=0; last=$size; fi
        if [ "$idle" -ge $((stall * 5)) ]; then
            hung=1
            kill -KILL -"$pid" 2>/dev/null || kill -KILL "$pid" 2>/dev/null
        fi
        sleep 0.2
    done
    wait "$pid" 2>/dev/null
    rc=$?
    rm -f "$top/$tag.pid" # only running children are killed on exit, never a reused pid
    call=$(tail -n 1 "$top/$tag.prog" 2>/dev/null)
    case "$call" in [0-9]*) ;; *) call="0 (before the first call)" ;; esac
    summary=$(grep -a '^fuzz seed=' "$top/$tag.out" | tail -n 1)
    if [ -n "$summary" ]; then
        for kv in $summary; do
            case "$kv" in
            calls=*) total_calls=$((total_calls + ${kv#calls=})) ;;
            ok=*) ok=$((ok + ${kv#ok=})) ;;
            errors=*) errors=$((errors + ${kv#errors=})) ;;
            esac
        done
    else
        # no summary (killed, crashed, interrupted): count the calls made
        total_calls=$((total_calls + ${call%% *}))
    fi
    grep -a '^FINDING' "$top/$tag.out"
    nf=$(grep -ac '^FINDING' "$top/$tag.out")
    findings=$((findings + nf))
    replay="cd <scratch> && $DFLE -q -j 1 $here/fuzz.lua seed=$seed calls=${call%% *} scratch=<scratch> verbose"
    if [ "$hung" = 1 ]; then
        hangs=$((hangs + 1)); failed_seeds="$failed_seeds $seed"
        echo "HANG seed=$seed: no progress for ${stall} s in call: $call"
        echo "  replay: $replay"
    elif grep -aqE 'ERROR: (Address|Leak)Sanitizer|runtime error:|^SUMMARY: ' "$top/$tag.err" ||
         { [ "$rc" != 0 ] && [ "$rc" != 1 ] && [ "$rc" != "$expect" ]; } ||
         { [ "$rc" = 1 ] && [ "$nf" = 0 ]; }; then
        crashes=$((crashes + 1)); failed_seeds="$failed_seeds $seed"
        echo "CRASH seed=$seed (exit status $rc) in call: $call"
        sed -n '1,60p' "$top/$tag.err" | sed 's/^/  | /'
        echo "  replay: $replay"
    elif [ "$rc" != "$expect" ] && [ "$nf" = 0 ]; then
        crashes=$((crashes + 1)); failed_seeds="$failed_seeds $seed"
        echo "UNEXPECTED seed=$seed: exit status $rc, expected $expect"
        sed -n '1,20p' "$top/$tag.err" | sed 's/^/  | /'
    fi
    [ "$nf" = 0 ] || failed_seeds="$failed_seeds $seed"
}

t0=$(now)
set -- $seeds
pair=0
while [ $# -gt 0 ]; do
    if [ "$jobs" -ge 2 ] && [ $# -ge 2 ]; then
        # two at a time; every other pair shares its scratch directory
        pair=$((pair + 1))
        a=$1 b=$2; shift 2
        make_scratch "$top/s$a"
        if [ $((pair % 2)) = 0 ]; then db="$top/s$a"; else db="$top/s$b"; make_scratch "$db"; fi
        start_child "$a" "$top/s$a" "c$a" "$calls"
        start_child "$b" "$db" "c$b" "$calls"
        finish_child "c$a" "$a"
        finish_child "c$b" "$b"
    else
        a=$1; shift
        make_scratch "$top/s$a"
        start_child "$a" "$top/s$a" "c$a" "$calls"
        finish_child "c$a" "$a"
    fi
    [ "${FUZZ_KEEP:-0}" = 1 ] || rm -rf "$top/s$a" "$top/s$b"
done

if [ "$mode" = long ] && [ -z "${FUZZ_SEEDS:-}" ]; then
    # Interrupted: SIGINT at a moment given by the seed, in a run too
    # long to end first; the fuzzer stops at the first "interrupted"
    # error, the command exits 130 with one line.  Then twice: the
    # second signal ends it at once.
    for s in 101 102; do
        make_scratch "$top/i$s"
        start_child "$s" "$top/i$s" "i$s" 100000
        pid=$(cat "$top/i$s.pid")
        # (once the calls have begun: setting up takes a few seconds in
        # the sanitizer build; at most 60 s)
        w=0
        while [ ! -s "$top/i$s.prog" ] && [ $w -lt 300 ]; do sleep 0.2; w=$((w + 1)); done
        sleep $((s % 3 + 2))
        kill -INT "$pid" 2>/dev/null
        if [ "$s" = 102 ]; then sleep 0.5; kill -INT "$pid" 2>/dev/null; fi
        finish_child "i$s" "$s" 130
        if [ "$s" = 101 ] && [ "$(grep -ac 'interrupted by SIGINT' "$top/i$s.err")" != 1 ]; then
            crashes=$((crashes + 1)); failed_seeds="$failed_seeds $s"
            echo "UNEXPECTED seed=$s: no single 'interrupted by SIGINT' line"
            sed -n '1,10p' "$top/i$s.err" | sed 's/^/  | /'
        fi
    done
    # A file-size limit: every write past 64 KB fails with EFBIG, which
    # must be an error naming the file, never a dead process.
    make_scratch "$top/f201"
    start_child 201 "$top/f201" f201 "$calls" "ulimit -f 128"
    finish_child f201 201
    # Killed at a random moment (kill -9): every output is whole, and a
    # second fuzzer in the same directory (over the leftovers, resuming
    # the ensemble files) runs clean.
    make_scratch "$top/k301"
    start_child 301 "$top/k301" k301 100000
    sleep $(awk 'BEGIN { srand(); printf "%.1f", 2 + 4 * rand() }')
    kill -KILL -"$(cat "$top/k301.pid")" 2>/dev/null
    finish_child k301 301 137
    check_outputs "$top/k301" 301
    start_child 302 "$top/k301" k302 "$calls"
    finish_child k302 302
    check_outputs "$top/k301" 302
fi

t1=$(now)
secs=$(echo "$t0 $t1" | awk '{ d = $2 - $1; if (d <= 0) d = 1; printf "%.1f", d }')
rate=$(echo "$total_calls $secs" | awk '{ printf "%.0f", $1 / $2 }')
[ -z "$failed_seeds" ] || echo "failed seeds:$failed_seeds (FUZZ_SEEDS=\"...\" FUZZ_KEEP=1 to rerun and keep the files)"
echo "fuzz: $total_calls calls in $secs s ($rate calls/s), ok $ok, errors $errors, findings $findings, crashes $crashes, hangs $hangs"
[ "$findings" = 0 ] && [ "$crashes" = 0 ] && [ "$hangs" = 0 ]
