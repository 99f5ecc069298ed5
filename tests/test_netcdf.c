/*
 * test_netcdf.c - NetCDF files of profile records and sample tables
 * (netcdf.h), read back with the netCDF library.
 */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <netcdf.h>

#include "dfle_test.h"

#include "dfle/netcdf.h"

static char dir[] = "/tmp/dfle_test_netcdf_XXXXXX";
static char path[512];

static int setup(void **state)
{
    (void)state;
    return mkdtemp(dir) == NULL;
}

static int teardown(void **state)
{
    char cmd[600];
    (void)state;
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd);
}

static void assert_text_att(int ncid, int var, const char *name, const char *want)
{
    char buf[512] = "";
    size_t len = 0;
    assert_int_equal(nc_inq_attlen(ncid, var, name, &len), NC_NOERR);
    assert_true(len < sizeof buf);
    assert_int_equal(nc_get_att_text(ncid, var, name, buf), NC_NOERR);
    buf[len] = '\0';
    assert_string_equal(buf, want);
}

/* z(t, x) of three states of a four-node profile, with x, A, time. */
static void test_profiles(void **state)
{
    const double x[4] = {0, 5, 10, 15}, A[4] = {1e3, 2e3, 4e3, 8e3}, t[3] = {0, 10, 20};
    double z[12], back[12], fill, xr[4];
    const double *values[1] = {z};
    const dfle_nc_var var = {"z", "m", "elevation", NULL};
    const dfle_nc_attr attrs[1] = {{"history", "today: dfle run.lua"}};
    dfle_error err;
    int ncid, v, dims[2];
    size_t len;
    (void)state;
    for (int k = 0; k < 12; k++)
        z[k] = k == 5 ? NAN : 100.0 - k;
    snprintf(path, sizeof path, "%s/records.nc", dir);
    assert_ok(dfle_nc_write_profiles(path, 4, x, A, 3, t, 1, &var, values, 1, attrs, &err), &err);
    assert_int_equal(nc_open(path, NC_NOWRITE, &ncid), NC_NOERR);
    assert_int_equal(nc_inq_varid(ncid, "z", &v), NC_NOERR);
    assert_int_equal(nc_inq_vardimid(ncid, v, dims), NC_NOERR);
    assert_int_equal(nc_inq_dimlen(ncid, dims[0], &len), NC_NOERR);
    assert_int_equal(len, 3);
    assert_int_equal(nc_inq_dimlen(ncid, dims[1], &len), NC_NOERR);
    assert_int_equal(len, 4);
    assert_int_equal(nc_get_var_double(ncid, v, back), NC_NOERR);
    for (int k = 0; k < 12; k++)
        if (k == 5)
            assert_true(isnan(back[k]));
        else
            assert_close(back[k], z[k], 0, 0);
    assert_text_att(ncid, v, "units", "m");
    assert_text_att(ncid, v, "coordinates", "A");
    assert_int_equal(nc_get_att_double(ncid, v, "_FillValue", &fill), NC_NOERR);
    assert_true(isnan(fill));
    assert_int_equal(nc_inq_varid(ncid, "x", &v), NC_NOERR);
    assert_text_att(ncid, v, "units", "m");
    assert_int_equal(nc_get_var_double(ncid, v, xr), NC_NOERR);
    assert_close(xr[3], 15, 0, 0);
    assert_int_equal(nc_inq_varid(ncid, "time", &v), NC_NOERR);
    assert_text_att(ncid, v, "units", "year");
    assert_text_att(ncid, NC_GLOBAL, "Conventions", "CF-1.8");
    assert_text_att(ncid, NC_GLOBAL, "featureType", "profile");
    assert_text_att(ncid, NC_GLOBAL, "history", "today: dfle run.lua");
    assert_int_equal(nc_close(ncid), NC_NOERR);
}

/* Numbers with NaN for a failed row, text padded to the longest value. */
static void test_table(void **state)
{
    const double idx[3] = {1, 2, 3}, S[3] = {0.7, NAN, 0.5};
    const double *cols[2] = {idx, S};
    const dfle_nc_var vars[2] = {{"index", "1", "sample", NULL}, {"S_df", NULL, "output", NULL}};
    const char *status[3] = {"ok", "failed", "ok"}, *reason[3] = {"", "no convergence", NULL};
    const dfle_nc_text text[2] = {{"status", NULL, status}, {"reason", "why", reason}};
    char buf[3 * 14 + 1];
    double back[3];
    dfle_error err;
    int ncid, v;
    size_t len;
    (void)state;
    snprintf(path, sizeof path, "%s/ens.nc", dir);
    assert_ok(dfle_nc_write_table(path, "sample", 3, 2, vars, cols, 2, text, 0, NULL, &err), &err);
    assert_int_equal(nc_open(path, NC_NOWRITE, &ncid), NC_NOERR);
    assert_int_equal(nc_inq_varid(ncid, "S_df", &v), NC_NOERR);
    assert_int_equal(nc_get_var_double(ncid, v, back), NC_NOERR);
    assert_close(back[0], 0.7, 0, 0);
    assert_true(isnan(back[1]));
    /* No units claimed where none are known. */
    assert_int_equal(nc_inq_attlen(ncid, v, "units", &len), NC_ENOTATT);
    assert_int_equal(nc_inq_varid(ncid, "reason", &v), NC_NOERR);
    memset(buf, 0, sizeof buf);
    assert_int_equal(nc_get_var_text(ncid, v, buf), NC_NOERR);
    assert_int_equal(strlen("no convergence"), 14);
    assert_memory_equal(buf + 14, "no convergence", 14);
    assert_int_equal(buf[0], '\0');
    assert_int_equal(nc_close(ncid), NC_NOERR);
}

/* A file that cannot be written is an error naming it; nothing is left
 * behind, and an existing file survives a failed write whole. */
static void test_errors(void **state)
{
    const double t[1] = {0}, x[1] = {0}, A[1] = {1}, z[1] = {1};
    const double *values[1] = {z};
    const dfle_nc_var var = {"z", "m", NULL, NULL};
    dfle_error err;
    (void)state;
    assert_int_equal(dfle_nc_write_profiles("/nonexistent/dir/r.nc", 1, x, A, 1, t, 1, &var,
                                            values, 0, NULL, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "/nonexistent/dir/r.nc");
    assert_int_equal(dfle_nc_write_profiles(path, 0, x, A, 1, t, 1, &var, values, 0, NULL, &err),
                     DFLE_EINVAL);
    /* a bad variable name fails after the file was begun */
    {
        const dfle_nc_var bad = {"z/bad", "m", NULL, NULL};
        char cmd[600];
        snprintf(path, sizeof path, "%s/ens.nc", dir);
        assert_int_not_equal(dfle_nc_write_profiles(path, 1, x, A, 1, t, 1, &bad, values, 0,
                                                    NULL, &err), DFLE_OK);
        assert_msg_contains(err.msg, "z/bad");
        snprintf(cmd, sizeof cmd, "test $(ls -A '%s' | wc -l) -eq 2", dir);
        assert_int_equal(system(cmd), 0); /* records.nc and ens.nc, no temporary file */
        {
            int ncid, v;
            assert_int_equal(nc_open(path, NC_NOWRITE, &ncid), NC_NOERR);
            assert_int_equal(nc_inq_varid(ncid, "S_df", &v), NC_NOERR); /* the old file, whole */
            nc_close(ncid);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_profiles),
        cmocka_unit_test(test_table),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
