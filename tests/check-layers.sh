#!/bin/sh
# check-layers.sh - the tree's architecture as a test (doc/c-api.md, "The
# house"): every #include of a public header goes to a layer at or below
# the including file's own, no file includes another folder's private
# (*_internal.h) header or any header of a folder above its own, and the
# C library's sources never include Lua.
# Includes stand for calls: a file can only call what it can see.
cd "$(dirname "$0")/.." || exit 2
fail=0

# Layers, bottom first; a header belongs to the layer of the folder that
# implements it.
rank() {
    case $1 in
    base) echo 0 ;; domain) echo 1 ;; routers | drainage) echo 2 ;; laws) echo 3 ;;
    model) echo 4 ;; solvers) echo 5 ;; dem) echo 6 ;; analysis) echo 7 ;; landscape) echo 8 ;;
    io) echo 9 ;; lua) echo 10 ;; cli | mpi) echo 11 ;; *) echo 99 ;;
    esac
}
header_layer() {
    case $1 in
    error.h | param.h | file.h | plausible.h | record.h) echo base ;; channel.h | network.h) echo domain ;;
    flow.h | flow1d.h | router*.h) echo routers ;; drainage.h) echo drainage ;;
    lua.h) echo lua ;; fluvial.h | law*.h) echo laws ;; model.h) echo model ;;
    solver.h) echo solvers ;; dem.h) echo dem ;; landscape.h) echo landscape ;;
    analysis.h | analytical.h | sampling.h | sensitivity.h | chi.h) echo analysis ;;
    stream.h | prior.h | mcmc.h | mcmc_diag.h | lsq.h | likelihood.h) echo analysis ;;
    csv.h | ensemble.h | plot.h | raster.h | netcdf.h) echo io ;; *) echo unknown ;;
    esac
}

for f in $(find src -name '*.[ch]' | sort); do
    layer=$(echo "$f" | cut -d/ -f2)
    r=$(rank "$layer")
    for h in $(sed -n 's|^#include "dfle/\([a-z0-9_]*\.h\)".*|\1|p' "$f"); do
        hl=$(header_layer "$h")
        if [ "$hl" = unknown ]; then
            echo "not ok - $f includes dfle/$h, which no layer claims (add it to $0)"
            fail=1
        elif [ "$(rank "$hl")" -gt "$r" ]; then
            echo "not ok - $f ($layer) includes dfle/$h ($hl): a call up the layers"
            fail=1
        fi
    done
    for h in $(sed -n 's|^#include "\([a-z]*\)/[a-z0-9_/]*_internal\.h".*|\1|p' "$f"); do
        if [ "$h" != "$layer" ] && [ "$h" != lua ]; then
            echo "not ok - $f ($layer) includes a private header of $h/"
            fail=1
        fi
    done
    # The library's own private headers outside *_internal.h (base/'s
    # loaders of GDAL and netCDF) serve the layers above theirs only.
    for h in $(sed -n 's|^#include "\([a-z]*\)/[a-z0-9_/]*\.h".*|\1|p' "$f"); do
        if [ "$h" != dfle ] && [ "$(rank "$h")" -gt "$r" ]; then
            echo "not ok - $f ($layer) includes a header of $h/: a call up the layers"
            fail=1
        fi
    done
    case $layer in
    lua | cli | mpi) ;;
    *)
        if grep -q '^#include <l\(ua\|auxlib\|ualib\)\.h>' "$f"; then
            echo "not ok - $f is in the C library but includes Lua"
            fail=1
        fi
        ;;
    esac
done
if [ "$fail" -eq 0 ]; then
    echo "ok - layers: every include goes down, no private header crosses a folder, the library has no Lua"
fi
exit $fail
