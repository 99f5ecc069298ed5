/*
 * raster.c - GeoTIFF through GDAL (raster.h).
 *
 * GDAL writes to the temporary file of dfle_file_begin_regular, which is
 * renamed over the target once GDALClose has flushed it, so a reader never
 * sees a half-written GeoTIFF; a device or a FIFO is refused (GDAL seeks
 * in what it writes).  The name must say GeoTIFF: a file named .png that
 * holds a TIFF misleads every program that opens it.  Band units are
 * UDUNITS' ("m2"), as in dfle's NetCDF files; the record goes into
 * GDAL's metadata (gdalinfo lists it), numbers as their shortest exact
 * text with their unit.  GDAL's error printer is silenced for the call
 * and its last message folded into dfle's, as the DEM reader does.
 * GDAL itself is loaded by the first write (base/gdal_lib.h).
 */
#include "dfle/raster.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "base/gdal_lib.h" /* GDAL, loaded by the first write */
#include "dfle/file.h"
#include "io/raster_internal.h"

int dfle_raster_has_extension(const char *path, const char *const *ext)
{
    size_t n = strlen(path);
    for (; *ext != NULL; ext++) {
        size_t m = strlen(*ext);
        if (n > m && strcasecmp(path + n - m, *ext) == 0 && path[n - m - 1] != '/')
            return 1;
    }
    return 0;
}

typedef struct meta_ctx {
    GDALMajorObjectH obj;
    const char *section; /* the last section seen */
} meta_ctx;

static int put_item(void *ud, const dfle_record_entry *e)
{
    meta_ctx *c = ud;
    GDALMajorObjectH ds = c->obj;
    char name[160], value[4096], num[32], unit[128];
    if (e->section != NULL && (c->section == NULL || strcmp(c->section, e->section) != 0)) {
        c->section = e->section;
        if (e->kind != NULL) { /* the section's kind, as <section> */
            dfle_record_entry k = {.section = e->section};
            dfle_record_flat_name(&k, name, sizeof name);
            GDALSetMetadataItem(ds, name, e->kind, NULL);
        }
    }
    if (e->key == NULL)
        return 0;
    dfle_record_flat_name(e, name, sizeof name);
    switch (e->type) {
    case DFLE_RECORD_NUMBER:
        if (e->unit != NULL)
            snprintf(value, sizeof value, "%s %s", dfle_number_text(e->num, num),
                     dfle_units_udunits(e->unit, unit, sizeof unit) ? unit : e->unit);
        else
            snprintf(value, sizeof value, "%s", dfle_number_text(e->num, num));
        break;
    case DFLE_RECORD_BOOL:
        snprintf(value, sizeof value, "%s", e->num != 0 ? "true" : "false");
        break;
    case DFLE_RECORD_TEXT:
        snprintf(value, sizeof value, "%s", e->text != NULL ? e->text : "");
        break;
    case DFLE_RECORD_LIST:
        dfle_record_join(e->items, e->nitems, value, sizeof value);
        break;
    }
    GDALSetMetadataItem(ds, name, value, NULL);
    return 0;
}

void raster_put_record(GDALMajorObjectH ds, const dfle_record *rec)
{
    char line[4200];
    GDALSetMetadataItem(ds, "dfle_version", DFLE_VERSION, NULL);
    if (rec == NULL)
        return;
    meta_ctx c = {ds, NULL};
    if (dfle_record_history(rec, line, sizeof line))
        GDALSetMetadataItem(ds, "history", line, NULL);
    dfle_record_each(rec, put_item, &c);
}

int dfle_raster_write_geotiff(const char *path, size_t nx, size_t ny, const dfle_raster_geo *geo,
                              size_t nbands, const dfle_raster_band *bands,
                              const dfle_record *rec, dfle_error *err)
{
    static const char *const tiff[] = {".tif", ".tiff", NULL};
    const char *write_to;
    dfle_file f;
    GDALDriverH drv;
    GDALDatasetH ds;
    double gt[6];
    int st;

    if (nx == 0 || ny == 0 || nbands == 0 || nx > 2147483647u || ny > 2147483647u)
        return dfle_error_set(err, DFLE_EINVAL, "raster: cannot write a %zu x %zu grid of %zu "
                              "bands", nx, ny, nbands);
    if (!dfle_raster_has_extension(path, tiff))
        return dfle_error_set(err, DFLE_EINVAL, "raster: '%s' is not the name of a GeoTIFF: the "
                              "file is a GeoTIFF, so its name must end in .tif or .tiff", path);
    if ((st = dfle_gdal_load("raster", err)) != DFLE_OK)
        return st;
    if ((drv = GDALGetDriverByName("GTiff")) == NULL)
        return dfle_error_set(err, DFLE_EIO, "raster: GDAL has no GTiff driver");
    if ((st = dfle_file_begin_regular(&f, path, "raster", &write_to, err)) != DFLE_OK)
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
        GDALSetMetadataItem(ds, "TIFFTAG_SOFTWARE", "dfle " DFLE_VERSION, NULL);
        raster_put_record(ds, rec);
        for (size_t b = 0; b < nbands && st == DFLE_OK; b++) {
            GDALRasterBandH band = GDALGetRasterBand(ds, (int)b + 1);
            char unit[128];
            GDALSetRasterNoDataValue(band, NAN);
            if (bands[b].name != NULL)
                GDALSetDescription(band, bands[b].name);
            if (bands[b].units != NULL && dfle_units_udunits(bands[b].units, unit, sizeof unit))
                GDALSetRasterUnitType(band, unit);
            if (GDALRasterIO(band, GF_Write, 0, 0, (int)nx, (int)ny, (void *)bands[b].values,
                             (int)nx, (int)ny, GDT_Float64, 0, 0) != CE_None)
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
