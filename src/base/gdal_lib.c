/*
 * gdal_lib.c - GDAL's function table, filled on first use (gdal_lib.h).
 *
 * The soname comes from extlib_names.h, which the build writes from the
 * library the linker takes for `pkg-config --libs gdal` (Makefile,
 * scripts/extlib-names.sh): the one a dfle linked with GDAL would load,
 * whose headers the table's types are checked against below.
 */
/* VSIStatL fills a struct stat64, which glibc declares only with this. */
#define _LARGEFILE64_SOURCE 1
#define DFLE_GDAL_LIB_TABLE 1

#include "base/gdal_lib.h"

#include <stddef.h>

#include "base/extlib.h"
#include "extlib_names.h"

/* Every entry's type is the one GDAL's header declares.  _Generic does
 * not evaluate its operand, so this refers to nothing at link time. */
#define DFLE_GDAL_CHECK(ret, name, params)                                                   \
    _Static_assert(_Generic(&name, ret(*) params: 1, default: 0),                           \
                   #name ": the type in DFLE_GDAL_FNS differs from GDAL's header");
DFLE_GDAL_FNS(DFLE_GDAL_CHECK)
#undef DFLE_GDAL_CHECK

dfle_gdal_fns dfle_gdal_fn;

#define DFLE_GDAL_SYM(ret, name, params) {#name, offsetof(dfle_gdal_fns, name)},
static const dfle_extlib_sym gdal_syms[] = {DFLE_GDAL_FNS(DFLE_GDAL_SYM)};
#undef DFLE_GDAL_SYM

/* Drivers register once per process (it is not safe to race). */
static void gdal_loaded(void)
{
    dfle_gdal_fn.GDALAllRegister();
}

static dfle_extlib gdal = {
    .what = "GDAL",
    .soname = DFLE_GDAL_SONAME,
    .package = DFLE_GDAL_PACKAGE,
    .syms = gdal_syms,
    .n = sizeof gdal_syms / sizeof gdal_syms[0],
    .table = &dfle_gdal_fn,
    .loaded = gdal_loaded,
    .lock = PTHREAD_MUTEX_INITIALIZER,
};

int dfle_gdal_load(const char *who, dfle_error *err)
{
    return dfle_extlib_load(&gdal, who, err);
}
