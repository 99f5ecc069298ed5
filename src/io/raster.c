/*
 * raster.c - GeoTIFF through GDAL (raster.h).
 *
 * GDAL writes to the temporary file of dfle_file_begin_external, which is
 * renamed over the target once GDALClose has flushed it, so a reader never
 * sees a half-written GeoTIFF.  GDAL's error printer is silenced for the
 * call and its last message folded into dfle's, as the DEM reader does.
 * GDAL itself is loaded by the first write (base/gdal_lib.h).
 */
#include "dfle/raster.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "base/gdal_lib.h" /* GDAL, loaded by the first write */
#include "dfle/file.h"

int dfle_raster_write_geotiff(const char *path, size_t nx, size_t ny, const dfle_raster_geo *geo,
                              size_t nbands, const double *const *bands,
                              const char *const *names, dfle_error *err)
{
    const char *write_to;
    dfle_file f;
    GDALDriverH drv;
    GDALDatasetH ds;
    double gt[6];
    int st;

    if (nx == 0 || ny == 0 || nbands == 0 || nx > 2147483647u || ny > 2147483647u)
        return dfle_error_set(err, DFLE_EINVAL, "raster: cannot write a %zu x %zu grid of %zu "
                              "bands", nx, ny, nbands);
    if ((st = dfle_gdal_load("raster", err)) != DFLE_OK)
        return st;
    if ((drv = GDALGetDriverByName("GTiff")) == NULL)
        return dfle_error_set(err, DFLE_EIO, "raster: GDAL has no GTiff driver");
    if ((st = dfle_file_begin_external(&f, path, "raster", &write_to, err)) != DFLE_OK)
        return st;
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
    {
        char *opts[] = {"COMPRESS=DEFLATE", "PREDICTOR=3", "TILED=YES", NULL};
        ds = GDALCreate(drv, write_to, (int)nx, (int)ny, (int)nbands, GDT_Float64, opts);
    }
    st = DFLE_OK;
    if (ds == NULL) {
        st = dfle_error_set(err, DFLE_EIO, "raster: cannot write '%s': %s", path,
                            CPLGetLastErrorMsg());
    } else {
        gt[0] = geo->x0, gt[1] = geo->dx, gt[2] = 0.0;
        gt[3] = geo->y0, gt[4] = 0.0, gt[5] = -geo->dy;
        GDALSetGeoTransform(ds, gt);
        if (geo->crs_wkt != NULL && geo->crs_wkt[0] != '\0')
            GDALSetProjection(ds, geo->crs_wkt);
        for (size_t b = 0; b < nbands && st == DFLE_OK; b++) {
            GDALRasterBandH band = GDALGetRasterBand(ds, (int)b + 1);
            GDALSetRasterNoDataValue(band, NAN);
            if (names != NULL && names[b] != NULL)
                GDALSetDescription(band, names[b]);
            if (GDALRasterIO(band, GF_Write, 0, 0, (int)nx, (int)ny, (void *)bands[b], (int)nx,
                             (int)ny, GDT_Float64, 0, 0) != CE_None)
                st = dfle_error_set(err, DFLE_EIO, "raster: cannot write '%s': %s", path,
                                    CPLGetLastErrorMsg());
        }
        GDALClose(ds);
        if (st == DFLE_OK && CPLGetLastErrorType() >= CE_Failure)
            st = dfle_error_set(err, DFLE_EIO, "raster: cannot write '%s': %s", path,
                                CPLGetLastErrorMsg());
    }
    CPLPopErrorHandler();
    if (st != DFLE_OK) {
        dfle_file_abort(&f);
        return st;
    }
    return dfle_file_commit(&f, err);
}
