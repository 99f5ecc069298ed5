/*
 * netcdf_lib.c - libnetcdf's function table, filled on first use
 * (netcdf_lib.h).
 *
 * The soname comes from extlib_names.h, which the build writes from the
 * library the linker takes for `pkg-config --libs netcdf` (Makefile,
 * scripts/extlib-names.sh): the one a dfle linked with netCDF would
 * load, whose header the table's types are checked against below.
 */
#define DFLE_NETCDF_LIB_TABLE 1

#include "base/netcdf_lib.h"

#include <stddef.h>

#include "base/extlib.h"
#include "extlib_names.h"

/* Every entry's type is the one <netcdf.h> declares.  _Generic does not
 * evaluate its operand, so this refers to nothing at link time. */
#define DFLE_NETCDF_CHECK(ret, name, params)                                                 \
    _Static_assert(_Generic(&name, ret(*) params: 1, default: 0),                           \
                   #name ": the type in DFLE_NETCDF_FNS differs from <netcdf.h>");
DFLE_NETCDF_FNS(DFLE_NETCDF_CHECK)
#undef DFLE_NETCDF_CHECK

dfle_netcdf_fns dfle_netcdf_fn;

#define DFLE_NETCDF_SYM(ret, name, params) {#name, offsetof(dfle_netcdf_fns, name)},
static const dfle_extlib_sym netcdf_syms[] = {DFLE_NETCDF_FNS(DFLE_NETCDF_SYM)};
#undef DFLE_NETCDF_SYM

static dfle_extlib netcdf = {
    .what = "netCDF",
    .soname = DFLE_NETCDF_SONAME,
    .package = DFLE_NETCDF_PACKAGE,
    .syms = netcdf_syms,
    .n = sizeof netcdf_syms / sizeof netcdf_syms[0],
    .table = &dfle_netcdf_fn,
    .lock = PTHREAD_MUTEX_INITIALIZER,
};

int dfle_netcdf_load(const char *who, dfle_error *err)
{
    return dfle_extlib_load(&netcdf, who, err);
}
