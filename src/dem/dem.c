/*
 * dem.c - the DEM object: making it from an array or from any raster
 * GDAL reads (georeferencing, NoData, the CRS), and freeing it.
 * Geometry and the CRS checks are dem_grid.c; filling and routing
 * dem_flow.c, which this file never calls (dem_internal.h).
 *
 * GDAL is the only place dfle meets file formats, so everything that
 * depends on a file's conventions (NoData values, masks, scale and
 * offset, the CRS) is settled here, once: after dfle_dem_read the grid
 * is plain doubles in metres with NaN for "no data", and the routing
 * and profile code never asks where it came from.  GDAL's own error
 * printer is replaced by a quiet one for the duration of each call, so
 * the library prints nothing; GDAL's last message is folded into ours.
 * GDAL itself is loaded by the first read (base/gdal_lib.h), so a
 * process that never reads a DEM never loads it.
 */
/* VSIStatL fills a struct stat64, which glibc declares only with this. */
#define _LARGEFILE64_SOURCE 1

#include "dem/dem_internal.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h> /* strcasecmp */

#include "base/gdal_lib.h" /* GDAL, loaded by the first dfle_dem_read */
#include "dfle/crs.h"
#include "dem/dem_crs.h"
#include "dem/dem_gdal.h"
#include "dem/dem_tiff.h"

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


/* Elevations are metres on Earth, within +-11 km.  A magnitude past
 * 10 000 km is no elevation in any unit a DEM uses: a corrupt file, an
 * undeclared NoData such as -3.4e38, or data that are not heights.
 * Such values would pass through filling and routing as numbers and
 * come out as slopes of 1e30, so they are refused; merely odd values
 * only warn (dfle_dem_check_plausible). */
#define DEM_Z_LIMIT 1e7

static int check_elevations(const dfle_dem *d, const char *path, dfle_error *err)
{
    const char *q = path != NULL ? "'" : "", *where = path != NULL ? path : "the grid";
    for (size_t i = 0; i < d->n; i++)
        if (fabs(d->z[i]) >= DEM_Z_LIMIT) /* false for NaN (NoData) */
            return dfle_error_set(err, DFLE_EINVAL,
                                  "dem: %s%s%s holds %g at row %zu, column %zu, which is no "
                                  "elevation in metres; if it marks missing data, declare it "
                                  "(nodata = %g)", q, where, q, d->z[i], i / d->nx + 1, i % d->nx + 1,
                                  d->z[i]);
    return DFLE_OK;
}

/* 1 when coordinates out to the grid's far corner still tell cells
 * apart: far out, the centres of neighbouring cells round to one
 * coordinate (a tie point of 1e300 made them all the same, and maps
 * failed later, in gnuplot). */
static int corner_resolved(double x0, double y0, double x1, double y1, double dx, double dy)
{
    const double far = fmax(fmax(fabs(x0), fabs(x1)), fmax(fabs(y0), fabs(y1)));
    return far * DBL_EPSILON <= 1e-4 * fmin(dx, dy);
}

/* Cell sizes past 1000 km, a grid whose far edge overflows, or a tie
 * point so far out that its cells cannot be told apart, come from a
 * damaged header, not from a DEM (degrees are far below the limits). */
static int check_geometry(const char *path, const double gt[6], int nx, int ny, dfle_error *err)
{
    double east = gt[0] + (double)nx * gt[1], south = gt[3] + (double)ny * gt[5];
    if (gt[1] > 1e6 || -gt[5] > 1e6 || !isfinite(east) || !isfinite(south) ||
        !corner_resolved(gt[0], gt[3], east, south, gt[1], -gt[5]))
        return dfle_error_set(err, DFLE_EINVAL, "dem: '%s' has cells of %g x %g and its corner at "
                              "(%g, %g): not the geometry of a DEM; is its header damaged?",
                              path, gt[1], -gt[5], gt[0], gt[3]);
    return DFLE_OK;
}

/* A header keyword's value must be one number: GDAL reads
 * "NODATA_value abc" as NoData 0, so that the file's real marker (say
 * -9999) becomes an elevation and the cells it marks deep pits. */
