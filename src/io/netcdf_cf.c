/*
 * netcdf_cf.c - the CF-1.8 attributes every NetCDF file of dfle carries
 * (netcdf_internal.h): units UDUNITS reads, a time coordinate xarray
 * decodes, the provenance of the run as global attributes, and the grid
 * mapping of a CRS.
 *
 * Why each choice:
 *  - units: dfle writes "m^2" and "-" in its CSV files; UDUNITS reads
 *    "m2" and "1".  A unit it has no syntax for (a fractional exponent,
 *    "m^2.5") is not written as `units` at all: UDUNITS would read
 *    "m2.5" as 0.5 m2, a wrong unit rather than none.
 *  - time: CF wants "<unit> since <date>"; model time is years from the
 *    start, so the units are common years (365 days, which UDUNITS and
 *    cftime both know) since year 0 of the "noleap" calendar, and the
 *    decoded year is the model year.  cftime counts in 64-bit
 *    microseconds, 292,471 years at most: a longer series says
 *    "common_year", a plain duration, rather than break its readers.
 *  - provenance: numbers as numbers (a double per parameter, readable
 *    as ds.attrs["router_M0"]), never as text.
 *  - the CRS: GDAL of Debian 12 (3.6) cannot write a CF grid mapping, so
 *    the projections DEMs come in are mapped here from OSR's parameters,
 *    with the WKT beside them for everything else.
 */
#include "io/netcdf_internal.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "base/gdal_lib.h" /* OSR for the grid mapping, loaded on first use */

int nc_cf_fail(const char *path, int status, const char *what, dfle_error *err)
{
    return dfle_error_set(err, DFLE_EIO, "netcdf: cannot write '%s' (%s): %s",
                          path != NULL ? path : "?", what, nc_strerror(status));
}

int nc_cf_put_text(int ncid, int var, const char *name, const char *text)
{
    return nc_put_att_text(ncid, var, name, strlen(text), text);
}

/* ---------------------------------------------------------------- */
/* Units                                                            */
/* ---------------------------------------------------------------- */

int nc_cf_put_units(int ncid, int var, const char *unit)
{
    char buf[128];
    if (unit == NULL)
        return NC_NOERR; /* unknown units are left out, not claimed */
    if (dfle_units_udunits(unit, buf, sizeof buf))
        return nc_cf_put_text(ncid, var, "units", buf);
    return nc_cf_put_text(ncid, var, "dfle_units", unit);
}

int nc_cf_put_time(int ncid, int var, double t_max)
{
    int s;
    if ((s = nc_cf_put_text(ncid, var, "standard_name", "time")) != NC_NOERR ||
        (s = nc_cf_put_text(ncid, var, "long_name", "model time (years from the start)")) !=
            NC_NOERR ||
        (s = nc_cf_put_text(ncid, var, "axis", "T")) != NC_NOERR)
        return s;
    if (!(t_max < NC_CF_SINCE_MAX_YEARS))
        return nc_cf_put_text(ncid, var, "units", "common_year");
    if ((s = nc_cf_put_text(ncid, var, "calendar", "noleap")) != NC_NOERR)
        return s;
    return nc_cf_put_text(ncid, var, "units", "common_years since 0000-01-01 00:00:00");
}

int nc_cf_deflate(int ncid, int var, int level)
{
    if (level <= 0)
        return NC_NOERR;
    return nc_def_var_deflate(ncid, var, 1, 1, level > 9 ? 9 : level);
}

/* ---------------------------------------------------------------- */
/* Provenance                                                       */
/* ---------------------------------------------------------------- */

typedef struct rec_ctx {
    int ncid, status;
    const char *section;   /* the section whose units are being gathered */
    char units[4096];
    size_t nunits;
} rec_ctx;

static void flush_units(rec_ctx *c)
{
    char name[160];
    if (c->section != NULL && c->nunits > 0 && c->status == NC_NOERR) {
        dfle_record_entry u = {.section = c->section, .key = "units"};
        dfle_record_flat_name(&u, name, sizeof name);
        c->status = nc_cf_put_text(c->ncid, NC_GLOBAL, name, c->units);
    }
    c->nunits = 0;
    c->units[0] = '\0';
}

