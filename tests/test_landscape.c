/*
 * test_landscape.c - the C pieces of landscapes: outlets in the routing,
 * the network's channel mask and the model's erodibility in space, the
 * implicit step's stream-power solve (n = 1 and n != 1) against its own
 * equation, its table of powers against pow, and the NetCDF writer
 * read back with the netCDF library.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <netcdf.h>

#include "dfle/drainage.h"
#include "dfle/landscape.h"
#include "dfle/raster.h"
#include "dfle_test.h"
#include "landscape/landscape_internal.h"

/* A cell named an outlet drains off the grid wherever it is. */
static void test_outlets(void **state)
{
    double z[9] = {5, 5, 5, 5, 1, 5, 5, 5, 5}; /* a pit in the middle */
    dfle_drainage_opts o;
    dfle_drainage *dr;
    dfle_error err;
    size_t mid = 4;
    (void)state;
    dfle_drainage_opts_default(&o);
    o.nx = o.ny = 3;
    for (int s = 0; s < 4; s++)
        o.edge[s] = DFLE_DRAINAGE_CLOSED;
    assert_ok(dfle_drainage_new(&o, &dr, &err), &err);
    assert_ok(dfle_drainage_set_outlets(dr, &mid, 1, &err), &err);
    assert_ok(dfle_drainage_route(dr, z, &err), &err);
    assert_int_equal(dfle_drainage_dir(dr)[4], DFLE_DRAINAGE_DIR_OUT);
    assert_close(dfle_drainage_area(dr)[4], 9.0, 0, 0);
    mid = 9;
    assert_int_equal(dfle_drainage_set_outlets(dr, &mid, 1, &err), DFLE_EINVAL);
    dfle_drainage_free(dr);
}

/* Implicit steps satisfy z' - z = dt (U - K A^m S'^n) at every cell. */
static void check_step(double n_exp)
{
    enum { NX = 12, NY = 10 };
    double z[NX * NY], z0[NX * NY];
    dfle_fluvial *fl;
    dfle_landscape *ls;
    dfle_landscape_opts o;
    dfle_landscape_status st;
    dfle_error err;
    for (int i = 0; i < NX * NY; i++)
        z[i] = 10.0 * (i / NX) + 0.37 * (i % 7);
    assert_ok(dfle_fluvial_new_stream_power(3e-5, 0.5, n_exp, &fl, &err), &err);
    dfle_landscape_opts_default(&o);
    o.nx = NX, o.ny = NY, o.dx = o.dy = 30;
    o.z = z;
    o.A0 = 0;
    o.fluvial = fl;
    o.U.value = 1e-3;
    assert_ok(dfle_landscape_new(&o, &ls, &err), &err);
    for (int k = 0; k < 5; k++)
        assert_ok(dfle_landscape_step(ls, 2e3, 1e-3, &st, &err), &err);
    memcpy(z0, dfle_landscape_z(ls), sizeof z0);
    assert_ok(dfle_landscape_step(ls, 50, 1e-3, &st, &err), &err);
    /* Every cell, with the receivers the step solved with: the drainage
     * object's until the next routing (a field read would route the new
     * surface, whose receivers may differ). */
    {
        const dfle_drainage *dr = dfle_landscape_drainage(ls);
        const uint32_t *rcv = dfle_drainage_receivers(dr);
        const unsigned char *dir = dfle_drainage_dir(dr);
        const double *A = dfle_drainage_area(dr), *zn = dfle_landscape_z(ls);
        int checked = 0;
        for (int i = 0; i < NX * NY; i++) {
            double S;
            if (rcv[i] == (uint32_t)i)
                continue; /* a base level */
            S = (zn[i] - zn[rcv[i]]) / dfle_drainage_length(dr, dir[i]);
            assert_close(zn[i] - z0[i], 50 * (1e-3 - dfle_fluvial_rate(fl, A[i], S)), 1e-8,
                         1e-12);
            checked++;
        }
        assert_true(checked >= NX * NY - 2 * (NX + NY));
    }
    assert_close(st.dV, st.V_uplift - st.V_fluvial - st.V_df - st.V_hillslope, 1e-9, 1e-6);
    assert_true(dfle_landscape_memory(ls) / (NX * NY) < 400);
    dfle_landscape_free(ls);
    dfle_fluvial_free(fl);
}

static void test_step_n1(void **state) { (void)state; check_step(1.0); }
static void test_step_n233(void **state) { (void)state; check_step(2.33); }
static void test_step_n07(void **state) { (void)state; check_step(0.7); }

/* The implicit sweep's powers for a fixed exponent (landscape_internal.h)
 * agree with pow to a few ulps over the whole range, tables or not, and
 * hand 0, subnormals, infinity and NaN to pow. */
