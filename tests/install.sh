#!/bin/sh
# The installed tree works as a user meets it: `make install` into a
# staging directory, then the command (its --help points at the installed
# docs), the man page, an example that needs data it does not have, the
# Lua module in a stock lua5.4, C programs built against the installed
# headers and the shared and static libraries, and GDAL and netCDF found
# at run time by each of them, none of which links them.
# BUILD=dir selects the build.  Exit status is non-zero on any failure.
set -u
BUILD=${BUILD:-build}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
root="$tmp/usr"
fail=0
check() { # message, command...
    msg=$1; shift
    if "$@" > "$tmp/out" 2>&1; then
        echo "ok - install: $msg"
    else
        echo "FAIL - install: $msg"; sed 's/^/    /' "$tmp/out"; fail=1
    fi
}

if ! make -s --no-print-directory install DESTDIR="$tmp" PREFIX=/usr BUILD="$BUILD" \
        > "$tmp/make.log" 2>&1; then
    echo "FAIL - install: make install"; cat "$tmp/make.log"; exit 1
fi

check "every part is in place" sh -c "
    for f in bin/dfle lib/libdfle.a lib/libdfle.so lib/libdfle.so.0 lib/lua/5.4/dfle.so \
             lib/pkgconfig/dfle.pc include/dfle/model.h share/man/man1/dfle.1 \
             share/doc/dfle/README.md share/doc/dfle/lua-api.md \
             share/doc/dfle/examples/quickstart.lua; do
        [ -e '$root/'\$f ] || { echo \"missing \$f\"; exit 1; }
    done"

check "--help names the installed docs" sh -c "
    '$root/bin/dfle' --help | grep -F 'man dfle; $root/share/doc/dfle/tutorial.md'"

if command -v man > /dev/null 2>&1; then
    check "the man page renders and lists every option" sh -c "
        MANWIDTH=80 man -l '$root/share/man/man1/dfle.1' 2>&1 > '$tmp/man.txt' &&
        for o in --quiet --verbose -j --shard --help --version DFLE_DATA_DIR; do
            grep -q -e \"\$o\" '$tmp/man.txt' || { echo \"man page lacks \$o\"; exit 1; }
        done"
fi

check "an installed DEM example without data says where to put it" sh -c "
    cd '$tmp' && env -u DFLE_DATA_DIR '$root/bin/dfle' \
        '$root/share/doc/dfle/examples/fig1_slope_area.lua' > ex.out 2>&1
    st=\$?; cat ex.out
    [ \$st -eq 2 ] && grep -q DFLE_DATA_DIR ex.out && grep -q -- --data ex.out"

if command -v lua5.4 > /dev/null 2>&1; then
    check "the module loads in a stock lua5.4" lua5.4 -e "
        package.cpath = '$root/lib/lua/5.4/?.so'
        local dfle = require 'dfle'
        local m = dfle.model{ channel = dfle.channel{ dx = 20 } }
        assert(m:run_to_steady{}.converged)
        local fit = assert(dfle.fit_slope_area(m))
        assert(fit.S_df > 0 and fit.A_df > 0, 'a fit')
        print(dfle.version)"
fi

# GDAL and libnetcdf are loaded on first use, not linked (doc/c-api.md,
# "Building and linking"): nothing installed needs them, and every part
# that reads or writes their formats finds them at run time.
check "nothing installed links GDAL or netCDF" sh -c "
    for f in bin/dfle lib/libdfle.so.0 lib/lua/5.4/dfle.so; do
        if readelf -d '$root/'\$f | grep NEEDED | grep -E 'gdal|netcdf|hdf5'; then
            echo \"\$f links them\"; exit 1
        fi
    done"

printf 'ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 10\n3 2 1\n3 2 1\n3 2 1\n' \
    > "$tmp/dem.asc"
cat > "$tmp/io.lua" <<LUA
local d = dfle.dem.read("$tmp/dem.asc")
assert(d.nx == 3 and d.ny == 3)
d:write_geotiff("$tmp/io.tif")
assert(dfle.dem.read("$tmp/io.tif").nx == 3)
local m = dfle.model{ channel = dfle.channel{ dx = 20 } }
m:run{ years = 200, record = { 100, 200 }, netcdf = "$tmp/io.nc" }
assert(io.open("$tmp/io.nc"), "no NetCDF file")
LUA
check "the installed command reads a DEM, writes GeoTIFF and NetCDF" \
    sh -c "rm -f '$tmp'/io.tif '$tmp'/io.nc && '$root/bin/dfle' -q '$tmp/io.lua'"
if command -v lua5.4 > /dev/null 2>&1; then
    check "so does the module in a stock lua5.4" sh -c "
        rm -f '$tmp'/io.tif '$tmp'/io.nc &&
        lua5.4 -e \"package.cpath = '$root/lib/lua/5.4/?.so'; dfle = require 'dfle'\" '$tmp/io.lua'"
fi

cat > "$tmp/dem.c" <<'PROG'
/* A DEM read through the static library, linked without GDAL. */
#include <stdio.h>
#include <dfle/dem.h>
int main(int argc, char **argv)
{
    dfle_dem *d;
    dfle_error err;
    if (argc < 2 || dfle_dem_read(argv[1], NULL, &d, &err) != DFLE_OK) {
        fprintf(stderr, "%s\n", argc < 2 ? "no path" : err.msg);
        return 1;
    }
    printf("%zu x %zu\n", dfle_dem_nx(d), dfle_dem_ny(d));
    dfle_dem_free(d);
    return 0;
}
PROG
check "a C program on the static library and GSL alone reads a DEM" sh -c "
    ${CC:-cc} -std=c11 -I'$root/include' '$tmp/dem.c' '$root/lib/libdfle.a' \
        \$(pkg-config --libs gsl) -lm -pthread -o '$tmp/dem' &&
    '$tmp/dem' '$tmp/dem.asc' | grep -qx '3 x 3'"

cat > "$tmp/prog.c" <<'PROG'
/* Eq. (26) from the installed library: S = (U/K)^(1/n) A^(-m/n). */
#include <math.h>
#include <stdio.h>
#include <dfle/fluvial.h>
int main(void)
{
    dfle_fluvial *fl;
    dfle_error err;
    double S;
    if (dfle_fluvial_new_stream_power(2e-5, 0.5, 1.0, &fl, &err) != DFLE_OK) {
        fprintf(stderr, "%s\n", err.msg);
        return 1;
    }
    S = dfle_fluvial_steady_slope(fl, 1e-4, 1e6);
    dfle_fluvial_free(fl);
    printf("S = %.6g\n", S);
    return fabs(S - 5e-3) < 1e-12 ? 0 : 1;
}
PROG
check "a C program builds and runs against the shared library" sh -c "
    ${CC:-cc} -std=c11 -I'$root/include' '$tmp/prog.c' -L'$root/lib' -ldfle -lm -o '$tmp/prog' &&
    LD_LIBRARY_PATH='$root/lib' '$tmp/prog' &&
    LD_LIBRARY_PATH='$root/lib' ldd '$tmp/prog' | grep -q 'libdfle.so.0 => $root/lib/libdfle.so.0'"

cat > "$tmp/host.c" <<'PROG'
/* A host embedding the binding runs a script through it. */
#include <lauxlib.h>
#include <lualib.h>
#include <dfle/lua.h>
int main(int argc, char **argv)
{
    lua_State *L = luaL_newstate();
    int st;
    luaL_openlibs(L);
    luaL_requiref(L, "dfle", luaopen_dfle, 1);
    lua_pop(L, 1);
    st = argc > 1 ? luaL_dofile(L, argv[1]) : 1;
    if (st != LUA_OK)
        fprintf(stderr, "%s\n", lua_tostring(L, -1));
    lua_close(L);
    return st != LUA_OK;
}
PROG
echo 'assert(dfle.model{ channel = dfle.channel{ dx = 20 } }:run_to_steady{}.converged)' > "$tmp/h.lua"
check "a Lua host builds against the installed binding and the shared library" sh -c "
    ${CC:-cc} -std=c11 -I'$root/include' \$(pkg-config --cflags lua5.4) '$tmp/host.c' \
        -L'$root/lib' -ldfle_lua \
        \$(PKG_CONFIG_PATH='$root/lib/pkgconfig' pkg-config --define-variable=prefix='$root' --libs dfle) \
        \$(pkg-config --libs lua5.4) -o '$tmp/host' &&
    LD_LIBRARY_PATH='$root/lib' '$tmp/host' '$tmp/h.lua'"

check "pkg-config describes the library" sh -c "
    PKG_CONFIG_PATH='$root/lib/pkgconfig' pkg-config --define-variable=prefix='$root' \
        --cflags --libs dfle | grep -F -- '-I$root/include' | grep -F -- '-ldfle'"

exit $fail
