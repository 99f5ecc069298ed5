/*
 * test_extlib.c - GDAL and libnetcdf, loaded on first use
 * (src/base/extlib.h, gdal_lib.h, netcdf_lib.h).
 *
 * Built twice (Makefile).  As test_extlib, with the library's loaders:
 * a process maps neither library until a call needs it, and the loader
 * says why a library or one of its functions cannot be had.  As
 * test_extlib_missing (DFLE_TEST_EXTLIB_MISSING), whose loaders are
 * compiled for sonames no system has: every entry point that needs GDAL
 * or netCDF fails with a message naming the library and what to
 * install, writes no file, and the rest of dfle, Lua binding included,
 * goes on working.
 */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "dfle_test.h"

#include <lauxlib.h>
#include <lua.h>
#include <lualib.h>

#include "base/extlib.h"
#include "dfle/dem.h"
#include "dfle/lua.h"
#include "dfle/netcdf.h"
#include "dfle/raster.h"

static char dir[] = "/tmp/dfle_test_extlib_XXXXXX";
static char asc[512];

/* A scratch directory holding a 3 x 3 ESRI ASCII grid GDAL reads. */
static int setup(void **state)
{
    FILE *f;
    (void)state;
    if (mkdtemp(dir) == NULL)
        return -1;
    snprintf(asc, sizeof asc, "%s/dem.asc", dir);
    if ((f = fopen(asc, "w")) == NULL)
        return -1;
    fputs("ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 10\n"
          "3 2 1\n3 2 1\n3 2 1\n", f);
    return fclose(f) == 0 ? 0 : -1;
}

static int teardown(void **state)
{
    char cmd[600];
    (void)state;
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd);
}

static void path_in_dir(char *buf, size_t len, const char *name)
{
    snprintf(buf, len, "%s/%s", dir, name);
}

/* A one-row table: the smallest file dfle_nc_write_table writes. */
static int write_table(const char *path, dfle_error *err)
{
    const double v = 1.5, *values[1] = {&v};
    const dfle_nc_var col = {"a", "m", "a column", NULL, NULL};
    return dfle_nc_write_table(path, "sample", 1, 1, &col, values, 0, NULL, 0, NULL, err);
}

#ifndef DFLE_TEST_EXTLIB_MISSING

/* Whether this process has mapped a file whose name contains `name`. */
static int mapped(const char *name)
{
    FILE *f = fopen("/proc/self/maps", "r");
    char line[4096];
    int found = 0;
    assert_non_null(f);
    while (!found && fgets(line, sizeof line, f) != NULL)
        found = strstr(line, name) != NULL;
    fclose(f);
    return found;
}

static void loads_each_library_on_first_use(void **state)
{
    char nc[600];
    dfle_error err;
    dfle_dem *d = NULL;
    (void)state;
    assert_false(mapped("libgdal"));
    assert_false(mapped("libnetcdf"));
    path_in_dir(nc, sizeof nc, "table.nc");
    assert_ok(write_table(nc, &err), &err);
    assert_true(mapped("libnetcdf"));
    assert_false(mapped("libgdal"));
    assert_ok(dfle_dem_read(asc, NULL, &d, &err), &err);
    assert_true(mapped("libgdal"));
    assert_int_equal(dfle_dem_nx(d), 3);
    assert_close(dfle_dem_z(d)[0], 3, 0, 0);
    dfle_dem_free(d);
}

/* A library that is not there: dlerror's words and what to install. */
static void says_which_library_is_missing(void **state)
{
    static const dfle_extlib_sym syms[] = {{"cos", 0}};
    void (*table[1])(void) = {NULL};
    dfle_extlib lib = {.what = "Thing", .soname = "libdfle-no-such-thing.so.7",
                       .package = "libthing7", .syms = syms, .n = 1, .table = table,
                       .lock = PTHREAD_MUTEX_INITIALIZER};
    dfle_error err;
    (void)state;
    for (int k = 0; k < 2; k++) { /* one attempt; every call says why */
        assert_int_equal(dfle_extlib_load(&lib, "thing.read", &err), DFLE_EEXTERNAL);
        assert_msg_contains(err.msg, "thing.read: Thing could not be loaded: "
                                     "libdfle-no-such-thing.so.7: cannot open shared object file");
        assert_msg_contains(err.msg, "; install libthing7, or rebuild dfle against the Thing "
                                     "that is installed (this build uses libdfle-no-such-thing.so.7)");
    }
    lib.package = ""; /* not built on Debian: no package name */
    assert_int_equal(dfle_extlib_load(&lib, "thing.read", &err), DFLE_EEXTERNAL);
    assert_msg_contains(err.msg, "install the package that provides libdfle-no-such-thing.so.7");
    assert_null(table[0]);
}

static int loaded_calls;
static void count_loaded(void) { loaded_calls++; }

