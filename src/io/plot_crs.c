/*
 * plot_crs.c - the name a map gives its coordinate reference system:
 * the EPSG code for the axis labels ("Easting (km, EPSG:32611)") and
 * the CRS's own name beside the scale bar ("WGS 84 / UTM zone 11N").
 *
 * Maps are drawn in kilometres of the grid's coordinates, so the CRS
 * must be projected and in metres; a geographic CRS (degrees) or one in
 * feet would give a false scale bar and is refused.  What the CRS is
 * comes from crs.h (GDAL, loaded only for a map that has a CRS).
 */
#include "io/plot_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "base/gdal_lib.h"
#include "dfle/crs.h"

int dfle_gp_crs_names(const char *crs, char *code, size_t ccap, char *name, size_t ncap,
                      dfle_error *err)
{
    dfle_crs_info info;
    dfle_error why;
    int rc;
    code[0] = name[0] = '\0';
    if (crs == NULL || crs[0] == '\0')
        return DFLE_OK;
    if ((rc = dfle_gdal_load("plot", err)) != DFLE_OK)
        return rc; /* its message says what to install */
    dfle_error_clear(&why);
    if (dfle_crs_info_of(crs, &info, &why) != DFLE_OK)
        return dfle_error_set(err, DFLE_EINVAL, "plot: the map's CRS is not one GDAL reads "
                              "(%.60s%s)", crs, strlen(crs) > 60 ? "..." : "");
    if (info.geographic)
        return dfle_error_set(err, DFLE_EINVAL, "plot: the map's CRS (%s) is geographic: a map "
                              "is drawn in km of a projected CRS in metres; reproject the grid",
                              info.name);
    if (info.projected && fabs(info.linear_unit - 1.0) > 1e-9)
        return dfle_error_set(err, DFLE_EINVAL, "plot: the map's CRS (%s) is in %s, not "
                              "metres: a map is drawn in km of a CRS in metres", info.name,
                              info.linear_unit_name);
    if (info.epsg > 0)
        snprintf(code, ccap, "EPSG:%d", info.epsg);
    snprintf(name, ncap, "%s", info.name);
    return DFLE_OK;
}
