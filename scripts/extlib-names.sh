#!/bin/sh
# extlib-names.sh CC PKG_CONFIG: writes to stdout the C header that names
# the shared libraries dfle loads on first use (src/base/extlib.h): for
# GDAL and netCDF, the soname of the library the linker would take for
# `pkg-config --libs <package>` (what a linked program would record), and
# the Debian package that provides it, for the message when it is missing.
# Run by make for every build; the header is replaced only if it changes.
set -eu
CC=${1:-cc}
PKG_CONFIG=${2:-pkg-config}

die() { echo "extlib-names: $*" >&2; exit 1; }

# The file the linker takes for the package's first -l: the -L
# directories pkg-config gives, then the compiler's own search path.
lib_file() {
    name=$($PKG_CONFIG --libs-only-l "$1" | tr ' ' '\n' | sed -n 's/^-l//p' | head -n 1)
    [ -n "$name" ] || die "pkg-config names no library for $1 (is its -dev package installed?)"
    for dir in $($PKG_CONFIG --libs-only-L "$1" | tr ' ' '\n' | sed -n 's/^-L//p'); do
        if [ -e "$dir/lib$name.so" ]; then
            echo "$dir/lib$name.so"
            return
        fi
    done
    f=$($CC -print-file-name="lib$name.so")
    [ -e "$f" ] || die "no lib$name.so for $1 where the linker looks"
    echo "$f"
}

soname() {
    s=$(readelf -d "$1" 2> /dev/null | sed -n 's/.*(SONAME).*\[\(.*\)\].*/\1/p')
    [ -n "$s" ] || s=$(objdump -p "$1" 2> /dev/null | awk '$1 == "SONAME" { print $2 }')
    [ -n "$s" ] || die "$1 has no soname (readelf and objdump, from binutils, read it)"
    echo "$s"
}

# The Debian package holding dir/soname, or nothing off Debian.
package() {
    f=$(readlink -f "$1") || f=$1
    dpkg -S "$f" 2> /dev/null | sed -n '1s/^\([^:,]*\).*/\1/p' || true
}

echo "/* Written by scripts/extlib-names.sh for this build; do not edit. */"
for spec in GDAL:gdal NETCDF:netcdf; do
    macro=${spec%%:*}
    pkg=${spec#*:}
    f=$(lib_file "$pkg")
    so=$(soname "$f")
    dir=$(dirname "$(readlink -f "$f")")
    deb=$(package "$dir/$so")
    echo "#ifndef DFLE_${macro}_SONAME"
    echo "#define DFLE_${macro}_SONAME \"$so\""
    echo "#endif"
    echo "#ifndef DFLE_${macro}_PACKAGE"
    echo "#define DFLE_${macro}_PACKAGE \"$deb\""
    echo "#endif"
done
