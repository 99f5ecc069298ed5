/*
 * test_vector.c - GeoPackages dfle writes (vector.h; p:write_gpkg,
 * dem:write_gpkg), read back with OGR itself (this test links GDAL):
 * layers, CRS, one line a cell to its receiver with the cell's
 * attributes, one point a cell, and the catchment as one polygon whose
 * area is its cells' (a D8 catchment joined through corners stays one
 * polygon); names must end in .gpkg; FIFOs stay FIFOs.
 */
#define _XOPEN_SOURCE 700 /* mkdtemp */
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <gdal.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>

#include "dfle_test.h"
#include "scratch_dir.h"
#include "lua_snippet.h"

#include "dfle/dem.h"
#include "dfle/vector.h"

static char dir[] = "/tmp/dfle_test_vector_XXXXXX";

static int setup(void **state)
{
    (void)state;
    GDALAllRegister();
    CPLPushErrorHandler(CPLQuietErrorHandler);
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

/* A bowl of 21 x 21 cells of 10 m around (105, 105) with a notch cut to
 * the south edge, filled: it spills through the notch, so every cell
 * drains to one outlet (the notch's edge cell), through corners too. */
static dfle_dem *cone(void)
{
    enum { N = 21 };
    double z[N * N];
    dfle_dem_geo g = {0, 210, 10, 10};
    dfle_dem *d;
    dfle_error err;
    for (int r = 0; r < N; r++)
        for (int c = 0; c < N; c++) {
            double dx = c - 10, dy = r - 10;
            z[r * N + c] = c == 10 && r > 10 ? 0.1 + 0.05 * (r - 10)
                                             : sqrt(dx * dx + dy * dy) + 0.01 * c;
        }
    assert_ok(dfle_dem_new(N, N, z, &g, &d, &err), &err);
    assert_ok(dfle_dem_set_crs(d, "EPSG:32611", &err), &err);
    assert_ok(dfle_dem_fill(d, NULL, &err), &err);
    return d;
}

static int layer_epsg(OGRLayerH l)
{
    OGRSpatialReferenceH s = OGR_L_GetSpatialRef(l);
    const char *code = s != NULL ? OSRGetAuthorityCode(s, NULL) : NULL;
    return code != NULL ? atoi(code) : 0;
}

static void test_network_layers(void **state)
{
    char gpkg[600];
    dfle_dem *dem = cone();
    dfle_network_opts no;
    dfle_profile *net;
    dfle_vector_opts o;
    dfle_error err;
    GDALDatasetH ds;
    OGRLayerH lines, points;
    OGRFeatureH f;
    size_t n;
    (void)state;
    dfle_network_opts_default(&no);
    no.A_min = 300;
    assert_ok(dfle_dem_network(dem, &no, &net, &err), &err);
    n = dfle_profile_size(net);
    in_dir(gpkg, sizeof gpkg, "net.gpkg");
    dfle_vector_opts_default(&o);
    o.channels = net;
    assert_ok(dfle_vector_write_gpkg(gpkg, &o, &err), &err);
    assert_non_null(ds = GDALOpenEx(gpkg, GDAL_OF_VECTOR, NULL, NULL, NULL));
    assert_string_equal(GDALGetDriverShortName(GDALGetDatasetDriver(ds)), "GPKG");
    assert_non_null(lines = GDALDatasetGetLayerByName(ds, "channels"));
    assert_non_null(points = GDALDatasetGetLayerByName(ds, "cells"));
    assert_int_equal(layer_epsg(lines), 32611);
    assert_int_equal(layer_epsg(points), 32611);
    assert_int_equal(OGR_L_GetGeomType(lines), wkbLineString);
    assert_int_equal(OGR_L_GetFeatureCount(points, 1), (GIntBig)n);
    {
        /* One line a cell with a receiver: every cell but the outlets. */
        size_t with = 0;
        for (size_t i = 0; i < n; i++)
            with += dfle_profile_receiver(net)[i] != 0;
        assert_int_equal(OGR_L_GetFeatureCount(lines, 1), (GIntBig)with);
    }
    OGR_L_ResetReading(lines);
    while ((f = OGR_L_GetNextFeature(lines)) != NULL) {
        OGRFeatureDefnH def = OGR_L_GetLayerDefn(lines);
        size_t cell = (size_t)OGR_F_GetFieldAsInteger64(f, OGR_FD_GetFieldIndex(def, "cell"));
        size_t rcv = (size_t)OGR_F_GetFieldAsInteger64(f, OGR_FD_GetFieldIndex(def, "receiver"));
        OGRGeometryH g = OGR_F_GetGeometryRef(f);
        const double *E = dfle_profile_field(net, DFLE_PROFILE_E);
        const double *N = dfle_profile_field(net, DFLE_PROFILE_N);
        assert_true(cell >= 1 && cell <= n);
        assert_int_equal(rcv, dfle_profile_receiver(net)[cell - 1]);
        assert_int_equal(OGR_G_GetPointCount(g), 2);
        assert_close(OGR_G_GetX(g, 0), E[cell - 1], 0, 0);
        assert_close(OGR_G_GetY(g, 0), N[cell - 1], 0, 0);
        assert_close(OGR_G_GetX(g, 1), E[rcv - 1], 0, 0);
        assert_close(OGR_G_GetY(g, 1), N[rcv - 1], 0, 0);
        assert_close(OGR_F_GetFieldAsDouble(f, OGR_FD_GetFieldIndex(def, "A")),
                     dfle_profile_field(net, DFLE_PROFILE_A)[cell - 1], 0, 0);
        assert_close(OGR_F_GetFieldAsDouble(f, OGR_FD_GetFieldIndex(def, "z")),
                     dfle_profile_field(net, DFLE_PROFILE_Z)[cell - 1], 0, 0);
        assert_close(OGR_F_GetFieldAsDouble(f, OGR_FD_GetFieldIndex(def, "S")),
                     dfle_profile_field(net, DFLE_PROFILE_S)[cell - 1], 0, 0);
        OGR_F_Destroy(f);
    }
    GDALClose(ds);
    dfle_profile_free(net);
    dfle_dem_free(dem);
}

/* The catchment of the notch's outlet is the whole bowl (every cell
 * drains there): one polygon of 21 x 21 cells of 100 m^2. */
static void test_catchment(void **state)
{
    char gpkg[600];
    dfle_dem *dem = cone();
    dfle_vector_opts o;
    dfle_error err;
    GDALDatasetH ds;
    OGRLayerH l;
    OGRFeatureH f;
    OGRFeatureDefnH def;
    (void)state;
    in_dir(gpkg, sizeof gpkg, "catchment.gpkg");
    dfle_vector_opts_default(&o);
    o.catchment_of = dem;
    o.outlet[0] = 105, o.outlet[1] = 5; /* the notch at the south edge */
    o.radius = 0;
    assert_ok(dfle_vector_write_gpkg(gpkg, &o, &err), &err);
    assert_non_null(ds = GDALOpenEx(gpkg, GDAL_OF_VECTOR, NULL, NULL, NULL));
    assert_non_null(l = GDALDatasetGetLayerByName(ds, "catchment"));
    assert_int_equal(layer_epsg(l), 32611);
    assert_int_equal(OGR_L_GetFeatureCount(l, 1), 1);
    OGR_L_ResetReading(l);
    assert_non_null(f = OGR_L_GetNextFeature(l));
    def = OGR_L_GetLayerDefn(l);
    assert_close(OGR_G_Area(OGR_F_GetGeometryRef(f)), 21 * 21 * 100.0, 1e-12, 0);
    assert_close(OGR_F_GetFieldAsDouble(f, OGR_FD_GetFieldIndex(def, "area")), 44100, 1e-12, 0);
    assert_int_equal(OGR_F_GetFieldAsInteger64(f, OGR_FD_GetFieldIndex(def, "cells")), 441);
    assert_close(OGR_F_GetFieldAsDouble(f, OGR_FD_GetFieldIndex(def, "outlet_E")), 105, 0, 0);
    OGR_F_Destroy(f);
    GDALClose(ds);
    dfle_dem_free(dem);
}

/* Through Lua: the Big Tujunga catchment above the black Fig. 1 outlet
 * is 11,355 cells of 30 m (10.2 km^2), and its network and main stem
 * land in the DEM's CRS. */
static void test_lua_bigtujunga(void **state)
{
    const char *data = getenv("DFLE_DATA_DIR");
    char code[2000], gpkg[600], tif[600];
    GDALDatasetH ds;
    OGRLayerH l;
    OGRFeatureH f;
    (void)state;
    if (data == NULL)
        skip();
    snprintf(tif, sizeof tif, "%s/dem/srtm_bigtujunga30m_utm11.tif", data);
    in_dir(gpkg, sizeof gpkg, "bt.gpkg");
    snprintf(code, sizeof code,
             "local dem = dfle.dem.read('%s')\n"
             "dem:fill()\n"
             "dem:write_gpkg('%s', { outlet = { 396887, 3799338 }, A_min = 1e5 })\n",
             tif, gpkg);
    run_lua_snippet(code);
    assert_non_null(ds = GDALOpenEx(gpkg, GDAL_OF_VECTOR, NULL, NULL, NULL));
    assert_non_null(l = GDALDatasetGetLayerByName(ds, "catchment"));
    OGR_L_ResetReading(l);
    assert_non_null(f = OGR_L_GetNextFeature(l));
    assert_close(OGR_G_Area(OGR_F_GetGeometryRef(f)), 11355 * 900.0, 1e-9, 0);
    OGR_F_Destroy(f);
    assert_non_null(l = GDALDatasetGetLayerByName(ds, "channels"));
    assert_int_equal(layer_epsg(l), 32611);
    assert_true(OGR_L_GetFeatureCount(l, 1) > 100);
    GDALClose(ds);
}

static void test_names_and_nodes(void **state)
{
    char p[600], fifo[600];
    dfle_dem *dem = cone();
    dfle_vector_opts o;
    dfle_error err;
    struct stat sb;
    (void)state;
    dfle_vector_opts_default(&o);
    o.catchment_of = dem;
    o.outlet[0] = 105, o.outlet[1] = 5;
    in_dir(p, sizeof p, "c.shp");
    assert_int_equal(dfle_vector_write_gpkg(p, &o, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "must end in .gpkg");
    in_dir(fifo, sizeof fifo, "fifo.gpkg");
    assert_int_equal(mkfifo(fifo, 0600), 0);
    assert_int_equal(dfle_vector_write_gpkg(fifo, &o, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "it is a FIFO");
    assert_int_equal(stat(fifo, &sb), 0);
    assert_true(S_ISFIFO(sb.st_mode));
    /* An outlet outside the grid: an error, and nothing left behind. */
    o.outlet[0] = 1e6;
    in_dir(p, sizeof p, "outside.gpkg");
    assert_int_not_equal(dfle_vector_write_gpkg(p, &o, &err), DFLE_OK);
    assert_msg_contains(err.msg, "outside the grid");
    assert_int_equal(stat(p, &sb), -1);
    dfle_dem_free(dem);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_network_layers),
        cmocka_unit_test(test_catchment),
        cmocka_unit_test(test_lua_bigtujunga),
        cmocka_unit_test(test_names_and_nodes),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
