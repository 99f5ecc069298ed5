/*
 * dem_profile_out.c - a profile's or network's CSV table and its record
 * (dem.h): where it comes from, and where it is on Earth.
 *
 * Where the DEM has a CRS, the record names it (a comment line of the
 * CSV file, and the JSON record) with its EPSG code and WKT, and the
 * table gains longitude and latitude of each cell centre, on the CRS's
 * own datum (crs.h): what a GIS or a map of another projection needs
 * beside E and N.
 */
#include "dem/dem_internal.h"

#include <math.h>
#include <stdio.h>

#include "dfle/crs.h"
#include "dfle/record.h"

const char *dfle_profile_crs_wkt(const dfle_profile *p) { return p->crs; }

int dfle_profile_write_csv(const dfle_profile *p, const char *path, const dfle_record *rec,
                           dfle_error *err)
{
    static const struct { enum dfle_profile_field f; const char *name, *unit; } fields[] = {
        {DFLE_PROFILE_E, "E", "m"}, {DFLE_PROFILE_N, "N", "m"}, {DFLE_PROFILE_X, "x", "m"},
        {DFLE_PROFILE_D, "d", "m"}, {DFLE_PROFILE_Z, "z", "m"}, {DFLE_PROFILE_A, "A", "m^2"},
        {DFLE_PROFILE_S, "S", "-"}};
    enum { NF = sizeof fields / sizeof fields[0] };
    dfle_column cols[NF + 3];
    double *receiver, *lon = NULL, *lat = NULL;
    size_t nc = NF + 1;
    int st;

    if (path == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "profile: no file name given");
    /* Receivers are whole numbers far below 2^53: exact as doubles. */
    if ((receiver = malloc(p->n * sizeof *receiver)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "profile: out of memory");
    for (size_t i = 0; i < p->n; i++)
        receiver[i] = (double)p->receiver[i];
    for (size_t k = 0; k < NF; k++)
        cols[k] = (dfle_column){fields[k].name, fields[k].unit, p->f[fields[k].f], NULL};
    cols[NF] = (dfle_column){"receiver", NULL, receiver, NULL};
    if (p->crs != NULL) {
        lon = malloc(p->n * sizeof *lon);
        lat = malloc(p->n * sizeof *lat);
        if (lon == NULL || lat == NULL) {
            st = dfle_error_set(err, DFLE_ENOMEM, "profile: out of memory");
            goto done;
        }
        if ((st = dfle_crs_lonlat(p->crs, p->n, p->f[DFLE_PROFILE_E], p->f[DFLE_PROFILE_N], lon,
                                  lat, err)) != DFLE_OK)
            goto done;
        cols[nc++] = (dfle_column){"lon", "degrees_east", lon, NULL};
        cols[nc++] = (dfle_column){"lat", "degrees_north", lat, NULL};
    }
    st = dfle_table_write(path, "profile", rec, cols, nc, p->n, 10, err);
done:
    free(receiver), free(lon), free(lat);
    return st;
}

void dfle_profile_describe(const dfle_profile *p, dfle_record *rec)
{
    const double *D = p->f[DFLE_PROFILE_D];
    double length = 0;
    for (size_t i = 0; i < p->n; i++)
        length = D[i] > length ? D[i] : length;
    if (p->crs != NULL) {
        dfle_crs_info info;
        dfle_error err;
        char label[512];
        dfle_record_section(rec, NULL, NULL);
        if (dfle_crs_info_of(p->crs, &info, &err) == DFLE_OK) {
            dfle_crs_label(&info, label, sizeof label);
            dfle_record_text(rec, "crs", label);
            snprintf(label, sizeof label, "degrees on %s (the CRS's datum)",
                     info.geographic_name[0] != '\0' ? info.geographic_name : "its datum");
            dfle_record_text(rec, "lon_lat", label);
        }
        /* The WKT where no EPSG code names the CRS exactly. */
        if (dfle_crs_info_of(p->crs, &info, &err) != DFLE_OK || info.epsg == 0)
            dfle_record_text(rec, "crs_wkt", p->crs);
    }
    dfle_record_section(rec, "profile", p->network ? "network" : "profile");
    if (p->dem != NULL)
        dfle_record_text(rec, "dem", p->dem);
    if (!p->network)
        dfle_record_text(rec, "from", p->from_head ? "head" : "outlet");
    if (isfinite(p->given[0])) {
        dfle_record_number(rec, "given_E", p->given[0], "m");
        dfle_record_number(rec, "given_N", p->given[1], "m");
        dfle_record_number(rec, "snapped_E", p->snapped[0], "m");
        dfle_record_number(rec, "snapped_N", p->snapped[1], "m");
    }
    if (p->radius >= 0)
        dfle_record_number(rec, "radius", p->radius, "m");
    if (p->A_min > 0)
        dfle_record_number(rec, "A_min", p->A_min, "m^2");
    if (p->A_max > 0)
        dfle_record_number(rec, "A_max", p->A_max, "m^2");
    if (p->slope.ds > 0)
        dfle_record_number(rec, "ds", p->slope.ds, "m");
    else
        dfle_record_number(rec, "dz", p->slope.dz, "m");
    dfle_record_number(rec, "n", (double)p->n, NULL);
    dfle_record_number(rec, "length", length, "m");
}