static int put_entry(void *ud, const dfle_record_entry *e)
{
    rec_ctx *c = ud;
    char name[160], text[4096];
    int s = NC_NOERR;

    if (c->section == NULL ? e->section != NULL
                           : e->section == NULL || strcmp(c->section, e->section) != 0) {
        flush_units(c);
        c->section = e->section;
        if (e->section != NULL && e->kind != NULL) {
            dfle_record_entry kind = {.section = e->section};
            dfle_record_flat_name(&kind, name, sizeof name);
            s = nc_cf_put_text(c->ncid, NC_GLOBAL, name, e->kind);
        }
    }
    if (s == NC_NOERR && e->key != NULL) {
        dfle_record_flat_name(e, name, sizeof name);
        switch (e->type) {
        case DFLE_RECORD_NUMBER:
            s = nc_put_att_double(c->ncid, NC_GLOBAL, name, NC_DOUBLE, 1, &e->num);
            break;
        case DFLE_RECORD_BOOL: {
            double v = e->num != 0;
            s = nc_put_att_double(c->ncid, NC_GLOBAL, name, NC_INT, 1, &v);
            break;
        }
        case DFLE_RECORD_TEXT:
            s = nc_cf_put_text(c->ncid, NC_GLOBAL, name, e->text != NULL ? e->text : "");
            break;
        case DFLE_RECORD_LIST:
            dfle_record_join(e->items, e->nitems, text, sizeof text);
            s = nc_cf_put_text(c->ncid, NC_GLOBAL, name, text);
            break;
        }
        if (s == NC_NOERR && e->section != NULL && e->unit != NULL) {
            char u[128];
            int n = snprintf(c->units + c->nunits, sizeof c->units - c->nunits, "%s%s=%s",
                             c->nunits > 0 ? ", " : "", e->key,
                             dfle_units_udunits(e->unit, u, sizeof u) ? u : e->unit);
            if (n > 0 && (size_t)n < sizeof c->units - c->nunits)
                c->nunits += (size_t)n;
        }
    }
    c->status = s;
    return s != NC_NOERR;
}

int nc_cf_put_record(int ncid, const dfle_record *rec)
{
    rec_ctx c;
    memset(&c, 0, sizeof c);
    c.ncid = ncid;
    dfle_record_each(rec, put_entry, &c);
    flush_units(&c);
    return c.status;
}

int nc_cf_put_globals(int ncid, const char *title, const dfle_record *rec)
{
    int s;
    if ((s = nc_cf_put_text(ncid, NC_GLOBAL, "Conventions", "CF-1.8")) != NC_NOERR ||
        (s = nc_cf_put_text(ncid, NC_GLOBAL, "title", title != NULL ? title : "dfle")) !=
            NC_NOERR ||
        (s = nc_cf_put_text(ncid, NC_GLOBAL, "source", "dfle " DFLE_VERSION)) != NC_NOERR ||
        (s = nc_cf_put_text(ncid, NC_GLOBAL, "dfle_version", DFLE_VERSION)) != NC_NOERR)
        return s;
    return rec != NULL ? nc_cf_put_provenance(ncid, rec) : NC_NOERR;
}

int nc_cf_put_provenance(int ncid, const dfle_record *rec)
{
    char line[4200];
    int s;
    if (rec == NULL || !dfle_record_history(rec, line, sizeof line)) {
        /* No command to name: when, and what wrote it. */
        time_t now = time(NULL);
        struct tm tm;
        char when[40] = "(unknown time)";
        if (gmtime_r(&now, &tm) != NULL)
            strftime(when, sizeof when, "%Y-%m-%dT%H:%M:%SZ", &tm);
        snprintf(line, sizeof line, "%s: written by the dfle " DFLE_VERSION " C library", when);
    }
    if ((s = nc_cf_put_text(ncid, NC_GLOBAL, "history", line)) != NC_NOERR)
        return s;
    return rec != NULL ? nc_cf_put_record(ncid, rec) : NC_NOERR;
}

/* ---------------------------------------------------------------- */
/* The grid mapping                                                 */
/* ---------------------------------------------------------------- */

/* A CF attribute from an OSR parameter; names are OSR's (WKT 1). */
typedef struct cf_param {
    const char *cf, *osr, *osr2; /* osr2: a second value (standard_parallel) */
} cf_param;

typedef struct cf_mapping {
    const char *osr_projection, *cf_name;
    cf_param p[6];
} cf_mapping;

