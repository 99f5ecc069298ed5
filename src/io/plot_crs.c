/*
 * plot_crs.c - the name a map gives its coordinate reference system:
 * the EPSG code for the axis labels ("Easting (km, EPSG:32611)") and
 * the CRS's own name beside the scale bar ("WGS 84 / UTM zone 11N").
 *
 * Maps are drawn in kilometres of the grid's coordinates, so the CRS
 * must be projected and in metres; a geographic CRS (degrees) or one in
 * feet would give a false scale bar and is refused.  GDAL is loaded
 * here only for a map that has a CRS.
 */
#include "io/plot_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "base/gdal_lib.h"

/* The EPSG code of srs, as the file says it or as GDAL's match at 90 %
 * confidence or more (an ESRI .prj names its CRS without a code). */
static void epsg_of(OGRSpatialReferenceH srs, char *code, size_t cap)
{
    const char *auth = OSRGetAuthorityName(srs, NULL);
    code[0] = '\0';
    if (auth != NULL && strcmp(auth, "EPSG") == 0 && OSRGetAuthorityCode(srs, NULL) != NULL) {
        snprintf(code, cap, "EPSG:%s", OSRGetAuthorityCode(srs, NULL));
        return;
    }
    {
        int nm = 0, *conf = NULL;
        OGRSpatialReferenceH *m = OSRFindMatches(srs, NULL, &nm, &conf);
        if (m != NULL && nm > 0 && conf[0] >= 90) {
            auth = OSRGetAuthorityName(m[0], NULL);
            if (auth != NULL && strcmp(auth, "EPSG") == 0 &&
                OSRGetAuthorityCode(m[0], NULL) != NULL)
                snprintf(code, cap, "EPSG:%s", OSRGetAuthorityCode(m[0], NULL));
        }
        OSRFreeSRSArray(m);
        CPLFree(conf);
    }
}

int dfle_gp_crs_names(const char *crs, char *code, size_t ccap, char *name, size_t ncap,
                      dfle_error *err)
{
    OGRSpatialReferenceH srs;
    int rc = DFLE_OK;
    code[0] = name[0] = '\0';
    if (crs == NULL || crs[0] == '\0')
        return DFLE_OK;
    if ((rc = dfle_gdal_load("plot", err)) != DFLE_OK)
        return rc;
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
    srs = OSRNewSpatialReference(NULL);
    if (srs == NULL || OSRSetFromUserInput(srs, crs) != OGRERR_NONE) {
        rc = dfle_error_set(err, DFLE_EINVAL, "plot: the map's CRS is not one GDAL reads "
                            "(%.60s%s)", crs, strlen(crs) > 60 ? "..." : "");
    } else if (OSRIsGeographic(srs)) {
        rc = dfle_error_set(err, DFLE_EINVAL, "plot: the map's CRS (%s) is geographic: a map "
                            "is drawn in km of a projected CRS in metres; reproject the grid",
                            OSRGetName(srs) != NULL ? OSRGetName(srs) : "unnamed");
    } else {
        char *unit = NULL;
        double metres = OSRIsProjected(srs) ? OSRGetLinearUnits(srs, &unit) : 1.0;
        if (fabs(metres - 1.0) > 1e-9) {
            rc = dfle_error_set(err, DFLE_EINVAL, "plot: the map's CRS (%s) is in %s, not "
                                "metres: a map is drawn in km of a CRS in metres",
                                OSRGetName(srs) != NULL ? OSRGetName(srs) : "unnamed",
                                unit != NULL ? unit : "another unit");
        } else {
            const char *nm = OSRGetName(srs);
            epsg_of(srs, code, ccap);
            snprintf(name, ncap, "%s", nm != NULL ? nm : "");
        }
    }
    OSRDestroySpatialReference(srs);
    CPLErrorReset();
    CPLPopErrorHandler();
    return rc;
}