static void test_pow_table(void **state)
{
    static const double ps[] = {2.33, 1.0 / 2.33, 0.7, 1.5, 6.0, 7.5};
    ls_pow t;
    (void)state;
    for (size_t q = 0; q < sizeof ps / sizeof *ps; q++) {
        ls_pow_init(&t, ps[q]);
        assert_int_equal(t.table, ps[q] <= 6.0);
        for (int k = 0; k <= 4000; k++) {
            double x = ldexp(1.0 + 0.618033988749895 * (k % 97) / 97.0, -70 + 140 * k / 4000);
            assert_close(ls_pow_eval(&t, x), pow(x, ps[q]), 2e-15, 0);
        }
        assert_true(ls_pow_eval(&t, 0.0) == 0.0);
        assert_close(ls_pow_eval(&t, 1e-310), pow(1e-310, ps[q]), 2e-15, 0);
        assert_true(isinf(ls_pow_eval(&t, INFINITY)));
        assert_true(isnan(ls_pow_eval(&t, NAN)));
    }
}

/* The NetCDF writer: dims, coordinates, values, read back. */
static void test_netcdf(void **state)
{
    char path[] = "/tmp/dfle-test-nc-XXXXXX";
    double v[6] = {1, 2, 3, 4, NAN, 6}, w[6], x[3], t;
    const double *vals[1] = {v};
    dfle_nc_var var = {"z", "m", "elevation", "surface_altitude", NULL};
    char text[64];
    dfle_raster_geo g = {100, 2000, 10, 20, NULL};
    dfle_nc *nc;
    dfle_error err;
    int fd = mkstemp(path), id, vid;
    size_t len, start[3] = {1, 0, 0}, count[3] = {1, 2, 3};
    (void)state;
    assert_true(fd >= 0);
    assert_ok(dfle_nc_create(path, 3, 2, &g, 1, &var, NULL, &nc, &err), &err);
    assert_ok(dfle_nc_append(nc, 0.0, vals, &err), &err);
    v[0] = 7;
    assert_ok(dfle_nc_append(nc, 500.0, vals, &err), &err);
    assert_ok(dfle_nc_close(nc, &err), &err);
    assert_int_equal(nc_open(path, NC_NOWRITE, &id), NC_NOERR);
    assert_int_equal(nc_inq_dimid(id, "time", &vid), NC_NOERR);
    assert_int_equal(nc_inq_dimlen(id, vid, &len), NC_NOERR);
    assert_int_equal(len, 2);
    assert_int_equal(nc_inq_varid(id, "x", &vid), NC_NOERR);
    assert_int_equal(nc_get_var_double(id, vid, x), NC_NOERR);
    assert_close(x[0], 105, 0, 0);
    assert_close(x[2], 125, 0, 0);
    assert_int_equal(nc_inq_varid(id, "time", &vid), NC_NOERR);
    assert_int_equal(nc_get_var1_double(id, vid, &start[0], &t), NC_NOERR);
    assert_close(t, 500, 0, 0);
    assert_int_equal(nc_inq_varid(id, "z", &vid), NC_NOERR);
    assert_int_equal(nc_get_vara_double(id, vid, start, count, w), NC_NOERR);
    assert_close(w[0], 7, 0, 0);
    assert_close(w[5], 6, 0, 0);
    assert_true(isnan(w[4]));
    /* CF attributes, as xarray reads them */
    {
        static const char *const want[][3] = {
            {"z", "units", "m"},          {"z", "long_name", "elevation"},
            {"z", "standard_name", "surface_altitude"},
            {"x", "standard_name", "projection_x_coordinate"},
            {"y", "units", "m"},          {"time", "axis", "T"},
        };
        for (size_t k = 0; k < sizeof want / sizeof *want; k++) {
            assert_int_equal(nc_inq_varid(id, want[k][0], &vid), NC_NOERR);
            assert_int_equal(nc_inq_attlen(id, vid, want[k][1], &len), NC_NOERR);
            assert_true(len < sizeof text);
            assert_int_equal(nc_get_att_text(id, vid, want[k][1], text), NC_NOERR);
            text[len] = '\0';
            assert_string_equal(text, want[k][2]);
        }
        assert_int_equal(nc_inq_attlen(id, NC_GLOBAL, "Conventions", &len), NC_NOERR);
        assert_int_equal(nc_get_att_text(id, NC_GLOBAL, "Conventions", text), NC_NOERR);
        text[len] = '\0';
        assert_string_equal(text, "CF-1.8");
    }
    nc_close(id);
    close(fd);
    unlink(path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_outlets),  cmocka_unit_test(test_step_n1),
        cmocka_unit_test(test_step_n233), cmocka_unit_test(test_step_n07),
        cmocka_unit_test(test_pow_table),         cmocka_unit_test(test_netcdf),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