static const cf_mapping mappings[] = {
    {"Transverse_Mercator", "transverse_mercator",
     {{"scale_factor_at_central_meridian", "scale_factor", NULL},
      {"longitude_of_central_meridian", "central_meridian", NULL},
      {"latitude_of_projection_origin", "latitude_of_origin", NULL},
      {"false_easting", "false_easting", NULL},
      {"false_northing", "false_northing", NULL}}},
    {"Lambert_Conformal_Conic_2SP", "lambert_conformal_conic",
     {{"standard_parallel", "standard_parallel_1", "standard_parallel_2"},
      {"longitude_of_central_meridian", "central_meridian", NULL},
      {"latitude_of_projection_origin", "latitude_of_origin", NULL},
      {"false_easting", "false_easting", NULL},
      {"false_northing", "false_northing", NULL}}},
    {"Albers_Conic_Equal_Area", "albers_conical_equal_area",
     {{"standard_parallel", "standard_parallel_1", "standard_parallel_2"},
      {"longitude_of_central_meridian", "longitude_of_center", NULL},
      {"latitude_of_projection_origin", "latitude_of_center", NULL},
      {"false_easting", "false_easting", NULL},
      {"false_northing", "false_northing", NULL}}},
    {"Lambert_Azimuthal_Equal_Area", "lambert_azimuthal_equal_area",
     {{"longitude_of_projection_origin", "longitude_of_center", NULL},
      {"latitude_of_projection_origin", "latitude_of_center", NULL},
      {"false_easting", "false_easting", NULL},
      {"false_northing", "false_northing", NULL}}},
    {"Mercator_1SP", "mercator",
     {{"longitude_of_projection_origin", "central_meridian", NULL},
      {"scale_factor_at_projection_origin", "scale_factor", NULL},
      {"false_easting", "false_easting", NULL},
      {"false_northing", "false_northing", NULL}}},
    {"Mercator_2SP", "mercator",
     {{"longitude_of_projection_origin", "central_meridian", NULL},
      {"standard_parallel", "standard_parallel_1", NULL},
      {"false_easting", "false_easting", NULL},
      {"false_northing", "false_northing", NULL}}},
};

static int put_num(int ncid, int var, const char *name, size_t n, const double *v)
{
    return nc_put_att_double(ncid, var, name, NC_DOUBLE, n, v);
}

/* The projection's CF name and parameters; 0 when CF has no name for it. */
static int put_projection(int ncid, int var, OGRSpatialReferenceH srs, int *s)
{
    const char *proj = OSRGetAttrValue(srs, "PROJECTION", 0);
    OGRErr e;
    if (proj == NULL)
        return 0;
    if (strcmp(proj, "Lambert_Conformal_Conic_1SP") == 0 &&
        OSRGetProjParm(srs, "scale_factor", 1.0, &e) == 1.0) {
        /* One standard parallel at the origin, where the scale is 1. */
        double sp = OSRGetProjParm(srs, "latitude_of_origin", 0.0, &e);
        double v[4] = {OSRGetProjParm(srs, "central_meridian", 0.0, &e), sp,
                       OSRGetProjParm(srs, "false_easting", 0.0, &e),
                       OSRGetProjParm(srs, "false_northing", 0.0, &e)};
        (void)((*s = nc_cf_put_text(ncid, var, "grid_mapping_name", "lambert_conformal_conic")) ||
               (*s = put_num(ncid, var, "standard_parallel", 1, &sp)) ||
               (*s = put_num(ncid, var, "longitude_of_central_meridian", 1, &v[0])) ||
               (*s = put_num(ncid, var, "latitude_of_projection_origin", 1, &v[1])) ||
               (*s = put_num(ncid, var, "false_easting", 1, &v[2])) ||
               (*s = put_num(ncid, var, "false_northing", 1, &v[3])));
        return 1;
    }
    if (strcmp(proj, "Polar_Stereographic") == 0) {
        double lat0 = OSRGetProjParm(srs, "latitude_of_origin", 90.0, &e);
        double k = OSRGetProjParm(srs, "scale_factor", 1.0, &e);
        double pole = lat0 < 0 ? -90.0 : 90.0;
        double v[3] = {OSRGetProjParm(srs, "central_meridian", 0.0, &e),
                       OSRGetProjParm(srs, "false_easting", 0.0, &e),
                       OSRGetProjParm(srs, "false_northing", 0.0, &e)};
        if ((*s = nc_cf_put_text(ncid, var, "grid_mapping_name", "polar_stereographic")) ||
            (*s = put_num(ncid, var, "straight_vertical_longitude_from_pole", 1, &v[0])) ||
            (*s = put_num(ncid, var, "latitude_of_projection_origin", 1, &pole)))
            return 1;
        /* Variant A gives the scale at the pole, variant B the latitude
         * of true scale (GDAL's latitude_of_origin, scale 1). */
        if (fabs(fabs(lat0) - 90.0) < 1e-12 && k != 1.0)
            *s = put_num(ncid, var, "scale_factor_at_projection_origin", 1, &k);
        else
            *s = put_num(ncid, var, "standard_parallel", 1, &lat0);
        if (*s == NC_NOERR)
            *s = put_num(ncid, var, "false_easting", 1, &v[1]);
        if (*s == NC_NOERR)
            *s = put_num(ncid, var, "false_northing", 1, &v[2]);
        return 1;
    }
    for (size_t m = 0; m < sizeof mappings / sizeof mappings[0]; m++) {
        const cf_mapping *cm = &mappings[m];
        if (strcmp(proj, cm->osr_projection) != 0)
            continue;
        if ((*s = nc_cf_put_text(ncid, var, "grid_mapping_name", cm->cf_name)) != NC_NOERR)
            return 1;
        for (int k = 0; k < 6 && cm->p[k].cf != NULL; k++) {
            double v[2];
            size_t n = 1;
            v[0] = OSRGetProjParm(srs, cm->p[k].osr, 0.0, &e);
            if (cm->p[k].osr2 != NULL)
                v[1] = OSRGetProjParm(srs, cm->p[k].osr2, 0.0, &e), n = 2;
            if ((*s = put_num(ncid, var, cm->p[k].cf, n, v)) != NC_NOERR)
                return 1;
        }
        return 1;
    }
    return 0;
}

