/*
 * crs.h - coordinate reference systems, through GDAL's OSR: a CRS a user
 * names (an EPSG code, WKT, a PROJ string) checked and kept as WKT, what
 * it is (its name, EPSG code, units), and map coordinates turned into
 * longitude and latitude.
 *
 * dfle never reprojects a grid: a CRS says where a grid in metres lies.
 * Longitude and latitude are given on the CRS's own geographic CRS (the
 * same datum, so no datum shift and no transformation grid is needed):
 * WGS 84 for a WGS 84 / UTM grid, NAD83 for a NAD83 one.  GDAL is
 * loaded by the first call (it is not linked); DFLE_EEXTERNAL, saying
 * what to install, where it cannot be.
 */
#ifndef DFLE_CRS_H
#define DFLE_CRS_H

#include <stddef.h>

#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_crs_info {
    char name[256];             /* "WGS 84 / UTM zone 11N"                 */
    int epsg;                   /* 32611; 0 when no EPSG code matches       */
    int geographic;             /* 1: in degrees                           */
    int projected;              /* 1: a map projection                     */
    double linear_unit;         /* projected: metres per unit (1 for m)    */
    char linear_unit_name[64];  /* "metre"                                 */
    char geographic_name[128];  /* its geographic CRS: "WGS 84"            */
} dfle_crs_info;

/* Room that holds the WKT of any CRS dfle_crs_from_text accepts. */
#define DFLE_CRS_WKT_MAX 16384

/* Read `text`, any string GDAL's OSRSetFromUserInput takes ("EPSG:32611",
 * WKT, a PROJ string), as WKT into wkt (cap bytes, DFLE_CRS_WKT_MAX
 * always enough) and *info (may be NULL).  DFLE_EINVAL, naming `what`
 * and the text, when GDAL does not understand it; with `metric`, also
 * when it is not a projected CRS in metres (a landscape's cells are in
 * metres). */
int dfle_crs_from_text(const char *text, const char *what, int metric, char *wkt, size_t cap,
                       dfle_crs_info *info, dfle_error *err);

/* What the CRS of WKT `wkt` is.  The EPSG code is the WKT's own, or
 * GDAL's best match at 90% confidence or more (an ESRI .prj carries
 * names only). */
int dfle_crs_info_of(const char *wkt, dfle_crs_info *info, dfle_error *err);

/* 1 if the two WKT texts are the same CRS (GDAL's OSRIsSame); 0 if not,
 * or if either cannot be read. */
int dfle_crs_same(const char *wkt_a, const char *wkt_b);

/* "WGS 84 / UTM zone 11N (EPSG:32611)" (the code only when known). */
void dfle_crs_label(const dfle_crs_info *info, char *buf, size_t cap);

/* Longitude and latitude [degrees] of n points (E[i], N[i]) of CRS
 * `wkt`, on its geographic CRS (dfle_crs_info.geographic_name).  A point
 * that cannot be transformed gets NaN. */
int dfle_crs_lonlat(const char *wkt, size_t n, const double *E, const double *N, double *lon,
                    double *lat, dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
