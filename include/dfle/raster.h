/*
 * raster.h - writing grids: GeoTIFF (through GDAL) and NetCDF time
 * series (CF conventions, through the netCDF C library).
 *
 * Grids are row-major, row 0 at the north, NaN = NoData, as everywhere
 * in dfle (dem.h, drainage.h, landscape.h); a grid lies where its
 * dfle_raster_geo says.  Every file is written whole or not at all
 * (file.h): to a temporary file beside the target, renamed over it once
 * complete.  GDAL and libnetcdf are not linked: the first GeoTIFF or
 * NetCDF file loads its library, and where it cannot be loaded the
 * call fails with DFLE_EEXTERNAL, saying what to install.
 */
#ifndef DFLE_RASTER_H
#define DFLE_RASTER_H

#include <stddef.h>

#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Where a grid lies: its north-west corner (E, N) [m], cell size [m],
 * and the CRS as WKT (NULL: none). */
typedef struct dfle_raster_geo {
    double x0, y0;
    double dx, dy;
    const char *crs_wkt;
} dfle_raster_geo;

/* A GeoTIFF of nbands Float64 bands of nx * ny values, band k named
 * names[k] (its description); NoData is NaN.  DFLE_EIO naming the path
 * and GDAL's reason when it cannot be written. */
int dfle_raster_write_geotiff(const char *path, size_t nx, size_t ny, const dfle_raster_geo *geo,
                              size_t nbands, const double *const *bands,
                              const char *const *names, dfle_error *err);

/* --- NetCDF time series ------------------------------------------------
 * dimensions (time, y, x), time unlimited; coordinates x and y at cell
 * centres [m] (projection_x/y_coordinate), time in years of model time;
 * one double variable per field with units, long_name, _FillValue NaN
 * and grid_mapping "crs" when a CRS is given (its WKT in crs_wkt and
 * spatial_ref, as GDAL writes it).  Conventions = "CF-1.8": xarray's
 * open_dataset reads it as it is. */
typedef struct dfle_nc dfle_nc;

typedef struct dfle_nc_var {
    const char *name;      /* "z", "E_df", ...        */
    const char *units;     /* "m", "m/yr", "1", ...   */
    const char *long_name; /* "elevation", ...         */
    const char *standard_name; /* CF standard name, or NULL */
} dfle_nc_var;

int dfle_nc_create(const char *path, size_t nx, size_t ny, const dfle_raster_geo *geo,
                   size_t nvars, const dfle_nc_var *vars, const char *title, dfle_nc **out,
                   dfle_error *err);
/* Append one time [yr]: values[k] holds nx * ny values of variable k. */
int dfle_nc_append(dfle_nc *nc, double t, const double *const *values, dfle_error *err);
size_t dfle_nc_steps(const dfle_nc *nc);
/* Close and put the file in place (rename over the target). */
int dfle_nc_close(dfle_nc *nc, dfle_error *err);
/* Give up: remove the temporary file (nc may be NULL). */
void dfle_nc_abort(dfle_nc *nc);

#ifdef __cplusplus
}
#endif
#endif
