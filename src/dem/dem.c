/*
 * dem.c - the DEM object: reading rasters through GDAL, georeferencing,
 * NoData, the CRS checks, and map <-> cell conversions.
 *
 * GDAL is the only place dfle meets file formats, so everything that
 * depends on a file's conventions (NoData values, masks, scale and
 * offset, the CRS) is settled here, once: after dfle_dem_read the grid
 * is plain doubles in metres with NaN for "no data", and the routing
 * and profile code never asks where it came from.  GDAL's own error
 * printer is replaced by a quiet one for the duration of each call, so
 * the library prints nothing; GDAL's last message is folded into ours.
 */
/* VSIStatL fills a struct stat64, which glibc declares only with this. */
#define _LARGEFILE64_SOURCE 1

#include "dem/dem_internal.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_vsi.h>
#include <gdal.h>
#include <ogr_srs_api.h>

/* Neighbour order E, SE, S, SW, W, NW, N, NE: the ESRI direction codes
 * 1, 2, 4, ..., 128, so a D8 grid from dfle reads like ArcGIS's. */
const int dfle_dem_nb_dr[8] = {0, 1, 1, 1, 0, -1, -1, -1};
const int dfle_dem_nb_dc[8] = {1, 1, 0, -1, -1, -1, 0, 1};

double dfle_dem_nb_dist(const struct dfle_dem *d, int k)
{
    if (dfle_dem_nb_dr[k] == 0)
        return d->dx;
    if (dfle_dem_nb_dc[k] == 0)
        return d->dy;
    return sqrt(d->dx * d->dx + d->dy * d->dy);
}

/* GDALAllRegister is not safe to race with itself; once per process. */
static pthread_once_t gdal_once = PTHREAD_ONCE_INIT;

static void gdal_register(void)
{
    GDALAllRegister();
}

static char *dup_string(const char *s)
{
    char *d;
    if (s == NULL)
        return NULL;
    d = malloc(strlen(s) + 1);
    if (d != NULL)
        strcpy(d, s);
    return d;
}

/* A zeroed DEM of nx x ny cells with its elevation array. */
static int dem_alloc(size_t nx, size_t ny, dfle_dem **out, dfle_error *err)
{
    dfle_dem *d;
    *out = NULL;
    if (nx == 0 || ny == 0)
        return dfle_error_set(err, DFLE_EINVAL, "dem: the grid has %zu x %zu cells; need at "
                              "least 1 x 1", nx, ny);
    /* Cell indices are kept as uint32 (order, queues): 4 bytes a cell
     * instead of 8 on the largest arrays. */
    if (nx > (size_t)UINT32_MAX / ny)
        return dfle_error_set(err, DFLE_EINVAL, "dem: %zu x %zu cells is more than dfle handles "
                              "(2^32 - 1); clip or resample the DEM", nx, ny);
    d = calloc(1, sizeof *d);
    if (d != NULL) {
        d->nx = nx;
        d->ny = ny;
        d->n = nx * ny;
        d->z = malloc(d->n * sizeof *d->z);
    }
    if (d == NULL || d->z == NULL) {
        free(d);
        return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory for %zu x %zu cells", nx, ny);
    }
    *out = d;
    return DFLE_OK;
}

void dfle_dem_free(dfle_dem *d)
{
    if (d == NULL)
        return;
    dfle_dem_unroute(d);
    free(d->z);
    free(d->path);
    free(d->crs_wkt);
    free(d->crs_name);
    free(d->linear_unit_name);
    free(d);
}

