/*
 * test_raster.c - GeoTIFFs dfle writes (raster.h; dem:write_geotiff,
 * ls:write_geotiff), read back with GDAL itself (this test links it):
 * CRS, geotransform, NoData, band names and units, the record in the
 * metadata, every band's values against the DEM's own routing; the name
 * must say GeoTIFF; targets that are not regular files stay as they are.
 */
#define _XOPEN_SOURCE 700 /* mkdtemp */
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <gdal.h>
#include <ogr_srs_api.h>


#include "dfle_test.h"
#include "scratch_dir.h"
#include "lua_snippet.h"

#include "dfle/crs.h"
#include "dfle/dem.h"
#include "dfle/raster.h"

static char dir[] = "/tmp/dfle_test_raster_XXXXXX";

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


static int epsg_of(GDALDatasetH ds)
{
    OGRSpatialReferenceH srs = GDALGetSpatialRef(ds);
    const char *code;
    if (srs == NULL)
        return 0;
    code = OSRGetAuthorityCode(srs, NULL);
    return code != NULL ? atoi(code) : 0;
}

static double *read_band(GDALDatasetH ds, int b, int nx, int ny)
{
    double *v = malloc((size_t)nx * (size_t)ny * sizeof *v);
    assert_non_null(v);
    assert_int_equal(GDALRasterIO(GDALGetRasterBand(ds, b), GF_Read, 0, 0, nx, ny, v, nx, ny,
                                  GDT_Float64, 0, 0), CE_None);
    return v;
}

/* A 4 x 3 DEM's products: each band what the DEM's routing says. */
static void test_dem_products(void **state)
{
    static const char asc_text[] = "ncols 4\nnrows 3\nxllcorner 1000\nyllcorner 2000\n"
                                   "cellsize 10\n9 8 7 9\n8 5 4 8\n9 6 2 9\n";
    static const char *const names[] = {"area", "d8", "slope", "z"};
    static const char *const units[] = {"m2", "", "1", "m"};
    char asc[600], tif[600], code[2000];
    double gt[6], *band[4];
    const double *z, *A;
    const unsigned char *code8;
    dfle_dem *dem;
    dfle_error err;
    dfle_dem_read_opts o = {0, 0, 0, "EPSG:32611"};
    GDALDatasetH ds;
    FILE *f;
    (void)state;
    in_dir(asc, sizeof asc, "small.asc");
    in_dir(tif, sizeof tif, "small.tif");
    assert_non_null(f = fopen(asc, "w"));
    fputs(asc_text, f);
    fclose(f);
    snprintf(code, sizeof code,
             "local dem = dfle.dem.read('%s', { crs = 'EPSG:32611' })\n"
             "dem:fill()\n"
             "dem:write_geotiff('%s', { layers = { 'area', 'd8', 'slope', 'z' } })\n", asc, tif);
    run_lua_snippet(code);
    assert_ok(dfle_dem_read(asc, &o, &dem, &err), &err);
    assert_ok(dfle_dem_fill(dem, NULL, &err), &err);
    assert_ok(dfle_dem_route(dem, &err), &err);
    z = dfle_dem_z(dem), A = dfle_dem_area(dem), code8 = dfle_dem_dir(dem);
    assert_non_null(ds = GDALOpen(tif, GA_ReadOnly));
    assert_string_equal(GDALGetDriverShortName(GDALGetDatasetDriver(ds)), "GTiff");
    assert_int_equal(GDALGetRasterCount(ds), 4);
    assert_int_equal(GDALGetRasterXSize(ds), 4);
    assert_int_equal(GDALGetRasterYSize(ds), 3);
    assert_int_equal(epsg_of(ds), 32611);
    assert_int_equal(GDALGetGeoTransform(ds, gt), CE_None);
    assert_close(gt[0], 1000, 0, 0), assert_close(gt[1], 10, 0, 0);
    assert_close(gt[3], 2030, 0, 0), assert_close(gt[5], -10, 0, 0);
    assert_close(gt[2], 0, 0, 0), assert_close(gt[4], 0, 0, 0);
    assert_string_equal(GDALGetMetadataItem(ds, "dfle_version", NULL), DFLE_VERSION);
    assert_non_null(GDALGetMetadataItem(ds, "history", NULL));
    assert_string_equal(GDALGetMetadataItem(ds, "dem_crs", NULL), "WGS 84 / UTM zone 11N");
    for (int b = 0; b < 4; b++) {
        GDALRasterBandH h = GDALGetRasterBand(ds, b + 1);
        int has = 0;
        double nd = GDALGetRasterNoDataValue(h, &has);
        assert_true(has && isnan(nd));
        assert_string_equal(GDALGetDescription(h), names[b]);
        assert_string_equal(GDALGetRasterUnitType(h), units[b]);
        assert_int_equal(GDALGetRasterDataType(h), GDT_Float64);
        band[b] = read_band(ds, b + 1, 4, 3);
    }
    for (int i = 0; i < 12; i++) {
        long long r = dfle_dem_receiver(dem, (size_t)i);
        assert_close(band[3][i], z[i], 0, 0);
        assert_close(band[0][i], A[i], 0, 0);
        if (r < 0) {
            assert_close(band[1][i], 0, 0, 0);
            assert_true(isnan(band[2][i]));
        } else {
            /* ESRI's code 2^k for direction k, the slope to that cell. */
            int dc = (int)(r % 4) - i % 4, dr = (int)(r / 4) - i / 4;
            assert_close(band[1][i], (double)(1u << code8[i]), 0, 0);
            assert_close(band[2][i], (z[i] - z[r]) / (10 * sqrt(dc * dc + dr * dr)), 1e-12, 0);
        }
    }
    for (int b = 0; b < 4; b++)
        free(band[b]);
    GDALClose(ds);
    dfle_dem_free(dem);
}

