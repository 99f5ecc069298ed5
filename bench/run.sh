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
# Start-up, beside the same with GDAL and libnetcdf preloaded (as when
# they were linked): their sonames as this build loads them.
preload=$(sed -n 's/^#define DFLE_\(GDAL\|NETCDF\)_SONAME "\(.*\)"$/\2/p' \
          "$BIN/../gen/extlib_names.h" 2> /dev/null | tr '\n' ' ')
"$BIN/startup" "$DFLE" "$preload" "$(command -v lua5.4)"
"$DFLE" -q "$here/steady_state.lua"
"$BIN/direct"
"$BIN/process"
"$DFLE" -q "$here/process.lua"
"$DFLE" -q "$here/dem.lua"
"$BIN/drainage"
"$BIN/landscape"
"$DFLE" -q "$here/landscape.lua"
"$DFLE" -q "$here/landscape_df.lua"
"$DFLE" -q "$here/landscape_process.lua"
"$DFLE" -q "$here/fit.lua"
"$DFLE" -q "$here/methods.lua"
"$DFLE" -q "$here/ensemble.lua"
"$BIN/pawn"
# dfle-mpi against threads, where `make mpi` built it and mpirun is there.
if [ -x "$(dirname "$DFLE")/dfle-mpi" ] && command -v mpirun > /dev/null; then
    sh "$here/mpi.sh" "$(dirname "$DFLE")/dfle-mpi"
fi
"$DFLE" -q "$here/laws.lua"
"$DFLE" -q "$here/invert.lua"
# The Python package against the same calls from Lua, where it is built.
if ls "$(dirname "$DFLE")"/python/dfle/_dfle*.so > /dev/null 2>&1 && [ -x /usr/bin/python3 ]; then
    PYTHONPATH="$(dirname "$DFLE")/python" /usr/bin/python3 "$here/python.py"
fi
