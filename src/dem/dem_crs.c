/*
 * dem_crs.c - coordinate reference systems through GDAL's OSR (crs.h).
 *
 * The lowest file of src/dem/: it knows nothing of DEMs, and the reader
 * (dem.c) describes a file's CRS through it.  Every call silences GDAL's
 * error printer for its duration (the library prints nothing) and folds
 * GDAL's last message into dfle's where one helps.
 */
#include "dfle/crs.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/gdal_lib.h" /* GDAL, loaded by the first call */
#include "dem/dem_crs.h"

/* A spatial reference from any text GDAL reads, or NULL. */
static OGRSpatialReferenceH srs_from(const char *text)
{
    OGRSpatialReferenceH srs = OSRNewSpatialReference(NULL);
    if (srs != NULL && OSRSetFromUserInput(srs, text) != OGRERR_NONE) {
        OSRDestroySpatialReference(srs);
        srs = NULL;
    }
    return srs;
}

static void copy_text(char *dst, size_t cap, const char *src)
{
    snprintf(dst, cap, "%s", src != NULL ? src : "");
}

/* The EPSG code the CRS carries, else GDAL's match at >= 90%: PROJ's
 * "same CRS, other names" (an ESRI .prj of a UTM zone); lower scores are
 * guesses and give 0. */
static int epsg_of(OGRSpatialReferenceH srs)
{
    const char *auth = OSRGetAuthorityName(srs, NULL);
    int code = 0, nm = 0, *conf = NULL;
    OGRSpatialReferenceH *m;
    if (auth != NULL && strcmp(auth, "EPSG") == 0 && OSRGetAuthorityCode(srs, NULL) != NULL)
        return atoi(OSRGetAuthorityCode(srs, NULL));
    m = OSRFindMatches(srs, NULL, &nm, &conf);
    if (m != NULL && nm > 0 && conf[0] >= 90) {
        auth = OSRGetAuthorityName(m[0], NULL);
        if (auth != NULL && strcmp(auth, "EPSG") == 0 && OSRGetAuthorityCode(m[0], NULL) != NULL)
            code = atoi(OSRGetAuthorityCode(m[0], NULL));
    }
    OSRFreeSRSArray(m);
    CPLFree(conf);
    return code;
}

void dem_crs_describe(OGRSpatialReferenceH srs, dfle_crs_info *info)
{
    memset(info, 0, sizeof *info);
    copy_text(info->name, sizeof info->name,
              OSRGetName(srs) != NULL ? OSRGetName(srs) : "unnamed CRS");
    info->geographic = OSRIsGeographic(srs) != 0;
    info->projected = OSRIsProjected(srs) != 0;
    if (info->projected) {
        char *unit = NULL;
        info->linear_unit = OSRGetLinearUnits(srs, &unit);
        copy_text(info->linear_unit_name, sizeof info->linear_unit_name,
                  unit != NULL ? unit : "unknown");
    }
    copy_text(info->geographic_name, sizeof info->geographic_name,
              OSRGetAttrValue(srs, "GEOGCS", 0));
    info->epsg = epsg_of(srs);
    CPLErrorReset(); /* a failed identification is not an error of ours */
}

int dfle_crs_info_of(const char *wkt, dfle_crs_info *info, dfle_error *err)
{
    OGRSpatialReferenceH srs;
    int st;
    if ((st = dfle_gdal_load("crs", err)) != DFLE_OK)
        return st;
    CPLPushErrorHandler(CPLQuietErrorHandler);
    if ((srs = srs_from(wkt)) == NULL) {
        st = dfle_error_set(err, DFLE_EINVAL, "crs: GDAL cannot read the CRS '%.60s%s'", wkt,
                            strlen(wkt) > 60 ? "..." : "");
    } else {
        dem_crs_describe(srs, info);
        OSRDestroySpatialReference(srs);
    }
    CPLPopErrorHandler();
    return st;
}