/* A synthetic landscape with crs = : the grid where x0, y0 say, in that
 * CRS, each field a band with its unit; and its NetCDF series as GDAL
 * (and so QGIS) reads it: the same grid and CRS, a band a record. */
static void test_landscape_crs(void **state)
{
    char tif[600], nc[600], sub[700], code[2000];
    double gt[6];
    GDALDatasetH ds;
    (void)state;
    in_dir(tif, sizeof tif, "ls.tif");
    in_dir(nc, sizeof nc, "ls.nc");
    snprintf(code, sizeof code,
             "local ls = dfle.landscape{ nx = 6, ny = 5, dx = 30, x0 = 390000, y0 = 3800000,\n"
             "  crs = 'EPSG:32611', noise = { seed = 1 } }\n"
             "ls:run{ years = 1e3, dt = 1e3, record = { 0, 1e3 }, netcdf = '%s' }\n"
             "ls:write_geotiff('%s', { 'z', 'A', 'E_f', 'channel' })\n", nc, tif);
    run_lua_snippet(code);
    snprintf(sub, sizeof sub, "NETCDF:\"%s\":z", nc);
    assert_non_null(ds = GDALOpen(sub, GA_ReadOnly));
    assert_int_equal(epsg_of(ds), 32611);
    assert_int_equal(GDALGetRasterXSize(ds), 6);
    assert_int_equal(GDALGetRasterCount(ds), 2); /* the records */
    assert_int_equal(GDALGetGeoTransform(ds, gt), CE_None);
    assert_close(gt[0], 390000, 0, 1e-6), assert_close(gt[3], 3800000, 0, 1e-6);
    assert_close(gt[1], 30, 0, 1e-9), assert_close(gt[5], -30, 0, 1e-9);
    assert_string_equal(GDALGetRasterUnitType(GDALGetRasterBand(ds, 1)), "m");
    GDALClose(ds);
    assert_non_null(ds = GDALOpen(tif, GA_ReadOnly));
    assert_int_equal(epsg_of(ds), 32611);
    assert_int_equal(GDALGetGeoTransform(ds, gt), CE_None);
    assert_close(gt[0], 390000, 0, 0), assert_close(gt[3], 3800000, 0, 0);
    assert_close(gt[1], 30, 0, 0), assert_close(gt[5], -30, 0, 0);
    assert_string_equal(GDALGetRasterUnitType(GDALGetRasterBand(ds, 1)), "m");
    assert_string_equal(GDALGetRasterUnitType(GDALGetRasterBand(ds, 2)), "m2");
    assert_string_equal(GDALGetRasterUnitType(GDALGetRasterBand(ds, 3)), "m/yr");
    assert_string_equal(GDALGetRasterUnitType(GDALGetRasterBand(ds, 4)), ""); /* flags */
    assert_string_equal(GDALGetDescription(GDALGetRasterBand(ds, 4)), "channel");
    assert_non_null(GDALGetMetadataItem(ds, "landscape_A0", NULL));
    assert_string_equal(GDALGetMetadataItem(ds, "router", NULL), "empirical");
    GDALClose(ds);
}

/* The name says GeoTIFF, and only regular files are replaced. */
static void test_names_and_nodes(void **state)
{
    const double z[4] = {1, 2, 3, 4};
    const dfle_raster_band b[1] = {{z, "z", "m"}};
    const dfle_raster_geo geo = {0, 20, 10, 10, NULL};
    char p[600], fifo[600], link[600], target[600];
    struct stat sb;
    dfle_error err;
    GDALDatasetH ds;
    (void)state;
    in_dir(p, sizeof p, "x.png");
    assert_int_equal(dfle_raster_write_geotiff(p, 2, 2, &geo, 1, b, NULL, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "must end in .tif or .tiff");
    assert_int_equal(stat(p, &sb), -1); /* nothing written */
    in_dir(p, sizeof p, "upper.TIFF");
    assert_ok(dfle_raster_write_geotiff(p, 2, 2, &geo, 1, b, NULL, &err), &err);
    in_dir(fifo, sizeof fifo, "fifo.tif");
    assert_int_equal(mkfifo(fifo, 0600), 0);
    assert_int_equal(dfle_raster_write_geotiff(fifo, 2, 2, &geo, 1, b, NULL, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "it is a FIFO");
    assert_int_equal(stat(fifo, &sb), 0);
    assert_true(S_ISFIFO(sb.st_mode));
    /* A link to a regular file: the file is replaced, the link stays. */
    in_dir(target, sizeof target, "target.tif");
    in_dir(link, sizeof link, "link.tif");
    assert_ok(dfle_raster_write_geotiff(target, 2, 2, &geo, 1, b, NULL, &err), &err);
    assert_int_equal(symlink(target, link), 0);
    assert_ok(dfle_raster_write_geotiff(link, 2, 2, &geo, 1, b, NULL, &err), &err);
    assert_int_equal(lstat(link, &sb), 0);
    assert_true(S_ISLNK(sb.st_mode));
    assert_non_null(ds = GDALOpen(target, GA_ReadOnly));
    GDALClose(ds);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_dem_products),
        cmocka_unit_test(test_landscape_crs),
        cmocka_unit_test(test_names_and_nodes),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
