#!/bin/sh
# Runs the Python package's tests (pytest) with Debian's /usr/bin/python3
# against BUILD/python; skips, saying why, where that interpreter, numpy
# or pytest is missing, and in sanitizer builds (the extension would need
# the sanitizer's runtime preloaded into Python).
BUILD=${1:-build}
PYTHON=${PYTHON:-/usr/bin/python3}
cd "$(dirname "$0")/../.." || exit 2
skip() { echo "python-tests: skipped: $1"; exit 0; }
[ -x "$PYTHON" ] || skip "no $PYTHON (scripts/install-deps.sh installs python3-dev, python3-numpy, python3-pytest)"
"$PYTHON" -c 'import numpy' 2>/dev/null || skip "$PYTHON has no numpy (install python3-numpy)"
"$PYTHON" -c 'import pytest' 2>/dev/null || skip "$PYTHON has no pytest (install python3-pytest)"
[ -z "${SANITIZE:-}" ] || skip "a sanitizer build"
ls "$BUILD"/python/dfle/_dfle*.so >/dev/null 2>&1 || { echo "python-tests: no $BUILD/python/dfle (make python)"; exit 1; }
out=$(mktemp) || exit 2
BUILD="$BUILD" PYTHONPATH="$PWD/$BUILD/python" "$PYTHON" -m pytest -q -p no:cacheprovider tests/python > "$out" 2>&1
st=$?
cat "$out"
# The summary as every suite here ends: "N passed, N failed".
passed=$(grep -o '[0-9][0-9]* passed' "$out" | tail -1 | cut -d' ' -f1)
failed=$(grep -o '[0-9][0-9]* failed' "$out" | tail -1 | cut -d' ' -f1)
rm -f "$out"
echo "python: ${passed:-0} passed, ${failed:-0} failed"
exit $st
