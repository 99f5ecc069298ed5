#!/bin/sh
# Runs the Python package's tests (pytest) with Debian's /usr/bin/python3
# against BUILD/python; skips, saying why, where that interpreter, numpy
# or pytest is missing.  In a sanitizer build (make check) the extension
# is ASan/UBSan code in an interpreter that is not: the runtimes are
# preloaded, and leak checking is off (the interpreter keeps memory to
# the end on purpose; make memcheck covers leaks).
BUILD=${1:-build}
PYTHON=${PYTHON:-/usr/bin/python3}
cd "$(dirname "$0")/../.." || exit 2
skip() { echo "python-tests: skipped: $1"; exit 0; }
[ -x "$PYTHON" ] || skip "no $PYTHON (scripts/install-deps.sh installs python3-dev, python3-numpy, python3-pytest)"
"$PYTHON" -c 'import numpy' 2>/dev/null || skip "$PYTHON has no numpy (install python3-numpy)"
"$PYTHON" -c 'import pytest' 2>/dev/null || skip "$PYTHON has no pytest (install python3-pytest)"
if [ -n "${SANITIZE:-}" ]; then
    asan=$(${CC:-cc} -print-file-name=libasan.so)
    ubsan=$(${CC:-cc} -print-file-name=libubsan.so)
    [ -f "$asan" ] && [ -f "$ubsan" ] || skip "a sanitizer build, and ${CC:-cc} names no libasan.so and libubsan.so to preload"
    export LD_PRELOAD="$asan $ubsan${LD_PRELOAD:+ $LD_PRELOAD}"
    export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
fi
ls "$BUILD"/python/dfle/_dfle*.so >/dev/null 2>&1 || { echo "python-tests: no $BUILD/python/dfle (make python)"; exit 1; }
out=$(mktemp) || exit 2
BUILD="$BUILD" PYTHONPATH="$PWD/$BUILD/python" "$PYTHON" -m pytest -q -rs -p no:cacheprovider tests/python > "$out" 2>&1
st=$?
cat "$out"
# The summary as every suite here ends: "N passed, N failed".
passed=$(grep -o '[0-9][0-9]* passed' "$out" | tail -1 | cut -d' ' -f1)
failed=$(grep -o '[0-9][0-9]* failed' "$out" | tail -1 | cut -d' ' -f1)
rm -f "$out"
echo "python: ${passed:-0} passed, ${failed:-0} failed"
exit $st
