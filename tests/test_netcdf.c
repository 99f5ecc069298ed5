/*
 * test_netcdf.c - the NetCDF files of dfle (netcdf.h, raster.h), read
 * back with the netCDF library: profile records, sample tables and grid
 * series, their CF attributes (cf_check.h) and provenance, the crop to
 * the data, flags, float32, the grid mapping of a CRS with longitude and
 * latitude, the time coordinate, targets that are not regular files
 * (left in place), a record read back onto a grid; and every file the
 * Lua API writes (m:run, ls:run, ens:write_netcdf) through the same
 * checks.
 */
#define _XOPEN_SOURCE 700 /* mkdtemp, mknod */
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/types.h>
#include <unistd.h>

#include <netcdf.h>

#include "cf_check.h"
#include "dfle_test.h"
#include "scratch_dir.h"
#include "lua_snippet.h"

#include "dfle/crs.h"
#include "dfle/netcdf.h"
#include "dfle/raster.h"
#include "dfle/record.h"

static char dir[] = "/tmp/dfle_test_netcdf_XXXXXX";
static char path[512];

static int setup(void **state)
{
    (void)state;
    return scratch_dir_make(dir);
}

static int teardown(void **state)
{
    (void)state;
    return scratch_dir_remove(dir);
}

static void in_dir(char *buf, size_t cap, const char *name)
{
    scratch_path(buf, cap, dir, name);
}

static void assert_text_att(int ncid, int var, const char *name, const char *want)
{
    char *s = cf_text_att(ncid, var, name);
    if (s == NULL) {
        print_error("no text attribute %s\n", name);
        fail();
    }
    assert_string_equal(s, want);
    free(s);
}

static double num_att(int ncid, int var, const char *name, nc_type want_type)
{
    double v = NAN;
    nc_type t;
    size_t len;
    assert_int_equal(nc_inq_att(ncid, var, name, &t, &len), NC_NOERR);
    assert_int_equal(t, want_type);
    assert_int_equal(len, 1);
    assert_int_equal(nc_get_att_double(ncid, var, name, &v), NC_NOERR);
    return v;
}

/* A record like the Lua binding's: stamp, command, two components. */
static dfle_record *test_record(void)
{
    dfle_record *rec;
    dfle_error err;
    const char *argv[] = {"dfle", "run it.lua", "--quick"};
    const dfle_param p[] = {{"M0", 3000, "m^(3-2 gamma)", 0}, {"tau_y", 300, "Pa", 0},
                            {"rho_b", 1800, "kg/m^3", 0}};
    assert_ok(dfle_record_new(&rec, &err), &err);
    dfle_record_stamp(rec);
    dfle_record_list(rec, "command", argv, 3);
    dfle_record_section(rec, "router", "empirical");
    dfle_record_params(rec, p, 3);
    dfle_record_section(rec, "landscape", NULL);
    dfle_record_param_number(rec, "U", 5e-4, "m/yr");
    dfle_record_param_bool(rec, "cap_channels", 1);
    dfle_record_param_text(rec, "hillslope", "threshold");
    return rec;
}

/* ---------------------------------------------------------------- */
/* Profiles and tables                                              */
/* ---------------------------------------------------------------- */

/* z(t, x) of three states of a four-node profile, with x, A, time, the
 * record's provenance, float32 and deflate. */