static int check_header_value(const char *path, size_t line, const char *key, char *value,
                              dfle_error *err)
{
    static const char *const keys[] = { "ncols", "nrows", "xllcorner", "yllcorner", "xllcenter",
                                         "yllcenter", "cellsize", "dx", "dy", "nodata_value" };
    size_t i, len = strlen(value);
    char *start = value, *end;

    for (i = 0; i < sizeof keys / sizeof keys[0]; i++)
        if (strcasecmp(key, keys[i]) == 0)
            break;
    if (i == sizeof keys / sizeof keys[0])
        return DFLE_OK; /* a keyword GDAL knows and we do not: its business */
    while (len > 0 && (value[len - 1] == ' ' || value[len - 1] == '\t' || value[len - 1] == '\r'))
        value[--len] = '\0';
    while (*start == ' ' || *start == '\t')
        start++;
    (void)strtod(start, &end);
    if (end == start || *end != '\0')
        return dfle_error_set(err, DFLE_EINVAL, "dem: '%s' line %zu: the header's %s is '%s', "
                              "not a number; is the header damaged?", path, line, key, start);
    return DFLE_OK;
}

/* GDAL's ESRI ASCII reader takes a word it cannot parse ("x", "1,5")
 * as 0 and ignores values past the last row, both without a word; a
 * hand-edited or script-written grid gets both wrong often enough to
 * read it once more and check every value is a number, n in all. */
