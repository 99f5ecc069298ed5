#!/bin/sh
# check-layers.sh - the tree's architecture as a test (doc/c-api.md, "The
# house"): every #include of a public header goes to a layer at or below
# the including file's own, no file includes another folder's private
# (*_internal.h) header or any header of a folder above its own, the
# subfolders of the Lua binding call down among themselves too, and
# nothing but the binding and the command includes Lua: not the C
# library, not its driver layer, not the MPI driver.
# Includes stand for calls: a file can only call what it can see.
#
#   sh tests/check-layers.sh              check src/
#   sh tests/check-layers.sh --self-test  check that it catches each kind
#                                         of mistake, in a scratch tree
cd "$(dirname "$0")/.." || exit 2

# Layers, bottom first; a header belongs to the layer of the folder that
# implements it.
rank() {
    case $1 in
    base) echo 0 ;; domain) echo 1 ;; routers | drainage) echo 2 ;; laws) echo 3 ;;
    model) echo 4 ;; solvers) echo 5 ;; dem) echo 6 ;; analysis) echo 7 ;; landscape) echo 8 ;;
    io) echo 9 ;; drive) echo 10 ;; mpi) echo 11 ;; lua) echo 12 ;; cli) echo 13 ;; python) echo 14 ;; *) echo 99 ;;
    esac
}
# The Lua binding's subfolders, bottom first: the core every file uses,
# the tracer, laws and routers written in Lua, the objects, the analysis
# functions, the parallel calls' machinery, the calls themselves, and the
# bridge through which a host without Lua (src/python/) drives the module.
lua_rank() {
    case $1 in
    core) echo 0 ;; trace) echo 1 ;; define) echo 2 ;; objects | analysis) echo 3 ;;
    drive) echo 4 ;; ensemble | invert) echo 5 ;; bridge) echo 6 ;; *) echo 99 ;;
    esac
}
header_layer() {
    case $1 in
    error.h | param.h | file.h | plausible.h | record.h | par.h) echo base ;; channel.h | network.h) echo domain ;;
    flow.h | flow1d.h | router*.h) echo routers ;; drainage.h) echo drainage ;;
    lua.h) echo lua ;; fluvial.h | law*.h) echo laws ;; model.h) echo model ;;
    model_events.h) echo model ;;
    solver.h) echo solvers ;; dem.h | crs.h) echo dem ;; landscape.h | landscape_events.h) echo landscape ;;
    analysis.h | analytical.h | sampling.h | sensitivity.h | chi.h) echo analysis ;;
    stream.h | prior.h | mcmc.h | mcmc_diag.h | lsq.h | likelihood.h) echo analysis ;;
    csv.h | ensemble.h | plot.h | raster.h | netcdf.h | vector.h) echo io ;;
    evaluator.h | pool.h | ensemble_run.h | invert_run.h) echo drive ;; *) echo unknown ;;
    esac
}

# check ROOT: the files of ROOT/src; prints "not ok" lines, returns 1 if any.
check() {
    root=$1
    bad=0
    for f in $(cd "$root" && find src -name '*.[ch]' | sort); do
        layer=$(echo "$f" | cut -d/ -f2)
        r=$(rank "$layer")
        text="$root/$f"
        for h in $(sed -n 's|^#include "dfle/\([a-z0-9_]*\.h\)".*|\1|p' "$text"); do
            hl=$(header_layer "$h")
            if [ "$hl" = unknown ]; then
                echo "not ok - $f includes dfle/$h, which no layer claims (add it to $0)"
                bad=1
            elif [ "$(rank "$hl")" -gt "$r" ]; then
                echo "not ok - $f ($layer) includes dfle/$h ($hl): a call up the layers"
                bad=1
            fi
        done
        for h in $(sed -n 's|^#include "\([a-z]*\)/[a-z0-9_/]*_internal\.h".*|\1|p' "$text"); do
            if [ "$h" != "$layer" ]; then
                echo "not ok - $f ($layer) includes a private header of $h/"
                bad=1
            fi
        done
        # The library's own private headers outside *_internal.h (base/'s
        # loaders of GDAL and netCDF) serve the layers above theirs only.
        for h in $(sed -n 's|^#include "\([a-z]*\)/[a-z0-9_/]*\.h".*|\1|p' "$text"); do
            if [ "$h" != dfle ] && [ "$(rank "$h")" -gt "$r" ]; then
                echo "not ok - $f ($layer) includes a header of $h/: a call up the layers"
                bad=1
            fi
        done
        # Inside the binding, its subfolders in their order.
        if [ "$layer" = lua ]; then
            sub=$(echo "$f" | cut -d/ -f3)
            sr=$(lua_rank "$sub")
            if [ "$sr" = 99 ]; then
                echo "not ok - $f is in src/lua/$sub/, which no rank claims (add it to $0)"
                bad=1
            fi
            for h in $(sed -n 's|^#include "lua/\([a-z]*\)/[a-z0-9_]*\.h".*|\1|p' "$text"); do
                if [ "$(lua_rank "$h")" -gt "$sr" ]; then
                    echo "not ok - $f (lua/$sub) includes a header of lua/$h/: a call up the binding's layers"
                    bad=1
                fi
            done
            for h in $(sed -n 's|^#include "lua/\([a-z]*\)/[a-z0-9_]*_internal\.h".*|\1|p' "$text"); do
                if [ "$h" != "$sub" ]; then
                    echo "not ok - $f (lua/$sub) includes a private header of lua/$h/"
                    bad=1
                fi
            done
        fi
        # Python's headers in the Python extension only.
        if [ "$layer" != python ] && grep -q '^#include <\(Python\|numpy/[a-z_]*\)\.h>' "$text"; then
            echo "not ok - $f ($layer) is not the Python extension but includes Python"
            bad=1
        fi
        case $layer in
        lua | cli) ;;
        *)
            if grep -q '^#include <l\(ua\|auxlib\|ualib\)\.h>' "$text"; then
                echo "not ok - $f ($layer) is not the Lua binding but includes Lua"
                bad=1
            fi
            ;;
        esac
    done
    return $bad
}

