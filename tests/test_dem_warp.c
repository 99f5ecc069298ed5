/*
 * test_dem_warp.c - a DEM resampled and cropped through GDAL
 * (dem_warp.c), against analytical answers on a plane z = a E + b N + c:
 * a block average of a plane is the plane at the block's centre, a
 * bilinear interpolation of it is the plane, a nearest neighbour is the
 * plane at the nearest centre; a crop is the same cells.  The CRS comes
 * along; NoData stays out of averages.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/crs.h"
#include "dfle/dem.h"
#include "dfle_test.h"

enum { NX = 30, NY = 24 };
static const double X0 = 380000, Y0 = 3800000, DX = 10;
static const double PA = 0.3, PB = 0.2, PC = 5.0;

static double plane(double E, double N) { return PA * (E - X0) + PB * (N - Y0) + 500 + PC; }

static dfle_dem *plane_dem(int with_hole)
{
    double z[NX * NY];
    dfle_dem_geo g = {X0, Y0, DX, DX};
    dfle_dem *d;
    dfle_error err;
    for (int r = 0; r < NY; r++)
        for (int c = 0; c < NX; c++)
            z[r * NX + c] = plane(X0 + (c + 0.5) * DX, Y0 - (r + 0.5) * DX);
    if (with_hole) /* rows 0-2, columns 0-2 (one 30 m block) and one cell of the next */
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 4; c++)
                if (c < 3 || r == 0)
                    z[r * NX + c] = NAN;
    assert_ok(dfle_dem_new(NX, NY, z, &g, &d, &err), &err);
    assert_ok(dfle_dem_set_crs(d, "EPSG:32611", &err), &err);
    return d;
}

static void centre(const dfle_dem *d, size_t r, size_t c, double *E, double *N)
{
    dfle_dem_cell_centre(d, r * dfle_dem_nx(d) + c, E, N);
}

static void test_average(void **state)
{
    dfle_dem *d = plane_dem(0), *c;
    dfle_error err;
    double e[4], E, N;
    (void)state;
    assert_ok(dfle_dem_resample(d, 30, 0, NULL, &c, &err), &err); /* coarser: average */
    assert_int_equal(dfle_dem_nx(c), NX / 3);
    assert_int_equal(dfle_dem_ny(c), NY / 3);
    assert_close(dfle_dem_dx(c), 30, 0, 0);
    dfle_dem_extent(c, e);
    assert_close(e[0], X0, 0, 0), assert_close(e[3], Y0, 0, 0);
    assert_int_equal(dfle_dem_epsg(c), 32611);
    assert_null(dfle_dem_path(c));
    for (size_t r = 0; r < dfle_dem_ny(c); r++)
        for (size_t k = 0; k < dfle_dem_nx(c); k++) {
            centre(c, r, k, &E, &N);
            assert_close(dfle_dem_z(c)[r * dfle_dem_nx(c) + k], plane(E, N), 1e-12, 0);
        }
    dfle_dem_free(c);
    dfle_dem_free(d);
}

static void test_bilinear_and_nearest(void **state)
{
    dfle_dem *d = plane_dem(0), *f, *n;
    dfle_error err;
    double E, N;
    (void)state;
    assert_ok(dfle_dem_resample(d, 5, 0, NULL, &f, &err), &err); /* finer: bilinear */
    assert_int_equal(dfle_dem_nx(f), 2 * NX);
    /* Inside the outer half cell (where there is nothing to interpolate
     * towards), the plane itself. */
    for (size_t r = 1; r + 1 < dfle_dem_ny(f); r++)
        for (size_t k = 1; k + 1 < dfle_dem_nx(f); k++) {
            centre(f, r, k, &E, &N);
            assert_close(dfle_dem_z(f)[r * dfle_dem_nx(f) + k], plane(E, N), 1e-12, 0);
        }
    assert_ok(dfle_dem_resample(d, 30, 0, "nearest", &n, &err), &err);
    for (size_t r = 0; r < dfle_dem_ny(n); r++)
        for (size_t k = 0; k < dfle_dem_nx(n); k++) {
            centre(n, r, k, &E, &N); /* a coarse centre is a fine centre */
            assert_close(dfle_dem_z(n)[r * dfle_dem_nx(n) + k], plane(E, N), 1e-12, 0);
        }
    dfle_dem_free(f);
    dfle_dem_free(n);
    dfle_dem_free(d);
}