int nc_cf_def_crs(int ncid, const char *wkt, int *var, const char *path, dfle_error *err)
{
    OGRSpatialReferenceH srs;
    const char *names[][2] = {{"geographic_crs_name", "GEOGCS"},
                              {"horizontal_datum_name", "DATUM"},
                              {"reference_ellipsoid_name", "SPHEROID"},
                              {"prime_meridian_name", "PRIMEM"}};
    int st, s = NC_NOERR;

    if ((st = dfle_gdal_load("netcdf", err)) != DFLE_OK)
        return st;
    if ((s = nc_def_var(ncid, "crs", NC_INT, 0, NULL, var)) != NC_NOERR)
        return nc_cf_fail(path, s, "crs", err);
    CPLPushErrorHandler(CPLQuietErrorHandler);
    srs = OSRNewSpatialReference(NULL);
    if (srs != NULL && OSRSetFromUserInput(srs, wkt) == OGRERR_NONE) {
        OGRErr e;
        double a = OSRGetSemiMajor(srs, &e), rf = OSRGetInvFlattening(srs, &e);
        double pm = OSRGetPrimeMeridian(srs, NULL);
        if (OSRIsGeographic(srs))
            s = nc_cf_put_text(ncid, *var, "grid_mapping_name", "latitude_longitude");
        else
            put_projection(ncid, *var, srs, &s);
        if (s == NC_NOERR && OSRIsProjected(srs) && OSRGetName(srs) != NULL)
            s = nc_cf_put_text(ncid, *var, "projected_crs_name", OSRGetName(srs));
        for (size_t k = 0; s == NC_NOERR && k < sizeof names / sizeof names[0]; k++)
            if (OSRGetAttrValue(srs, names[k][1], 0) != NULL)
                s = nc_cf_put_text(ncid, *var, names[k][0], OSRGetAttrValue(srs, names[k][1], 0));
        if (s == NC_NOERR && a > 0)
            s = put_num(ncid, *var, "semi_major_axis", 1, &a);
        if (s == NC_NOERR && rf > 0)
            s = put_num(ncid, *var, "inverse_flattening", 1, &rf);
        if (s == NC_NOERR)
            s = put_num(ncid, *var, "longitude_of_prime_meridian", 1, &pm);
    }
    if (srs != NULL)
        OSRDestroySpatialReference(srs);
    CPLErrorReset();
    CPLPopErrorHandler();
    if (s == NC_NOERR)
        s = nc_cf_put_text(ncid, *var, "crs_wkt", wkt);
    if (s == NC_NOERR)
        s = nc_cf_put_text(ncid, *var, "spatial_ref", wkt);
    return s == NC_NOERR ? DFLE_OK : nc_cf_fail(path, s, "crs", err);
}