static void test_profiles(void **state)
{
    const double x[4] = {0, 5, 10, 15}, A[4] = {1e3, 2e3, 4e3, 8e3}, t[3] = {0, 10, 20};
    double z[12], back[12], fill, xr[4];
    const double *values[1] = {z};
    const dfle_nc_var var = {"z", "m", "elevation", NULL, NULL};
    dfle_record *rec = test_record();
    dfle_nc_opts o;
    dfle_error err;
    int ncid, v, dims[2], shuffle, deflate, level;
    size_t len;
    nc_type type;
    (void)state;
    for (int k = 0; k < 12; k++)
        z[k] = k == 5 ? NAN : 100.0 - k;
    in_dir(path, sizeof path, "records.nc");
    dfle_nc_opts_default(&o);
    o.provenance = rec;
    o.float32 = 1;
    o.title = "profiles";
    assert_ok(dfle_nc_write_profiles(path, 4, x, A, 3, t, 1, &var, values, &o, &err), &err);
    cf_check_file(path);
    assert_int_equal(nc_open(path, NC_NOWRITE, &ncid), NC_NOERR);
    assert_int_equal(nc_inq_varid(ncid, "z", &v), NC_NOERR);
    assert_int_equal(nc_inq_vartype(ncid, v, &type), NC_NOERR);
    assert_int_equal(type, NC_FLOAT);
    assert_int_equal(nc_inq_var_deflate(ncid, v, &shuffle, &deflate, &level), NC_NOERR);
    assert_true(deflate && level == 4);
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
            assert_close(back[k], z[k], 0, 0); /* whole numbers: exact in float */
    assert_text_att(ncid, v, "units", "m");
    assert_text_att(ncid, v, "coordinates", "A");
    assert_int_equal(nc_get_att_double(ncid, v, "_FillValue", &fill), NC_NOERR);
    assert_true(isnan(fill));
    assert_int_equal(nc_inq_varid(ncid, "A", &v), NC_NOERR);
    assert_text_att(ncid, v, "units", "m2");
    assert_int_equal(nc_inq_varid(ncid, "x", &v), NC_NOERR);
    assert_text_att(ncid, v, "units", "m");
    assert_int_equal(nc_get_var_double(ncid, v, xr), NC_NOERR);
    assert_close(xr[3], 15, 0, 0);
    assert_int_equal(nc_inq_varid(ncid, "time", &v), NC_NOERR);
    assert_text_att(ncid, v, "units", "common_years since 0000-01-01 00:00:00");
    assert_text_att(ncid, v, "calendar", "noleap");
    assert_text_att(ncid, v, "standard_name", "time");
    assert_text_att(ncid, NC_GLOBAL, "title", "profiles");
    /* Provenance: CF's history from the record, numbers as numbers. */
    {
        char *h = cf_text_att(ncid, NC_GLOBAL, "history");
        assert_non_null(h);
        assert_msg_contains(h, ": dfle 'run it.lua' --quick");
        free(h);
    }
    assert_text_att(ncid, NC_GLOBAL, "router", "empirical");
    assert_close(num_att(ncid, NC_GLOBAL, "router_M0", NC_DOUBLE), 3000, 0, 0);
    assert_close(num_att(ncid, NC_GLOBAL, "landscape_U", NC_DOUBLE), 5e-4, 0, 0);
    assert_close(num_att(ncid, NC_GLOBAL, "landscape_cap_channels", NC_INT), 1, 0, 0);
    assert_text_att(ncid, NC_GLOBAL, "landscape_hillslope", "threshold");
    assert_text_att(ncid, NC_GLOBAL, "router_units",
                    "M0=m^(3-2 gamma), tau_y=Pa, rho_b=kg/m3");
    assert_text_att(ncid, NC_GLOBAL, "dfle_version", DFLE_VERSION);
    assert_int_equal(nc_close(ncid), NC_NOERR);
    dfle_record_free(rec);
}

/* Numbers with NaN for a failed row, text padded to the longest value,
 * units UDUNITS reads, and none where UDUNITS has no syntax for them. */