/* The extent is whole new cells from the north-west corner, covering
 * the old; NoData stays out of the average. */
static void test_extent_and_nodata(void **state)
{
    dfle_dem *d = plane_dem(1), *c;
    dfle_error err;
    double e[4], E, N;
    (void)state;
    assert_ok(dfle_dem_resample(d, 70, 0, "average", &c, &err), &err);
    assert_int_equal(dfle_dem_nx(c), 5); /* ceil(300 / 70) */
    assert_int_equal(dfle_dem_ny(c), 4); /* ceil(240 / 70) */
    dfle_dem_extent(c, e);
    assert_close(e[1], X0 + 350, 0, 0);
    assert_close(e[2], Y0 - 280, 0, 0);
    dfle_dem_free(c);
    assert_ok(dfle_dem_resample(d, 30, 0, NULL, &c, &err), &err);
    assert_true(isnan(dfle_dem_z(c)[0])); /* a block of NoData */
    /* the next block lacks one cell: the mean of the other 8 */
    {
        double sum = 0;
        for (int r = 0; r < 3; r++)
            for (int k = 3; k < 6; k++)
                if (!(r == 0 && k == 3)) {
                    E = X0 + (k + 0.5) * DX, N = Y0 - (r + 0.5) * DX;
                    sum += plane(E, N);
                }
        assert_close(dfle_dem_z(c)[1], sum / 8, 1e-12, 0);
    }
    dfle_dem_free(c);
    assert_int_equal(dfle_dem_resample(d, -1, 0, NULL, &c, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "dx and dy");
    assert_int_equal(dfle_dem_resample(d, 30, 0, "spline", &c, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "method must be");
    assert_int_equal(dfle_dem_resample(d, 1e-3, 0, NULL, &c, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "at most 2e9");
    dfle_dem_free(d);
}

static void test_crop(void **state)
{
    dfle_dem *d = plane_dem(1), *c;
    dfle_error err;
    double e[4], box[4] = {X0 + 25, X0 + 95, Y0 - 115, Y0 - 41};
    (void)state;
    assert_ok(dfle_dem_crop(d, box, &c, &err), &err);
    /* the cells the box overlaps: columns 2..9, rows 4..11 */
    assert_int_equal(dfle_dem_nx(c), 8);
    assert_int_equal(dfle_dem_ny(c), 8);
    dfle_dem_extent(c, e);
    assert_close(e[0], X0 + 20, 0, 0), assert_close(e[1], X0 + 100, 0, 0);
    assert_close(e[2], Y0 - 120, 0, 0), assert_close(e[3], Y0 - 40, 0, 0);
    assert_int_equal(dfle_dem_epsg(c), 32611);
    for (size_t r = 0; r < 8; r++)
        for (size_t k = 0; k < 8; k++)
            assert_close(dfle_dem_z(c)[r * 8 + k], dfle_dem_z(d)[(r + 4) * NX + k + 2], 0, 0);
    dfle_dem_free(c);
    /* the data's bounding box: all but the hole's first rows and columns
     * (the hole is in the north-west corner, cells beside it have data) */
    assert_int_equal(dfle_dem_data_extent(d, box), 1);
    assert_close(box[0], X0, 0, 0), assert_close(box[3], Y0, 0, 0);
    /* a box past the grid is bounded by it; one off it is refused */
    box[0] = X0 - 1e4, box[1] = X0 + 1e4, box[2] = Y0 - 1e4, box[3] = Y0 - 200;
    assert_ok(dfle_dem_crop(d, box, &c, &err), &err);
    assert_int_equal(dfle_dem_nx(c), NX);
    assert_int_equal(dfle_dem_ny(c), 4);
    dfle_dem_free(c);
    box[2] = Y0 + 10, box[3] = Y0 + 100;
    assert_int_equal(dfle_dem_crop(d, box, &c, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "does not overlap the grid");
    box[2] = Y0 - 10, box[3] = Y0 - 20;
    assert_int_equal(dfle_dem_crop(d, box, &c, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "N_min < N_max");
    /* a box of NoData only: the reader's own error */
    box[0] = X0, box[1] = X0 + 25, box[2] = Y0 - 5, box[3] = Y0;
    assert_int_equal(dfle_dem_crop(d, box, &c, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "NoData");
    dfle_dem_free(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_average),
        cmocka_unit_test(test_bilinear_and_nearest),
        cmocka_unit_test(test_extent_and_nodata),
        cmocka_unit_test(test_crop),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
