#!/bin/sh
# Runs every test: the cmocka binaries, the Lua-level tests and smoke runs
# of the examples.  Exit status is non-zero if anything failed.
# BUILD=dir selects the build; MEMCHECK=1 runs the cmocka tests under valgrind.
BUILD=${BUILD:-build}
# Test data (DEMs, SALib reference cases) come from DFLE_DATA_DIR; on the
# CI machine they sit beside the clone, which is the default here.
if [ -z "${DFLE_DATA_DIR:-}" ]; then
    DFLE_DATA_DIR="$(cd "$(dirname "$0")/../.." && pwd)/shared/data"
fi
if [ ! -d "$DFLE_DATA_DIR/dem" ]; then
    echo "run-tests: no test data in $DFLE_DATA_DIR (set DFLE_DATA_DIR to the directory holding dem/ and salib/)"
    exit 1
fi
export DFLE_DATA_DIR
DFLE="$BUILD/dfle"
failed=0
failures=

run() { # name, command...
    name=$1; shift
    if "$@"; then :; else
        failed=$((failed + 1)); failures="$failures $name"
    fi
}

vg=
if [ "${MEMCHECK:-0}" = 1 ]; then
    vg="valgrind -q --error-exitcode=99 --leak-check=full --errors-for-leak-kinds=definite"
fi

for t in "$BUILD"/tests/test_*; do
    [ -x "$t" ] || continue
    run "$(basename "$t")" $vg "$t"
done

# The architecture: includes go down the layers (doc/c-api.md).
run layers sh tests/check-layers.sh
run layers-self-test sh tests/check-layers.sh --self-test

# Lua-level tests of the scripting API (ends with "N passed, N failed").
run lua-tests $vg "$DFLE" -q tests/lua/run.lua "$DFLE"

# The Python package (tests/python/, ends with "N passed, N failed"):
# Debian's interpreter with numpy and pytest, or a clear skip.
run python-tests sh tests/python/run.sh "$BUILD"

# The installed tree (not in sanitizer or valgrind runs: it installs the
# plain build's files and links a program against them).
if [ -z "${SANITIZE:-}" ] && [ "${MEMCHECK:-0}" != 1 ]; then
    run install sh tests/install.sh
fi
# The API fuzzer, its short fixed-seed mode (ends with "fuzz: N calls ...";
# `make fuzz` runs the long one).  Not under valgrind: it is slow there,
# and `make check` runs it under the sanitizers.
run fuzz sh tests/fuzz/run.sh short "$DFLE"

# Every example in its quick mode, in a scratch directory.
tmp=$(mktemp -d)
for ex in examples/*.lua; do
    [ -f "$ex" ] || continue
    echo "== example $ex (quick)"
    run "$ex" sh -c "cd '$tmp' && '$PWD/$DFLE' -q '$PWD/$ex' --quick > '$tmp/out.txt' 2>&1 || { cat '$tmp/out.txt'; exit 1; }"
done
# The figures they drew are the ones doc/figures.md lists, no more, no less.
run figures "$DFLE" -q doc/gallery.lua --check "$tmp"
rm -rf "$tmp"

if [ "$failed" -ne 0 ]; then
    echo "FAILED:$failures"
    exit 1
fi
echo "all test programs passed"