static int check_ascii_values(const char *path, size_t n, dfle_error *err)
{
    FILE *f = fopen(path, "r");
    char word[128];
    size_t count = 0, line = 1;
    int c, in_header = 1, st = DFLE_OK;

    if (f == NULL)
        return dfle_error_set(err, DFLE_EIO, "dem: cannot read '%s' again to check it", path);
    while (st == DFLE_OK) {
        size_t len = 0;
        while ((c = getc(f)) != EOF && (c == ' ' || c == '\t' || c == '\r' || c == '\n'))
            line += c == '\n';
        if (c == EOF)
            break;
        while (c != EOF && c != ' ' && c != '\t' && c != '\r' && c != '\n') {
            if (len + 1 < sizeof word)
                word[len++] = (char)c;
            c = getc(f);
        }
        word[len] = '\0';
        if (c == '\n')
            ungetc(c, f);
        /* Header lines start with a keyword (ncols, cellsize, ...):
         * skip the line; values begin at the first numeric word. */
        if (in_header && ((word[0] >= 'a' && word[0] <= 'z') || (word[0] >= 'A' && word[0] <= 'Z'))) {
            char value[128];
            size_t vlen = 0;
            while ((c = getc(f)) != EOF && c != '\n')
                if (vlen + 1 < sizeof value)
                    value[vlen++] = (char)c;
            value[vlen] = '\0';
            st = check_header_value(path, line, word, value, err);
            line++;
            continue;
        }
        in_header = 0;
        {
            char *end;
            (void)strtod(word, &end);
            if (end == word || *end != '\0')
                st = dfle_error_set(err, DFLE_EINVAL, "dem: '%s' line %zu: '%s' is not a number "
                                    "(value %zu of %zu)", path, line, word, count + 1, n);
        }
        count++;
    }
    if (st == DFLE_OK && ferror(f))
        st = dfle_error_set(err, DFLE_EIO, "dem: cannot read '%s' again to check it", path);
    if (st == DFLE_OK && count != n)
        st = dfle_error_set(err, DFLE_EINVAL, "dem: '%s' holds %zu values where its header "
                            "(ncols x nrows) says %zu", path, count, n);
    fclose(f);
    return st;
}
void dfle_dem_free(dfle_dem *d)
{
    if (d == NULL)
        return;
    dfle_drainage_free(d->flow);
    free(d->order);
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
    if (!corner_resolved(geo->x0, geo->y0, geo->x0 + (double)nx * geo->dx,
                         geo->y0 - (double)ny * geo->dy, geo->dx, geo->dy))
        return dfle_error_set(err, DFLE_EINVAL, "dem: the grid's corner (%g, %g) is so far out "
                              "that cells of %g x %g cannot be told apart there", geo->x0,
                              geo->y0, geo->dx, geo->dy);
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
    if ((st = check_elevations(d, NULL, err)) != DFLE_OK) {
        dfle_dem_free(d);
        return st;
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
    dfle_crs_info info;

    if (srs == NULL)
        return DFLE_OK;
    if (OSRExportToWkt(srs, &wkt) == OGRERR_NONE && wkt != NULL)
        d->crs_wkt = dup_string(wkt);
    CPLFree(wkt);
    if (d->crs_wkt == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory");
    dem_crs_describe(srs, &info);
    d->crs_name = dup_string(info.name);
    d->geographic = info.geographic;
    d->epsg = info.epsg;
    if (info.projected) {
        d->linear_unit = info.linear_unit;
        d->linear_unit_name = dup_string(info.linear_unit_name);
        if (d->linear_unit_name == NULL)
            return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory");
    }
    if (d->crs_name == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory");
    return DFLE_OK;
}

int dfle_dem_set_crs(dfle_dem *d, const char *crs, dfle_error *err)
{
    dfle_crs_info info;
    char *buf = malloc(DFLE_CRS_WKT_MAX), *wkt = NULL, *name = NULL, *unit = NULL;
    int st;
    if (buf == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory");
    if ((st = dfle_crs_from_text(crs, "dem: crs", 0, buf, DFLE_CRS_WKT_MAX, &info, err)) !=
        DFLE_OK) {
        free(buf);
        return st;
    }
    wkt = dup_string(buf);
    name = dup_string(info.name);
    if (info.projected)
        unit = dup_string(info.linear_unit_name);
    free(buf);
    if (wkt == NULL || name == NULL || (info.projected && unit == NULL)) {
        free(wkt), free(name), free(unit);
        return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory");
    }
    free(d->crs_wkt), free(d->crs_name), free(d->linear_unit_name);
    d->crs_wkt = wkt;
    d->crs_name = name;
    d->linear_unit_name = unit;
    d->linear_unit = info.projected ? info.linear_unit : 0.0;
    d->geographic = info.geographic;
    d->epsg = info.epsg;
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
    if (!(gt[1] > 0 && gt[5] < 0 && isfinite(gt[1]) && isfinite(gt[5]) && isfinite(gt[0]) &&
          isfinite(gt[3])))
        return dfle_error_set(err, DFLE_EINVAL, "dem: '%s' is not a north-up grid (pixel size "
                              "%g x %g); warp it first (gdalwarp)", path, gt[1], gt[5]);
    if ((st = check_geometry(path, gt, GDALGetRasterXSize(ds), GDALGetRasterYSize(ds), err)) !=
        DFLE_OK)
        return st;
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
    if (has_nodata && !o->set_nodata &&
        strcmp(GDALGetDriverShortName(GDALGetDatasetDriver(ds)), "GTiff") == 0) {
        /* GDAL reads a tag that is no number as 0 (dem_tiff.c). */
        char text[256];
        if (dem_tiff_nodata_text(path, text, sizeof text) && !dem_tiff_nodata_valid(text)) {
            st = dfle_error_set(err, DFLE_EINVAL, "dem: '%s' declares its NoData value as '%s' "
                                "(the GDAL_NODATA tag), which is not a number; GDAL would read "
                                "it as %g and take every cell of that elevation for NoData. Fix "
                                "the file (gdal_edit.py -a_nodata <value> '%s') or say what "
                                "marks missing data: dfle.dem.read(path, { nodata = ... })",
                                path, text, nodata, path);
            goto fail;
        }
    }
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
    if (!(isfinite(scale) && isfinite(offset) && scale != 0.0)) {
        st = dfle_error_set(err, DFLE_EINVAL, "dem: '%s' declares a scale %g and offset %g for its "
                            "values; they must be finite and the scale non-zero", path, scale,
                            offset);
        goto fail;
    }
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
    if ((st = check_elevations(d, path, err)) != DFLE_OK)
        goto fail;
    if (strcmp(GDALGetDriverShortName(GDALGetDatasetDriver(ds)), "AAIGrid") == 0 &&
        (st = check_ascii_values(path, d->n, err)) != DFLE_OK)
        goto fail;
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

GDALDatasetH dem_to_gdal(const dfle_dem *d, dfle_error *err)
{
    GDALDriverH drv = GDALGetDriverByName("MEM");
    GDALDatasetH ds;
    double gt[6] = {d->x0, d->dx, 0.0, d->y0, 0.0, -d->dy};
    GDALRasterBandH band;
    if (drv == NULL ||
        (ds = GDALCreate(drv, "", (int)d->nx, (int)d->ny, 1, GDT_Float64, NULL)) == NULL) {
        dfle_error_set(err, DFLE_ENOMEM, "dem: GDAL cannot hold the grid in memory: %s",
                       gdal_message("no MEM driver"));
        return NULL;
    }
    GDALSetGeoTransform(ds, gt);
    if (d->crs_wkt != NULL)
        GDALSetProjection(ds, d->crs_wkt);
    band = GDALGetRasterBand(ds, 1);
    GDALSetRasterNoDataValue(band, NAN);
    if (GDALRasterIO(band, GF_Write, 0, 0, (int)d->nx, (int)d->ny, d->z, (int)d->nx, (int)d->ny,
                     GDT_Float64, 0, 0) != CE_None) {
        dfle_error_set(err, DFLE_EIO, "dem: GDAL cannot take the grid: %s",
                       gdal_message("write error"));
        GDALClose(ds);
        return NULL;
    }
    return ds;
}

int dem_from_gdal(GDALDatasetH ds, const char *what, dfle_dem **out, dfle_error *err)
{
    static const dfle_dem_read_opts defaults = {0, 0, 0.0, NULL};
    int st = read_dataset(ds, what, &defaults, out, err);
    if (st == DFLE_OK) {
        free((*out)->path);
        (*out)->path = NULL; /* made in memory: no file */
    }
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
    if ((st = dfle_gdal_load("dem.read", err)) != DFLE_OK)
        return st;
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
/* Plausibility                                                     */
/* ---------------------------------------------------------------- */

int dfle_dem_check_plausible(const dfle_dem *d, char *msg, size_t cap)
{
    /* Markers GIS software writes for "no data"; a file that holds them
     * without declaring them reads them as real, deep pits or peaks. */
    static const double markers[] = {-9999.0, -99999.0, -32768.0, -32767.0, 32767.0, 65535.0};
    size_t count[sizeof markers / sizeof markers[0]] = {0};
    double lo = INFINITY, hi = -INFINITY;

    for (size_t i = 0; i < d->n; i++) {
        double z = d->z[i];
        if (isnan(z))
            continue;
        lo = z < lo ? z : lo;
        hi = z > hi ? z : hi;
        for (size_t k = 0; k < sizeof markers / sizeof markers[0]; k++)
            count[k] += z == markers[k];
    }
    for (size_t k = 0; k < sizeof markers / sizeof markers[0]; k++)
        if (count[k] > 0) {
            snprintf(msg, cap, "%zu cell%s hold %g, a common NoData marker that the file does not "
                     "declare; read as elevations they make %s that filling and routing honour; if "
                     "%g marks missing data, pass nodata = %g", count[k], count[k] == 1 ? "" : "s",
                     markers[k], markers[k] < 0 ? "deep pits" : "high peaks", markers[k],
                     markers[k]);
            return 1;
        }
    /* The land surface spans -430 m (Dead Sea) to 8849 m (Everest). */
    if (lo < -500.0 || hi > 9000.0) {
        snprintf(msg, cap, "elevations run from %g to %g m, beyond any on land (-430 to 8849 m): "
                 "are they in metres (not feet or centimetres), and is every missing value "
                 "declared as NoData?", lo, hi);
        return 1;
    }
    return 0;
}
