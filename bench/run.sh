#!/bin/sh
# make bench: prints benchmark figures (never asserts on time).
# usage: bench/run.sh path/to/dfle [directory of the C drivers]
DFLE=${1:-build/dfle}
BIN=${2:-build/bench}
here=$(dirname "$0")
# Data (the Big Tujunga DEM) from DFLE_DATA_DIR, as for the tests.
if [ -z "${DFLE_DATA_DIR:-}" ]; then
    DFLE_DATA_DIR="$(cd "$here/../.." && pwd)/shared/data"
fi
export DFLE_DATA_DIR
# The load average: on a shared machine, wall-clock ratios (threads, ranks)
# mean little when it exceeds the cores.
echo "dfle benchmarks on $(uname -m), $(nproc) cores, $(date -u +%Y-%m-%d), load average $(cut -d' ' -f1 /proc/loadavg 2>/dev/null || echo '?')"
"$DFLE" -q "$here/steady_state.lua"
"$DFLE" -q "$here/process.lua"
"$DFLE" -q "$here/dem.lua"
"$BIN/drainage"
"$BIN/landscape"
"$DFLE" -q "$here/landscape.lua"
"$DFLE" -q "$here/methods.lua"
"$DFLE" -q "$here/ensemble.lua"
"$BIN/pawn"
"$DFLE" -q "$here/laws.lua"