int dfle_dem_new(size_t nx, size_t ny, const double *z, const dfle_dem_geo *geo,
                 dfle_dem **out, dfle_error *err)
{
    dfle_dem *d;
    int st;

    *out = NULL;
    if (z == NULL || geo == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "dem: elevations and geometry are required");
    if (!(isfinite(geo->dx) && geo->dx > 0 && isfinite(geo->dy) && geo->dy > 0))
        return dfle_error_set(err, DFLE_EINVAL, "dem: cell size must be finite and > 0 m "
                              "(got dx = %g, dy = %g)", geo->dx, geo->dy);
    if (!(isfinite(geo->x0) && isfinite(geo->y0)))
        return dfle_error_set(err, DFLE_EINVAL, "dem: the grid's corner must be finite");
    if ((st = dem_alloc(nx, ny, &d, err)) != DFLE_OK)
        return st;
    d->x0 = geo->x0;
    d->y0 = geo->y0;
    d->dx = geo->dx;
    d->dy = geo->dy;
    for (size_t i = 0; i < d->n; i++) {
        d->z[i] = isfinite(z[i]) ? z[i] : NAN;
        d->n_nodata += !isfinite(z[i]);
    }
    if (d->n_nodata == d->n) {
        dfle_dem_free(d);
        return dfle_error_set(err, DFLE_EINVAL, "dem: every cell is NoData");
    }
    *out = d;
    return DFLE_OK;
}

/* ---------------------------------------------------------------- */
/* Reading                                                          */
/* ---------------------------------------------------------------- */

/* GDAL's last message, or a fallback, for folding into ours. */
static const char *gdal_message(const char *fallback)
{
    const char *m = CPLGetLastErrorMsg();
    return m != NULL && m[0] != '\0' ? m : fallback;
}

