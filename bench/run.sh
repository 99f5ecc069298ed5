#!/bin/sh
# make bench: prints benchmark figures (never asserts on time).
# usage: bench/run.sh path/to/dfle
DFLE=${1:-build/dfle}
here=$(dirname "$0")
echo "dfle benchmarks on $(uname -m), $(nproc) cores, $(date -u +%Y-%m-%d)"
"$DFLE" -q "$here/steady_state.lua"
"$DFLE" -q "$here/process.lua"
"$DFLE" -q "$here/dem.lua"
"$DFLE" -q "$here/methods.lua"
"$DFLE" -q "$here/ensemble.lua"
"$DFLE" -q "$here/laws.lua"
"$DFLE" -q "$here/invert.lua"
