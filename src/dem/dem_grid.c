/*
 * dem_grid.c - what a DEM's grid is: accessors, extent, the check that
 * its horizontal units are metres, and map <-> cell conversions.
 *
 * Pure functions of the structure that dem.c filled in, apart from
 * GDAL: the routing (dem_flow.c) and the profiles (dem_profile.c) call
 * down into here, and this file calls nothing of theirs.
 */
#include "dem/dem_internal.h"

#include "dfle/record.h"

#include <math.h>

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

void dfle_dem_describe(const dfle_dem *d, dfle_record *rec)
{
    dfle_record_section(rec, "dem", NULL);
    if (d->path != NULL)
        dfle_record_text(rec, "file", d->path);
    dfle_record_number(rec, "nx", (double)d->nx, NULL);
    dfle_record_number(rec, "ny", (double)d->ny, NULL);
    dfle_record_number(rec, "dx", d->dx, "m");
    dfle_record_number(rec, "dy", d->dy, "m");
    dfle_record_number(rec, "x0", d->x0, "m");
    dfle_record_number(rec, "y0", d->y0, "m");
    if (d->crs_name != NULL)
        dfle_record_text(rec, "crs", d->crs_name);
    if (d->epsg > 0)
        dfle_record_number(rec, "epsg", (double)d->epsg, NULL);
    dfle_record_bool(rec, "filled", d->filled);
}

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
          r < (double)d->ny)) {
        /* Longitude and latitude given for a grid in metres: the commonest
         * slip, so name the grid's CRS and what it wants. */
        if (!d->geographic && fabs(E) <= 180 && fabs(N) <= 90 && (e[1] - e[0] > 360 || e[3] - e[2] > 180))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "dem: %s (%.10g E, %.10g N) is outside the grid (E %.0f..%.0f, "
                                  "N %.0f..%.0f); it looks like longitude and latitude, but the "
                                  "DEM is in %s: give the point in its coordinates (metres)",
                                  what, E, N, e[0], e[1], e[2], e[3],
                                  d->crs_name != NULL ? d->crs_name : "a projected CRS");
        return dfle_error_set(err, DFLE_EINVAL,
                              "dem: %s (%.10g E, %.10g N) is outside the grid (E %.0f..%.0f, "
                              "N %.0f..%.0f)", what, E, N, e[0], e[1], e[2], e[3]);
    }
    *index = (size_t)r * d->nx + (size_t)c;
    return DFLE_OK;
}

void dfle_dem_cell_centre(const dfle_dem *d, size_t index, double *E, double *N)
{
    size_t r = index / d->nx, c = index % d->nx;
    *E = d->x0 + ((double)c + 0.5) * d->dx;
    *N = d->y0 - ((double)r + 0.5) * d->dy;
}