/* Record the CRS: name, WKT, EPSG code, geographic or not, linear unit. */
static int read_crs(dfle_dem *d, OGRSpatialReferenceH srs, dfle_error *err)
{
    char *wkt = NULL;
    const char *name, *auth;

    if (srs == NULL)
        return DFLE_OK;
    if (OSRExportToWkt(srs, &wkt) == OGRERR_NONE && wkt != NULL)
        d->crs_wkt = dup_string(wkt);
    CPLFree(wkt);
    name = OSRGetName(srs);
    d->crs_name = dup_string(name != NULL ? name : "unnamed CRS");
    if (d->crs_wkt == NULL || d->crs_name == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory");
    d->geographic = OSRIsGeographic(srs) != 0;
    if (OSRIsProjected(srs)) {
        char *unit = NULL;
        d->linear_unit = OSRGetLinearUnits(srs, &unit);
        d->linear_unit_name = dup_string(unit != NULL ? unit : "unknown");
        if (d->linear_unit_name == NULL)
            return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory");
    }
    /* The EPSG code when the file says it, else GDAL's best match (an
     * ESRI .prj carries names only); identification is best effort. */
    auth = OSRGetAuthorityName(srs, NULL);
    if (auth != NULL && strcmp(auth, "EPSG") == 0 && OSRGetAuthorityCode(srs, NULL) != NULL) {
        d->epsg = atoi(OSRGetAuthorityCode(srs, NULL));
    } else {
        int nm = 0, *conf = NULL;
        OGRSpatialReferenceH *m = OSRFindMatches(srs, NULL, &nm, &conf);
        /* 90% and up is PROJ's "same CRS, other names" (e.g. an ESRI
         * .prj of a UTM zone); lower scores are guesses. */
        if (m != NULL && nm > 0 && conf[0] >= 90) {
            auth = OSRGetAuthorityName(m[0], NULL);
            if (auth != NULL && strcmp(auth, "EPSG") == 0 &&
                OSRGetAuthorityCode(m[0], NULL) != NULL)
                d->epsg = atoi(OSRGetAuthorityCode(m[0], NULL));
        }
        OSRFreeSRSArray(m);
        CPLFree(conf);
    }
    CPLErrorReset(); /* a failed identification is not an error of ours */
    return DFLE_OK;
}

/* NoData from the file's mask (a per-dataset mask or alpha band), on top
 * of the NoData value, which the caller handles so it can be replaced. */
static int apply_mask(dfle_dem *d, GDALRasterBandH band, const char *path, dfle_error *err)
{
    int flags = GDALGetMaskFlags(band);
    unsigned char *m;
    GDALRasterBandH mb;

    if (flags & (GMF_ALL_VALID | GMF_NODATA))
        return DFLE_OK;
    if ((mb = GDALGetMaskBand(band)) == NULL)
        return DFLE_OK;
    if ((m = malloc(d->n)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory reading the mask of '%s'",
                              path);
    if (GDALRasterIO(mb, GF_Read, 0, 0, (int)d->nx, (int)d->ny, m, (int)d->nx, (int)d->ny,
                     GDT_Byte, 0, 0) != CE_None) {
        free(m);
        return dfle_error_set(err, DFLE_EIO, "dem: cannot read the mask of '%s': %s", path,
                              gdal_message("read error"));
    }
    for (size_t i = 0; i < d->n; i++)
        if (m[i] == 0)
            d->z[i] = NAN;
    free(m);
    return DFLE_OK;
}

static int metre_unit(const char *u)
{
    static const char *const ok[] = {"", "m", "metre", "meter", "metres", "meters", NULL};
    for (int k = 0; ok[k] != NULL; k++)
        if (strcmp(u, ok[k]) == 0)
            return 1;
    return 0;
}

/* Everything after GDALOpen: the dataset is closed by the caller. */
static int read_dataset(GDALDatasetH ds, const char *path, const dfle_dem_read_opts *o,
                        dfle_dem **out, dfle_error *err)
{
    double gt[6], nodata, scale, offset;
    int has_nodata = 0, band_no = o->band > 0 ? o->band : 1, nbands = GDALGetRasterCount(ds);
    GDALRasterBandH band;
    OGRSpatialReferenceH srs = NULL;
    const char *zunit;
    dfle_dem *d;
    int st;

    if (nbands < 1)
        return dfle_error_set(err, DFLE_EINVAL, "dem: '%s' has no raster band", path);
    if (band_no > nbands)
        return dfle_error_set(err, DFLE_EINVAL, "dem: band %d requested but '%s' has %d", band_no,
                              path, nbands);
    if (GDALGetGeoTransform(ds, gt) != CE_None)
        return dfle_error_set(err, DFLE_EINVAL,
                              "dem: '%s' has no georeferencing, so its cell size and position "
                              "are unknown", path);
    if (gt[2] != 0.0 || gt[4] != 0.0)
        return dfle_error_set(err, DFLE_EINVAL, "dem: '%s' is a rotated grid; warp it to a "
                              "north-up grid first (gdalwarp)", path);
    if (!(gt[1] > 0 && gt[5] < 0 && isfinite(gt[0]) && isfinite(gt[3])))
        return dfle_error_set(err, DFLE_EINVAL, "dem: '%s' is not a north-up grid (pixel size "
                              "%g x %g); warp it first (gdalwarp)", path, gt[1], gt[5]);
    band = GDALGetRasterBand(ds, band_no);
    zunit = GDALGetRasterUnitType(band);
    if (zunit != NULL && !metre_unit(zunit))
        return dfle_error_set(err, DFLE_EINVAL, "dem: elevations in '%s' are in '%s'; dfle "
                              "needs metres (convert with gdal_calc.py)", path, zunit);
    if ((st = dem_alloc((size_t)GDALGetRasterXSize(ds), (size_t)GDALGetRasterYSize(ds), &d,
                        err)) != DFLE_OK)
        return st;
    d->x0 = gt[0];
    d->y0 = gt[3];
    d->dx = gt[1];
    d->dy = -gt[5];
    if (GDALRasterIO(band, GF_Read, 0, 0, (int)d->nx, (int)d->ny, d->z, (int)d->nx, (int)d->ny,
                     GDT_Float64, 0, 0) != CE_None) {
        st = dfle_error_set(err, DFLE_EIO, "dem: cannot read '%s': %s", path,
                            gdal_message("read error"));
        goto fail;
    }
    nodata = GDALGetRasterNoDataValue(band, &has_nodata);
    if (o->set_nodata) {
        nodata = o->nodata;
        has_nodata = 1;
    }
    /* A Float32 file stores its NoData rounded to float; compare there. */
    {
        int f32 = GDALGetRasterDataType(band) == GDT_Float32;
        float nodata_f = (float)nodata;
        for (size_t i = 0; i < d->n; i++) {
            double v = d->z[i];
            if (!isfinite(v) ||
                (has_nodata && (f32 ? (float)v == nodata_f : v == nodata)))
                d->z[i] = NAN;
        }
    }
    if ((st = apply_mask(d, band, path, err)) != DFLE_OK)
        goto fail;
    scale = GDALGetRasterScale(band, NULL);
    offset = GDALGetRasterOffset(band, NULL);
    for (size_t i = 0; i < d->n; i++) {
        if (scale != 1.0 || offset != 0.0)
            d->z[i] = d->z[i] * scale + offset;
        d->n_nodata += isnan(d->z[i]);
    }
    if (d->n_nodata == d->n) {
        st = dfle_error_set(err, DFLE_EINVAL, "dem: every cell of '%s' is NoData (%g)", path,
                            nodata);
        goto fail;
    }
    if (o->crs != NULL) {
        srs = OSRNewSpatialReference(NULL);
        if (srs == NULL || OSRSetFromUserInput(srs, o->crs) != OGRERR_NONE) {
            OSRDestroySpatialReference(srs);
            st = dfle_error_set(err, DFLE_EINVAL, "dem: crs '%s' is not a CRS GDAL understands "
                                "(try 'EPSG:32611')", o->crs);
            goto fail;
        }
        st = read_crs(d, srs, err);
        OSRDestroySpatialReference(srs);
    } else {
        st = read_crs(d, GDALGetSpatialRef(ds), err);
    }
    if (st != DFLE_OK)
        goto fail;
    if ((d->path = dup_string(path)) == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory");
        goto fail;
    }
    *out = d;
    return DFLE_OK;
fail:
    dfle_dem_free(d);
    return st;
}

int dfle_dem_read(const char *path, const dfle_dem_read_opts *opts, dfle_dem **out,
                  dfle_error *err)
{
    static const dfle_dem_read_opts defaults = {0, 0, 0.0, NULL};
    const dfle_dem_read_opts *o = opts != NULL ? opts : &defaults;
    VSIStatBufL sb;
    GDALDatasetH ds;
    int st;

    *out = NULL;
    if (path == NULL || path[0] == '\0')
        return dfle_error_set(err, DFLE_EINVAL, "dem: path must be a file name");
    pthread_once(&gdal_once, gdal_register);
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
    if (VSIStatL(path, &sb) != 0) {
        st = dfle_error_set(err, DFLE_EIO, "dem: cannot read '%s': no such file", path);
    } else if (VSI_ISDIR(sb.st_mode)) {
        st = dfle_error_set(err, DFLE_EIO, "dem: cannot read '%s': it is a directory", path);
    } else if (!VSI_ISREG(sb.st_mode)) {
        /* GDAL would open a FIFO and wait for a writer for ever, or read
         * a device such as /dev/zero: rasters are files. */
        st = dfle_error_set(err, DFLE_EIO, "dem: cannot read '%s': not a regular file (a "
                            "device, pipe or socket)", path);
    } else if ((ds = GDALOpenEx(path, GDAL_OF_RASTER | GDAL_OF_READONLY, NULL, NULL, NULL)) ==
               NULL) {
        st = dfle_error_set(err, DFLE_EIO, "dem: cannot read '%s': %s", path,
                            gdal_message("not a raster format GDAL reads"));
    } else {
        st = read_dataset(ds, path, o, out, err);
        GDALClose(ds);
    }
    CPLPopErrorHandler();
    return st;
}

/* ---------------------------------------------------------------- */
/* Accessors and geometry                                           */
/* ---------------------------------------------------------------- */

size_t dfle_dem_nx(const dfle_dem *d) { return d->nx; }
size_t dfle_dem_ny(const dfle_dem *d) { return d->ny; }
double dfle_dem_dx(const dfle_dem *d) { return d->dx; }
double dfle_dem_dy(const dfle_dem *d) { return d->dy; }
const double *dfle_dem_z(const dfle_dem *d) { return d->z; }
size_t dfle_dem_nodata_count(const dfle_dem *d) { return d->n_nodata; }
const char *dfle_dem_path(const dfle_dem *d) { return d->path; }
const char *dfle_dem_crs_name(const dfle_dem *d) { return d->crs_name; }
const char *dfle_dem_crs_wkt(const dfle_dem *d) { return d->crs_wkt; }
int dfle_dem_epsg(const dfle_dem *d) { return d->epsg; }
int dfle_dem_is_geographic(const dfle_dem *d) { return d->geographic; }

void dfle_dem_extent(const dfle_dem *d, double ext[4])
{
    ext[0] = d->x0;
    ext[1] = d->x0 + (double)d->nx * d->dx;
    ext[2] = d->y0 - (double)d->ny * d->dy;
    ext[3] = d->y0;
}

/* A grid with no CRS whose cells are under 0.01 units and whose extent
 * fits in longitude/latitude is almost surely in degrees (an ESRI ASCII
 * grid without its .prj); a metric DEM with 1 cm cells at the origin is
 * the only false alarm, and `crs` overrides it. */
static int looks_like_degrees(const dfle_dem *d)
{
    double e[4];
    dfle_dem_extent(d, e);
    return d->crs_wkt == NULL && d->dx < 0.01 && d->dy < 0.01 && e[0] >= -360 &&
           e[1] <= 360 && e[2] >= -90 && e[3] <= 90;
}

int dfle_dem_check_metric(const dfle_dem *d, const char *what, dfle_error *err)
{
    const char *name = d->path != NULL ? d->path : "the grid";
    if (d->geographic)
        return dfle_error_set(err, DFLE_EINVAL,
                              "dem: %s needs a grid in metres, but '%s' is in a geographic CRS "
                              "(%s; cell size %g x %g degrees); reproject it to a projected CRS "
                              "in metres first, e.g. gdalwarp -t_srs EPSG:32611 (UTM 11N)",
                              what, name, d->crs_name, d->dx, d->dy);
    if (d->linear_unit > 0 && fabs(d->linear_unit - 1.0) > 1e-12)
        return dfle_error_set(err, DFLE_EINVAL,
                              "dem: %s needs a grid in metres, but the CRS of '%s' (%s) is in "
                              "'%s' (%g m); reproject it to a CRS in metres first (gdalwarp)",
                              what, name, d->crs_name, d->linear_unit_name, d->linear_unit);
    if (looks_like_degrees(d))
        return dfle_error_set(err, DFLE_EINVAL,
                              "dem: %s needs a grid in metres, but '%s' has no CRS and its cell "
                              "size (%g) and coordinates look like degrees; reproject it, or "
                              "say it is metric with dfle.dem.read(path, {crs = ...})",
                              what, name, d->dx);
    return DFLE_OK;
}

int dfle_dem_cell_at(const dfle_dem *d, double E, double N, const char *what, size_t *index,
                     dfle_error *err)
{
    double e[4], c, r;
    dfle_dem_extent(d, e);
    c = floor((E - d->x0) / d->dx);
    r = floor((d->y0 - N) / d->dy);
    if (!(isfinite(E) && isfinite(N) && c >= 0 && r >= 0 && c < (double)d->nx &&
          r < (double)d->ny))
        return dfle_error_set(err, DFLE_EINVAL,
                              "dem: %s (%.10g E, %.10g N) is outside the grid (E %.0f..%.0f, "
                              "N %.0f..%.0f)", what, E, N, e[0], e[1], e[2], e[3]);
    *index = (size_t)r * d->nx + (size_t)c;
    return DFLE_OK;
}

void dfle_dem_cell_centre(const dfle_dem *d, size_t index, double *E, double *N)
{
    size_t r = index / d->nx, c = index % d->nx;
    *E = d->x0 + ((double)c + 0.5) * d->dx;
    *N = d->y0 - ((double)r + 0.5) * d->dy;
}