/* A library without a function dfle calls (another version). */
static void says_which_function_is_missing(void **state)
{
    static const dfle_extlib_sym syms[] = {
        {"cos", 0 * sizeof(void (*)(void))},
        {"dfle_no_such_function", 1 * sizeof(void (*)(void))},
    };
    double (*table[2])(double) = {NULL, NULL};
    dfle_extlib lib = {.what = "libm", .soname = "libm.so.6", .package = "libc6", .syms = syms,
                       .n = 2, .table = table, .loaded = count_loaded,
                       .lock = PTHREAD_MUTEX_INITIALIZER};
    dfle_extlib lib1 = lib; /* the same library, asked only for cos */
    dfle_error err;
    (void)state;
    assert_int_equal(dfle_extlib_load(&lib, "m", &err), DFLE_EEXTERNAL);
    assert_msg_contains(err.msg, "m: libm could not be loaded: ");
    assert_msg_contains(err.msg, "dfle_no_such_function");
    assert_int_equal(loaded_calls, 0);
    lib1.n = 1;
    for (int k = 0; k < 2; k++)
        assert_int_equal(dfle_extlib_load(&lib1, "m", &err), DFLE_OK);
    assert_int_equal(loaded_calls, 1);
    assert_non_null(table[0]);
    assert_close(table[0](0.0), 1.0, 0, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(loads_each_library_on_first_use),
        cmocka_unit_test(says_which_library_is_missing),
        cmocka_unit_test(says_which_function_is_missing),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}

#else /* DFLE_TEST_EXTLIB_MISSING: the loaders look for libraries that are not there */

/* No file and no temporary file left in the scratch directory but the DEM. */
static void assert_dir_holds_only_the_dem(void)
{
    char cmd[600];
    snprintf(cmd, sizeof cmd, "test \"$(ls -A '%s')\" = dem.asc", dir);
    assert_int_equal(system(cmd), 0);
}

static void dem_read_says_gdal_is_missing(void **state)
{
    dfle_error err;
    dfle_dem *d = (dfle_dem *)&err; /* set to NULL on failure */
    (void)state;
    for (int k = 0; k < 2; k++) { /* every call, not only the first */
        assert_int_equal(dfle_dem_read(asc, NULL, &d, &err), DFLE_EEXTERNAL);
        assert_null(d);
        assert_msg_contains(err.msg, "dem.read: GDAL could not be loaded: "
                                     "libdfle-test-missing-gdal.so.0: cannot open shared object");
        assert_msg_contains(err.msg, "; install ");
    }
}

static void geotiff_says_gdal_is_missing(void **state)
{
    const double z[4] = {1, 2, 3, 4};
    const dfle_raster_band bands[1] = {{z, "z", "m"}};
    const dfle_raster_geo geo = {0, 20, 10, 10, NULL};
    char tif[600];
    dfle_error err;
    (void)state;
    path_in_dir(tif, sizeof tif, "out.tif");
    assert_int_equal(dfle_raster_write_geotiff(tif, 2, 2, &geo, 1, bands, NULL, &err),
                     DFLE_EEXTERNAL);
    assert_msg_contains(err.msg, "raster: GDAL could not be loaded: "
                                 "libdfle-test-missing-gdal.so.0");
    assert_dir_holds_only_the_dem();
}

static void netcdf_says_netcdf_is_missing(void **state)
{
    const double x[2] = {0, 5}, A[2] = {1e3, 2e3}, t[1] = {0}, z[2] = {2, 1};
    const double *values[1] = {z};
    const dfle_nc_var var = {"z", "m", "elevation", NULL, NULL};
    const dfle_raster_geo geo = {0, 20, 10, 10, NULL};
    const char *want = "netcdf: netCDF could not be loaded: libdfle-test-missing-netcdf.so.0";
    char nc[600];
    dfle_error err;
    dfle_nc *series = (dfle_nc *)&err; /* set to NULL on failure */
    (void)state;
    path_in_dir(nc, sizeof nc, "out.nc");
    assert_int_equal(write_table(nc, &err), DFLE_EEXTERNAL);
    assert_msg_contains(err.msg, want);
    assert_int_equal(dfle_nc_write_profiles(nc, 2, x, A, 1, t, 1, &var, values, NULL, &err),
                     DFLE_EEXTERNAL);
    assert_msg_contains(err.msg, want);
    assert_int_equal(dfle_nc_create(nc, 2, 2, &geo, 1, &var, NULL, &series, &err),
                     DFLE_EEXTERNAL);
    assert_null(series);
    assert_msg_contains(err.msg, want);
    assert_dir_holds_only_the_dem();
}

/* Runs `code` in a fresh state with the dfle module; returns its error
 * message (or "ok") in buf. */
static void run_lua(const char *code, char *buf, size_t len)
{
    lua_State *L = luaL_newstate();
    assert_non_null(L);
    luaL_openlibs(L);
    luaL_requiref(L, "dfle", luaopen_dfle, 1);
    lua_pop(L, 1);
    if (luaL_dostring(L, code) != LUA_OK)
        snprintf(buf, len, "%s", lua_tostring(L, -1));
    else
        snprintf(buf, len, "ok");
    lua_close(L);
}

/* What a script sees: the call raises a clear error; the script goes on. */
static void scripts_get_the_message(void **state)
{
    char code[1400], msg[1024];
    (void)state;
    snprintf(code, sizeof code,
             "local ok, e = pcall(dfle.dem.read, '%s')\n"
             "assert(not ok)\n"
             "local m = dfle.model{ channel = dfle.channel{ dx = 20 } }\n"
             "local ok2, e2 = pcall(m.run, m, { years = 200, record = { 100, 200 },\n"
             "                                  netcdf = '%s/run.nc' })\n"
             "assert(not ok2)\n"
             "assert(m:run{ years = 100 }.reason == 'time', 'the model runs on')\n"
             "error(e .. '\\n' .. e2, 0)\n",
             asc, dir);
    run_lua(code, msg, sizeof msg);
    assert_msg_contains(msg, "dfle.dem.read: GDAL could not be loaded: "
                             "libdfle-test-missing-gdal.so.0: cannot open shared object file");
    assert_msg_contains(msg, "\n");
    assert_msg_contains(strchr(msg, '\n'), "netCDF could not be loaded: "
                                           "libdfle-test-missing-netcdf.so.0");
    assert_dir_holds_only_the_dem();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(dem_read_says_gdal_is_missing),
        cmocka_unit_test(geotiff_says_gdal_is_missing),
        cmocka_unit_test(netcdf_says_netcdf_is_missing),
        cmocka_unit_test(scripts_get_the_message),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}

#endif
