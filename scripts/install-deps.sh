#!/bin/sh
# Installs the Debian packages dfle needs to build, test and plot.
# Used by the README's set-up command and by .ci/run, so the two never drift.
#   build:  gcc/clang, make, pkg-config, Lua 5.4 headers, GSL
#   lua5.4: the stand-alone interpreter, which loads the dfle module (build/dfle.so)
#   test:   cmocka, valgrind (make memcheck)
#   plots:  gnuplot (no X11 needed: the png and svg terminals)
#   DEMs:   GDAL (GeoTIFF, ESRI ASCII and every raster format GDAL reads)
#   series: the netCDF C library (landscape time series, CF conventions)
#   Python: Debian's python3 headers, numpy and pytest (make python; doc/python.md),
#   xarray and netCDF4 (the tests open dfle's NetCDF files as a user would),
#   pandas and matplotlib (doc/python.md's tutorial, which the tests run)
#   MPI:    OpenMPI, for `make mpi` / `make test-mpi` only (the plain build needs none)
set -eu

packages="build-essential pkg-config liblua5.4-dev lua5.4 libgsl-dev libcmocka-dev gnuplot-nox valgrind libgdal-dev libnetcdf-dev"
packages="$packages python3-dev python3-numpy python3-pytest python3-xarray python3-netcdf4 python3-pandas python3-matplotlib"
packages="$packages openmpi-bin libopenmpi-dev"

if [ "$(id -u)" -ne 0 ]; then
    sudo=sudo
else
    sudo=
fi

missing=
for p in $packages; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" \
        || missing="$missing $p"
done

if [ -n "$missing" ]; then
    echo "install-deps: installing:$missing"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends $missing
else
    echo "install-deps: all packages present"
fi