int dfle_crs_from_text(const char *text, const char *what, int metric, char *wkt, size_t cap,
                       dfle_crs_info *info, dfle_error *err)
{
    OGRSpatialReferenceH srs;
    dfle_crs_info mine;
    char *w = NULL;
    int st;

    if (cap > 0)
        wkt[0] = '\0';
    if (info == NULL)
        info = &mine;
    if (text == NULL || text[0] == '\0')
        return dfle_error_set(err, DFLE_EINVAL, "%s: the CRS is empty (give e.g. 'EPSG:32611')",
                              what);
    if ((st = dfle_gdal_load(what, err)) != DFLE_OK)
        return st;
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
    if ((srs = srs_from(text)) == NULL) {
        st = dfle_error_set(err, DFLE_EINVAL, "%s: '%.80s%s' is not a CRS GDAL understands (give "
                            "an EPSG code such as 'EPSG:32611', WKT or a PROJ string)", what,
                            text, strlen(text) > 80 ? "..." : "");
        CPLPopErrorHandler();
        return st;
    }
    dem_crs_describe(srs, info);
    if (metric && !(info->projected && fabs(info->linear_unit - 1.0) < 1e-12)) {
        char label[320];
        dfle_crs_label(info, label, sizeof label);
        st = dfle_error_set(err, DFLE_EINVAL, "%s: %s is %s; the grid's cells are in metres, so "
                            "its CRS must be a projected one in metres (a UTM zone, say "
                            "'EPSG:32611')", what, label,
                            info->geographic ? "a geographic CRS (degrees)"
                            : info->projected ? "in another unit than metres"
                                              : "not a projected CRS");
    } else if (OSRExportToWkt(srs, &w) != OGRERR_NONE || w == NULL) {
        st = dfle_error_set(err, DFLE_EINVAL, "%s: GDAL cannot write '%s' as WKT", what, text);
    } else if (strlen(w) >= cap) {
        st = dfle_error_set(err, DFLE_EINVAL, "%s: the WKT of '%.40s' is %zu bytes, more than "
                            "dfle keeps (%zu)", what, text, strlen(w), cap - 1);
    } else {
        memcpy(wkt, w, strlen(w) + 1);
    }
    CPLFree(w);
    OSRDestroySpatialReference(srs);
    CPLPopErrorHandler();
    return st;
}

int dfle_crs_same(const char *wkt_a, const char *wkt_b)
{
    OGRSpatialReferenceH a, b;
    int same = 0;
    dfle_error err;
    if (dfle_gdal_load("crs", &err) != DFLE_OK)
        return 0;
    CPLPushErrorHandler(CPLQuietErrorHandler);
    a = srs_from(wkt_a);
    b = srs_from(wkt_b);
    if (a != NULL && b != NULL)
        same = OSRIsSame(a, b) != 0;
    if (a != NULL)
        OSRDestroySpatialReference(a);
    if (b != NULL)
        OSRDestroySpatialReference(b);
    CPLErrorReset();
    CPLPopErrorHandler();
    return same;
}

void dfle_crs_label(const dfle_crs_info *info, char *buf, size_t cap)
{
    if (info->epsg > 0)
        snprintf(buf, cap, "%s (EPSG:%d)", info->name, info->epsg);
    else
        snprintf(buf, cap, "%s", info->name);
}

int dfle_crs_lonlat(const char *wkt, size_t n, const double *E, const double *N, double *lon,
                    double *lat, dfle_error *err)
{
    OGRSpatialReferenceH src = NULL, geo = NULL;
    OGRCoordinateTransformationH ct = NULL;
    int st;

    if ((st = dfle_gdal_load("crs", err)) != DFLE_OK)
        return st;
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
    if ((src = srs_from(wkt)) == NULL || (geo = OSRCloneGeogCS(src)) == NULL) {
        st = dfle_error_set(err, DFLE_EINVAL, "crs: GDAL cannot read the CRS to give longitude "
                            "and latitude");
        goto done;
    }
    /* (E, N) in and (longitude, latitude) out, whatever order the
     * definitions give their axes. */
    OSRSetAxisMappingStrategy(src, OAMS_TRADITIONAL_GIS_ORDER);
    OSRSetAxisMappingStrategy(geo, OAMS_TRADITIONAL_GIS_ORDER);
    if ((ct = OCTNewCoordinateTransformation(src, geo)) == NULL) {
        st = dfle_error_set(err, DFLE_EINVAL, "crs: no transformation to longitude and latitude "
                            "(%s)", CPLGetLastErrorMsg());
        goto done;
    }
    memcpy(lon, E, n * sizeof *lon);
    memcpy(lat, N, n * sizeof *lat);
    for (size_t k = 0; k < n;) {
        int m = n - k > 1u << 20 ? 1 << 20 : (int)(n - k);
        if (!OCTTransform(ct, m, lon + k, lat + k, NULL)) {
            /* All or nothing per call: point by point, NaN where one fails. */
            for (int i = 0; i < m; i++) {
                double x = E[k + i], y = N[k + i];
                if (OCTTransform(ct, 1, &x, &y, NULL))
                    lon[k + i] = x, lat[k + i] = y;
                else
                    lon[k + i] = lat[k + i] = NAN;
            }
        }
        k += (size_t)m;
    }
done:
    if (ct != NULL)
        OCTDestroyCoordinateTransformation(ct);
    if (geo != NULL)
        OSRDestroySpatialReference(geo);
    if (src != NULL)
        OSRDestroySpatialReference(src);
    CPLErrorReset();
    CPLPopErrorHandler();
    return st;
}