# Each kind of mistake in a scratch tree, one file each: the check must
# name every one of them, and pass the same tree without them.
self_test() {
    tmp=$(mktemp -d) || exit 2
    trap 'rm -rf "$tmp"' EXIT
    mkdir -p "$tmp/src/drive" "$tmp/src/base" "$tmp/src/mpi" "$tmp/src/io" \
        "$tmp/src/lua/core" "$tmp/src/lua/ensemble" "$tmp/src/lua/drive"
    printf '#include "dfle/error.h"\n' > "$tmp/src/drive/fine.c"
    printf '#include "lua/drive/lua_drive.h"\n#include "lua/core/dfle_lua.h"\n' \
        > "$tmp/src/lua/ensemble/fine.c"
    if ! check "$tmp" > "$tmp/out"; then
        echo "not ok - self-test: a clean tree fails"
        cat "$tmp/out"
        return 1
    fi
    printf '#include <lua.h>\n' > "$tmp/src/drive/a.c"
    printf '#include <lauxlib.h>\n' > "$tmp/src/io/b.c"
    printf '#include <lua.h>\n' > "$tmp/src/mpi/c.c"
    printf '#include "dfle/pool.h"\n' > "$tmp/src/base/d.c"
    printf '#include "lua/drive/lua_drive.h"\n' > "$tmp/src/mpi/e.c"
    printf '#include "lua/ensemble/lua_ensemble.h"\n' > "$tmp/src/lua/core/f.c"
    printf '#include "lua/ensemble/lua_ensemble_internal.h"\n' > "$tmp/src/lua/drive/g.c"
    printf '#include "drive/drive_internal.h"\n' > "$tmp/src/io/h.c"
    if check "$tmp" > "$tmp/out"; then
        echo "not ok - self-test: a tree with every mistake passes"
        return 1
    fi
    miss=0
    for want in "src/drive/a.c (drive) is not the Lua binding but includes Lua" \
        "src/io/b.c (io) is not the Lua binding but includes Lua" \
        "src/mpi/c.c (mpi) is not the Lua binding but includes Lua" \
        "src/base/d.c (base) includes dfle/pool.h (drive): a call up the layers" \
        "src/mpi/e.c (mpi) includes a header of lua/: a call up the layers" \
        "src/lua/core/f.c (lua/core) includes a header of lua/ensemble/" \
        "src/lua/drive/g.c (lua/drive) includes a header of lua/ensemble/" \
        "src/lua/drive/g.c (lua/drive) includes a private header of lua/ensemble/" \
        "src/io/h.c (io) includes a private header of drive/"; do
        if ! grep -qF "$want" "$tmp/out"; then
            echo "not ok - self-test: not caught: $want"
            miss=1
        fi
    done
    [ "$miss" -eq 0 ] && echo "ok - layers self-test: every kind of mistake is caught"
    return $miss
}

if [ "${1:-}" = --self-test ]; then
    self_test
    exit $?
fi
if check .; then
    echo "ok - layers: every include goes down, in the library and in the binding's subfolders; only the binding and the command include Lua"
    exit 0
fi
exit 1