static void test_table(void **state)
{
    const double idx[3] = {1, 2, 3}, S[3] = {0.7, NAN, 0.5}, ke[3] = {1e-14, 2e-14, 3e-14};
    const double *cols[4] = {idx, S, ke, S};
    const dfle_nc_var vars[4] = {{"index", "1", "sample", NULL, NULL},
                                 {"S_df", NULL, "output", NULL, NULL},
                                 {"k_e", "m^2.5 s^2 kg^-1.5", "input", NULL, NULL},
                                 {"A_df", "m^2", "output", NULL, NULL}};
    const char *status[3] = {"ok", "failed", "ok"}, *reason[3] = {"", "no convergence", NULL};
    const dfle_nc_text text[2] = {{"status", NULL, status}, {"reason", "why", reason}};
    const dfle_nc_attr attrs[1] = {{"history", "today: dfle run.lua"}};
    char buf[3 * 14 + 1];
    double back[3];
    dfle_error err;
    int ncid, v;
    size_t len;
    (void)state;
    in_dir(path, sizeof path, "ens.nc");
    assert_ok(dfle_nc_write_table(path, "sample", 3, 4, vars, cols, 2, text, 1, attrs, &err),
              &err);
    cf_check_file(path);
    assert_int_equal(nc_open(path, NC_NOWRITE, &ncid), NC_NOERR);
    assert_int_equal(nc_inq_varid(ncid, "S_df", &v), NC_NOERR);
    assert_int_equal(nc_get_var_double(ncid, v, back), NC_NOERR);
    assert_close(back[0], 0.7, 0, 0);
    assert_true(isnan(back[1]));
    /* No units claimed where none are known. */
    assert_int_equal(nc_inq_attlen(ncid, v, "units", &len), NC_ENOTATT);
    /* k_e's unit has a fractional power: not as `units` ("m2.5" would
     * be read as 0.5 m2), as text beside it. */
    assert_int_equal(nc_inq_varid(ncid, "k_e", &v), NC_NOERR);
    assert_int_equal(nc_inq_attlen(ncid, v, "units", &len), NC_ENOTATT);
    assert_text_att(ncid, v, "dfle_units", "m^2.5 s^2 kg^-1.5");
    assert_int_equal(nc_inq_varid(ncid, "A_df", &v), NC_NOERR);
    assert_text_att(ncid, v, "units", "m2");
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
    const dfle_nc_var var = {"z", "m", NULL, NULL, NULL};
    dfle_error err;
    (void)state;
    assert_int_equal(dfle_nc_write_profiles("/nonexistent/dir/r.nc", 1, x, A, 1, t, 1, &var,
                                            values, NULL, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "/nonexistent/dir/r.nc");
    assert_int_equal(dfle_nc_write_profiles(path, 0, x, A, 1, t, 1, &var, values, NULL, &err),
                     DFLE_EINVAL);
    /* a bad variable name fails after the file was begun */
    {
        const dfle_nc_var bad = {"z/bad", "m", NULL, NULL, NULL};
        char cmd[600];
        in_dir(path, sizeof path, "ens.nc");
        assert_int_not_equal(dfle_nc_write_profiles(path, 1, x, A, 1, t, 1, &bad, values, NULL,
                                                    &err), DFLE_OK);
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

/* ---------------------------------------------------------------- */
/* Grids                                                            */
/* ---------------------------------------------------------------- */

/* A 5 x 4 grid whose data (z) fill columns 1..3 of rows 1..2: the file
 * holds that window, flags as bytes. */
static void test_grid_crop_and_flags(void **state)
{
    enum { NX = 5, NY = 4 };
    double z[NX * NY], ch[NX * NY], w[6], x[3], y[2];
    const double *vals[2] = {z, ch};
    const dfle_nc_var vars[2] = {{"z", "m", "elevation", "surface_altitude", NULL},
                                 {"channel", NULL, "cell kind", NULL, "hillslope channel head"}};
    const dfle_raster_geo g = {100, 2000, 10, 20, NULL};
    dfle_nc_opts o;
    dfle_nc *nc;
    dfle_error err;
    signed char b[6], fv[3];
    int id, vid;
    size_t len, c0, r0, wx, wy, start[3] = {1, 0, 0}, count[3] = {1, 2, 3};
    nc_type type;
    (void)state;
    for (int k = 0; k < NX * NY; k++) {
        int r = k / NX, c = k % NX;
        int in = r >= 1 && r <= 2 && c >= 1 && c <= 3 && k != 2 * NX + 2;
        z[k] = in ? 100.0 + k : NAN;
        ch[k] = in ? (double)(k % 3) : NAN;
    }
    z[2 * NX + 2] = NAN; /* a hole inside the box stays NaN */
    in_dir(path, sizeof path, "grid.nc");
    dfle_nc_opts_default(&o);
    o.mask = z;
    assert_ok(dfle_nc_create(path, NX, NY, &g, 2, vars, &o, &nc, &err), &err);
    dfle_nc_window(nc, &c0, &r0, &wx, &wy);
    assert_int_equal(c0, 1), assert_int_equal(r0, 1);
    assert_int_equal(wx, 3), assert_int_equal(wy, 2);
    assert_ok(dfle_nc_append(nc, 0.0, vals, &err), &err);
    z[NX + 1] = 7;
    assert_ok(dfle_nc_append(nc, 500.0, vals, &err), &err);
    assert_ok(dfle_nc_close(nc, &err), &err);
    cf_check_file(path);
    assert_int_equal(nc_open(path, NC_NOWRITE, &id), NC_NOERR);
    assert_int_equal(nc_inq_dimid(id, "time", &vid), NC_NOERR);
    assert_int_equal(nc_inq_dimlen(id, vid, &len), NC_NOERR);
    assert_int_equal(len, 2);
    assert_int_equal(nc_inq_varid(id, "x", &vid), NC_NOERR);
    assert_int_equal(nc_get_var_double(id, vid, x), NC_NOERR);
    assert_close(x[0], 100 + 1.5 * 10, 0, 0); /* column 1's centre */
    assert_close(x[2], 100 + 3.5 * 10, 0, 0);
    assert_int_equal(nc_inq_varid(id, "y", &vid), NC_NOERR);
    assert_int_equal(nc_get_var_double(id, vid, y), NC_NOERR);
    assert_close(y[0], 2000 - 1.5 * 20, 0, 0);
    assert_int_equal(nc_inq_varid(id, "z", &vid), NC_NOERR);
    assert_int_equal(nc_get_vara_double(id, vid, start, count, w), NC_NOERR);
    assert_close(w[0], 7, 0, 0);
    assert_close(w[1], 100 + NX + 2, 0, 0);
    assert_true(isnan(w[4])); /* the hole */
    assert_int_equal(nc_inq_varid(id, "channel", &vid), NC_NOERR);
    assert_int_equal(nc_inq_vartype(id, vid, &type), NC_NOERR);
    assert_int_equal(type, NC_BYTE);
    assert_int_equal(nc_get_vara_schar(id, vid, start, count, b), NC_NOERR);
    assert_int_equal(b[0], (NX + 1) % 3);
    assert_int_equal(b[4], -1); /* NoData: the _FillValue */
    assert_int_equal(nc_get_att_schar(id, vid, "flag_values", fv), NC_NOERR);
    assert_int_equal(fv[0], 0), assert_int_equal(fv[2], 2);
    assert_text_att(id, vid, "flag_meanings", "hillslope channel head");
    assert_int_equal(nc_inq_varid(id, "time", &vid), NC_NOERR);
    assert_text_att(id, vid, "units", "common_years since 0000-01-01 00:00:00");
    nc_close(id);
}

/* UTM zone 11N: CF's transverse_mercator with the zone's parameters, and
 * lat/lon: on the central meridian (E = 500000 m) the longitude is -117
 * exactly, and near the equator the latitude is N / (k0 a (1 - e^2))
 * radians (the meridian arc to first order; the next term is 1e-12 of
 * it at 35 m). */
static void test_grid_crs(void **state)
{
    const double a = 6378137.0, f = 1 / 298.257223563, e2 = f * (2 - f), k0 = 0.9996;
    double z[4] = {1, 2, 3, 4}, lat[4], lon[4], v;
    const double *vals[1] = {z};
    const dfle_nc_var var = {"z", "m", "elevation", NULL, NULL};
    /* Cell centres at E = 500000, 500010 and N = 25, -5. */
    dfle_raster_geo gw = {499995, 40, 10, 30, NULL};
    char wkt[4096];
    dfle_nc *nc;
    dfle_error err;
    int id, vid;
    (void)state;
    assert_ok(dfle_crs_from_text("EPSG:32611", "test", 1, wkt, sizeof wkt, NULL, &err), &err);
    gw.crs_wkt = wkt;
    in_dir(path, sizeof path, "utm.nc");
    assert_ok(dfle_nc_create(path, 2, 2, &gw, 1, &var, NULL, &nc, &err), &err);
    assert_ok(dfle_nc_append(nc, 0.0, vals, &err), &err);
    assert_ok(dfle_nc_close(nc, &err), &err);
    cf_check_file(path);
    assert_int_equal(nc_open(path, NC_NOWRITE, &id), NC_NOERR);
    assert_int_equal(nc_inq_varid(id, "crs", &vid), NC_NOERR);
    assert_text_att(id, vid, "grid_mapping_name", "transverse_mercator");
    assert_int_equal(nc_get_att_double(id, vid, "longitude_of_central_meridian", &v), NC_NOERR);
    assert_close(v, -117, 0, 0);
    assert_int_equal(nc_get_att_double(id, vid, "scale_factor_at_central_meridian", &v),
                     NC_NOERR);
    assert_close(v, k0, 0, 0);
    assert_int_equal(nc_get_att_double(id, vid, "false_easting", &v), NC_NOERR);
    assert_close(v, 500000, 0, 0);
    assert_int_equal(nc_get_att_double(id, vid, "semi_major_axis", &v), NC_NOERR);
    assert_close(v, a, 0, 0);
    assert_int_equal(nc_get_att_double(id, vid, "inverse_flattening", &v), NC_NOERR);
    assert_close(v, 1 / f, 1e-15, 0);
    assert_text_att(id, vid, "projected_crs_name", "WGS 84 / UTM zone 11N");
    {
        char *w = cf_text_att(id, vid, "crs_wkt");
        assert_non_null(w);
        assert_string_equal(w, wkt);
        free(w);
    }
    assert_int_equal(nc_inq_varid(id, "z", &vid), NC_NOERR);
    assert_text_att(id, vid, "grid_mapping", "crs");
    assert_text_att(id, vid, "coordinates", "lat lon");
    assert_int_equal(nc_inq_varid(id, "lat", &vid), NC_NOERR);
    assert_text_att(id, vid, "units", "degrees_north");
    assert_int_equal(nc_get_var_double(id, vid, lat), NC_NOERR);
    assert_int_equal(nc_inq_varid(id, "lon", &vid), NC_NOERR);
    assert_text_att(id, vid, "standard_name", "longitude");
    assert_int_equal(nc_get_var_double(id, vid, lon), NC_NOERR);
    nc_close(id);
    assert_close(lon[0], -117, 0, 1e-12);  /* row 0, column 0: E = 500000 */
    assert_close(lon[2], -117, 0, 1e-12);
    assert_true(lon[1] > -117);            /* east of the meridian */
    assert_close(lat[0], 25.0 / (k0 * a * (1 - e2)) * 180 / M_PI, 1e-9, 0); /* N = 25 */
    assert_close(lat[2], -5.0 / (k0 * a * (1 - e2)) * 180 / M_PI, 1e-9, 0); /* N = -5 */
}

/* Model time beyond what a date can count (cftime: 292,471 years) is a
 * plain duration; within it, years since year 0. */
static void test_grid_long_time(void **state)
{
    double z[1] = {1};
    const double *vals[1] = {z};
    const dfle_nc_var var = {"z", "m", NULL, NULL, NULL};
    const dfle_raster_geo g = {0, 10, 10, 10, NULL};
    dfle_nc *nc;
    dfle_error err;
    int id, vid;
    size_t len;
    (void)state;
    in_dir(path, sizeof path, "long.nc");
    assert_ok(dfle_nc_create(path, 1, 1, &g, 1, &var, NULL, &nc, &err), &err);
    assert_ok(dfle_nc_append(nc, 0.0, vals, &err), &err);
    assert_ok(dfle_nc_append(nc, 1e7, vals, &err), &err);
    assert_ok(dfle_nc_close(nc, &err), &err);
    cf_check_file(path);
    assert_int_equal(nc_open(path, NC_NOWRITE, &id), NC_NOERR);
    assert_int_equal(nc_inq_varid(id, "time", &vid), NC_NOERR);
    assert_text_att(id, vid, "units", "common_year");
    assert_int_equal(nc_inq_attlen(id, vid, "calendar", &len), NC_ENOTATT);
    nc_close(id);
}

/* A record back onto the grid (a restart): by index and by time; a grid
 * the file does not fit is refused, naming what differs. */
static void test_read_grid(void **state)
{
    enum { NX = 4, NY = 3 };
    double z[NX * NY], back[NX * NY], t;
    const double *vals[1] = {z};
    const dfle_nc_var var = {"z", "m", NULL, NULL, NULL};
    dfle_raster_geo g = {1000, 5000, 10, 10, NULL};
    dfle_nc_opts o;
    dfle_nc *nc;
    dfle_error err;
    (void)state;
    for (int k = 0; k < NX * NY; k++)
        z[k] = k % NX == 0 ? NAN : (double)k; /* column 0 NoData: cropped away */
    in_dir(path, sizeof path, "restart.nc");
    dfle_nc_opts_default(&o);
    o.mask = z;
    o.float32 = 0;
    assert_ok(dfle_nc_create(path, NX, NY, &g, 1, &var, &o, &nc, &err), &err);
    assert_ok(dfle_nc_append(nc, 0.0, vals, &err), &err);
    for (int k = 0; k < NX * NY; k++)
        z[k] += 0.25;
    assert_ok(dfle_nc_append(nc, 1500.0, vals, &err), &err);
    assert_ok(dfle_nc_close(nc, &err), &err);
    assert_ok(dfle_nc_read_grid(path, "z", 1, 0, &g, NX, NY, back, &t, &err), &err);
    assert_close(t, 1500, 0, 0);
    for (int k = 0; k < NX * NY; k++)
        if (k % NX == 0)
            assert_true(isnan(back[k]));
        else
            assert_close(back[k], z[k], 0, 0);
    assert_ok(dfle_nc_read_grid(path, "z", (size_t)-1, 0.0, &g, NX, NY, back, &t, &err), &err);
    assert_close(back[1], 1, 0, 0);
    assert_int_equal(dfle_nc_read_grid(path, "z", (size_t)-1, 700, &g, NX, NY, back, NULL, &err),
                     DFLE_EINVAL);
    assert_msg_contains(err.msg, "no record at t = 700 yr");
    assert_int_equal(dfle_nc_read_grid(path, "z", 2, 0, &g, NX, NY, back, NULL, &err),
                     DFLE_EINVAL);
    assert_msg_contains(err.msg, "has 2 records");
    assert_int_equal(dfle_nc_read_grid(path, "E_df", 0, 0, &g, NX, NY, back, NULL, &err),
                     DFLE_EINVAL);
    assert_msg_contains(err.msg, "no field 'E_df'");
    g.x0 += 5; /* half a cell off */
    assert_int_equal(dfle_nc_read_grid(path, "z", 0, 0, &g, NX, NY, back, NULL, &err),
                     DFLE_EINVAL);
    assert_msg_contains(err.msg, "x coordinates");
    g.x0 -= 5;
    assert_int_equal(dfle_nc_read_grid(path, "z", 0, 0, &g, 2, NY, back, NULL, &err),
                     DFLE_EINVAL); /* the window lies outside a smaller grid */
}

/* ---------------------------------------------------------------- */
/* Targets that are not regular files                               */
/* ---------------------------------------------------------------- */

static void assert_node(const char *p, mode_t kind)
{
    struct stat sb;
    assert_int_equal(lstat(p, &sb), 0);
    assert_int_equal(sb.st_mode & S_IFMT, kind);
}

/* A FIFO, a device node (the test's own, numbered like /dev/full, whose
 * writes fail) and links to them are refused, and stay as they were:
 * libnetcdf removes what it was told to create when a write fails, and
 * it was once handed such nodes. */
static void test_nodes_left_in_place(void **state)
{
    const double t[1] = {0}, x[1] = {0}, A[1] = {1}, z[1] = {1};
    const double *values[1] = {z};
    const dfle_nc_var var = {"z", "m", NULL, NULL, NULL};
    const dfle_raster_geo g = {0, 10, 10, 10, NULL};
    char fifo[600], dev[600], link1[600], link2[600];
    int have_dev;
    dfle_nc *nc = NULL;
    dfle_error err;
    (void)state;
    in_dir(fifo, sizeof fifo, "fifo");
    in_dir(dev, sizeof dev, "full");
    in_dir(link1, sizeof link1, "to-fifo.nc");
    in_dir(link2, sizeof link2, "to-full.nc");
    assert_int_equal(mkfifo(fifo, 0600), 0);
    have_dev = mknod(dev, S_IFCHR | 0600, makedev(1, 7)) == 0; /* needs root */
    assert_int_equal(symlink(fifo, link1), 0);
    assert_int_equal(symlink(dev, link2), 0);
    for (int k = 0; k < 4; k++) {
        const char *p = k == 0 ? fifo : k == 1 ? dev : k == 2 ? link1 : link2;
        if (k % 2 == 1 && !have_dev)
            continue;
        assert_int_equal(dfle_nc_write_profiles(p, 1, x, A, 1, t, 1, &var, values, NULL, &err),
                         DFLE_EIO);
        assert_msg_contains(err.msg, k % 2 == 0 ? "a FIFO" : "a character device");
        assert_msg_contains(err.msg, "give the name of a regular file");
        if (k >= 2)
            assert_msg_contains(err.msg, "a link to");
        assert_int_equal(dfle_nc_create(p, 1, 1, &g, 1, &var, NULL, &nc, &err), DFLE_EIO);
        assert_null(nc);
        assert_int_equal(dfle_nc_write_table(p, "sample", 1, 1, &var, values, 0, NULL, 0, NULL,
                                             &err), DFLE_EIO);
    }
    assert_node(fifo, S_IFIFO);
    assert_node(link1, S_IFLNK);
    assert_node(link2, S_IFLNK);
    if (have_dev)
        assert_node(dev, S_IFCHR);
    unlink(fifo), unlink(dev), unlink(link1), unlink(link2);
}

/* ---------------------------------------------------------------- */
/* Every NetCDF file of the Lua API                                 */
/* ---------------------------------------------------------------- */


static void test_lua_files(void **state)
{
    char code[4096], m[600], ls[600], ens[600], csv[600];
    int id, vid;
    (void)state;
    in_dir(m, sizeof m, "model.nc");
    in_dir(ls, sizeof ls, "landscape.nc");
    in_dir(ens, sizeof ens, "ensemble.nc");
    in_dir(csv, sizeof csv, "ensemble.csv");
    snprintf(code, sizeof code,
             "local m = dfle.model{ channel = dfle.channel{ dx = 50 } }\n"
             "m:run{ years = 100, record = { 50, 100 }, netcdf = '%s' }\n"
             "local ls = dfle.landscape{ nx = 8, ny = 6, dx = 30, x0 = 390000, y0 = 3800000,\n"
             "  crs = 'EPSG:32611', U = 5e-4, A0 = 2700, noise = { seed = 2 } }\n"
             "ls:run{ years = 2e3, dt = 1e3, record = { 0, 2e3 }, netcdf = '%s',\n"
             "        fields = { 'z', 'A', 'S', 'E_f', 'E_df', 'reach', 'channel', 'dzdt', 'U',\n"
             "                   'base' } }\n"
             "local e = dfle.ensemble{ params = { U = { 1e-4, 1e-3 } }, n = 2, seed = 1,\n"
             "  out = '%s', workers = 1, outputs = { 'S_df', 'A_df' },\n"
             "  build = function(p) return dfle.model{ channel = dfle.channel{ dx = 50 },\n"
             "                                         U = p.U } end }\n"
             "e:write_netcdf('%s')\n",
             m, ls, csv, ens);
    run_lua_snippet(code);
    cf_check_file(m);
    cf_check_file(ls);
    cf_check_file(ens);
    /* The landscape's provenance: its parameters as numbers. */
    assert_int_equal(nc_open(ls, NC_NOWRITE, &id), NC_NOERR);
    assert_close(num_att(id, NC_GLOBAL, "landscape_U", NC_DOUBLE), 5e-4, 0, 0);
    assert_close(num_att(id, NC_GLOBAL, "landscape_A0", NC_DOUBLE), 2700, 0, 0);
    assert_close(num_att(id, NC_GLOBAL, "landscape_S_c", NC_DOUBLE), 0.8, 0, 0);
    assert_close(num_att(id, NC_GLOBAL, "fluvial_k_e", NC_DOUBLE), 5e-14, 0, 0);
    assert_close(num_att(id, NC_GLOBAL, "law_k_df", NC_DOUBLE), 1e-4, 0, 0);
    assert_close(num_att(id, NC_GLOBAL, "router_M0", NC_DOUBLE), 3000, 0, 0);
    assert_text_att(id, NC_GLOBAL, "router", "empirical");
    assert_text_att(id, NC_GLOBAL, "law", "power");
    assert_text_att(id, NC_GLOBAL, "run_reason", "time");
    assert_int_equal(nc_inq_varid(id, "crs", &vid), NC_NOERR);
    assert_text_att(id, vid, "grid_mapping_name", "transverse_mercator");
    assert_int_equal(nc_inq_varid(id, "A", &vid), NC_NOERR);
    assert_text_att(id, vid, "units", "m2");
    assert_int_equal(nc_inq_varid(id, "S", &vid), NC_NOERR);
    assert_text_att(id, vid, "units", "1");
    nc_close(id);
    assert_int_equal(nc_open(m, NC_NOWRITE, &id), NC_NOERR);
    assert_close(num_att(id, NC_GLOBAL, "model_U", NC_DOUBLE), 5e-4, 0, 0);
    assert_text_att(id, NC_GLOBAL, "run", "run");
    nc_close(id);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_profiles),
        cmocka_unit_test(test_table),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_grid_crop_and_flags),
        cmocka_unit_test(test_grid_crs),
        cmocka_unit_test(test_grid_long_time),
        cmocka_unit_test(test_read_grid),
        cmocka_unit_test(test_nodes_left_in_place),
        cmocka_unit_test(test_lua_files),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
