/*
 * test_crs.c - coordinate reference systems through OSR (crs.h): a CRS
 * named by the user read and described, refused when it is no CRS or,
 * for a grid in metres, not a projected one in metres; lon/lat against
 * Snyder's inverse transverse Mercator (utm_check.h), which comes from
 * neither GDAL nor PROJ; and a DEM given a CRS.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/crs.h"
#include "dfle/dem.h"
#include "dfle_test.h"
#include "utm_check.h"

static char wkt[DFLE_CRS_WKT_MAX];

static void test_from_text(void **state)
{
    dfle_crs_info info;
    dfle_error err;
    char label[400];
    (void)state;
    assert_ok(dfle_crs_from_text("EPSG:32611", "test", 1, wkt, sizeof wkt, &info, &err), &err);
    assert_string_equal(info.name, "WGS 84 / UTM zone 11N");
    assert_int_equal(info.epsg, 32611);
    assert_true(info.projected && !info.geographic);
    assert_close(info.linear_unit, 1, 0, 0);
    assert_string_equal(info.geographic_name, "WGS 84");
    dfle_crs_label(&info, label, sizeof label);
    assert_string_equal(label, "WGS 84 / UTM zone 11N (EPSG:32611)");
    assert_true(strncmp(wkt, "PROJCS[\"WGS 84 / UTM zone 11N\"", 30) == 0);
    /* The same CRS from a PROJ string. */
    assert_ok(dfle_crs_from_text("+proj=utm +zone=11 +datum=WGS84 +units=m +no_defs", "test", 1,
                                 wkt, sizeof wkt, &info, &err), &err);
    assert_true(info.projected);
    {
        char again[DFLE_CRS_WKT_MAX];
        assert_ok(dfle_crs_from_text("EPSG:32611", "test", 1, again, sizeof again, NULL, &err),
                  &err);
        assert_true(dfle_crs_same(wkt, again));
        assert_ok(dfle_crs_from_text("EPSG:32610", "test", 1, again, sizeof again, NULL, &err),
                  &err);
        assert_false(dfle_crs_same(wkt, again));
    }
    assert_int_equal(dfle_crs_from_text("EPSG:4326", "landscape: crs", 1, wkt, sizeof wkt, NULL,
                                        &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "landscape: crs: WGS 84 (EPSG:4326) is a geographic CRS");
    assert_int_equal(dfle_crs_from_text("EPSG:2229", "landscape: crs", 1, wkt, sizeof wkt, NULL,
                                        &err), DFLE_EINVAL); /* California zone 5, US feet */
    assert_msg_contains(err.msg, "in another unit than metres");
    assert_ok(dfle_crs_from_text("EPSG:4326", "test", 0, wkt, sizeof wkt, &info, &err), &err);
    assert_true(info.geographic);
    assert_int_equal(dfle_crs_from_text("not a crs", "test", 0, wkt, sizeof wkt, NULL, &err),
                     DFLE_EINVAL);
    assert_msg_contains(err.msg, "'not a crs' is not a CRS GDAL understands");
    assert_int_equal(dfle_crs_from_text("", "test", 0, wkt, sizeof wkt, NULL, &err), DFLE_EINVAL);
    assert_int_equal(dfle_crs_from_text("EPSG:32611", "test", 0, wkt, 20, NULL, &err),
                     DFLE_EINVAL);
    assert_msg_contains(err.msg, "more than dfle keeps");
}

/* Points across UTM zone 11N, at 34 and 48 N, up to 150 km from the
 * central meridian (where Snyder's series is good to a millimetre):
 * PROJ's answer is Snyder's to 1e-8 degrees. */
static void test_lonlat(void **state)
{
    double E[12], N[12], lon[12], lat[12];
    dfle_error err;
    (void)state;
    assert_ok(dfle_crs_from_text("EPSG:32611", "test", 1, wkt, sizeof wkt, NULL, &err), &err);
    for (int k = 0; k < 12; k++) {
        E[k] = 350000 + 60000 * (k % 6) + 1234.5;
        N[k] = k < 6 ? 3799338 : 5320000;
    }
    assert_ok(dfle_crs_lonlat(wkt, 12, E, N, lon, lat, &err), &err);
    for (int k = 0; k < 12; k++) {
        double wl, wp;
        utm_to_lonlat(11, E[k], N[k], &wl, &wp);
        assert_close(lon[k], wl, 0, 1e-8);
        assert_close(lat[k], wp, 0, 1e-8);
    }
}

static void test_dem_set_crs(void **state)
{
    const double z[4] = {1, 2, 3, 4};
    const dfle_dem_geo g = {390000, 3800000, 30, 30};
    dfle_dem *d;
    dfle_error err;
    (void)state;
    assert_ok(dfle_dem_new(2, 2, z, &g, &d, &err), &err);
    assert_null(dfle_dem_crs_wkt(d));
    assert_ok(dfle_dem_set_crs(d, "EPSG:32611", &err), &err);
    assert_int_equal(dfle_dem_epsg(d), 32611);
    assert_string_equal(dfle_dem_crs_name(d), "WGS 84 / UTM zone 11N");
    assert_ok(dfle_dem_check_metric(d, "a test", &err), &err);
    assert_ok(dfle_dem_set_crs(d, "EPSG:4326", &err), &err); /* replaced */
    assert_true(dfle_dem_is_geographic(d));
    assert_int_equal(dfle_dem_check_metric(d, "a test", &err), DFLE_EINVAL);
    assert_int_equal(dfle_dem_set_crs(d, "nowhere", &err), DFLE_EINVAL);
    assert_true(dfle_dem_is_geographic(d)); /* kept */
    dfle_dem_free(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_from_text),
        cmocka_unit_test(test_lonlat),
        cmocka_unit_test(test_dem_set_crs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
