/*
 * netcdf.h - NetCDF files of one-dimensional results: a channel
 * profile's recorded states, and tables of samples (ensembles).
 *
 * Grids and their time series are in raster.h; these share its variable
 * description (dfle_nc_var), options (dfle_nc_opts) and choices:
 * netCDF-4 with deflate, CF-1.8 attributes so xarray's open_dataset
 * decodes units, time, coordinates and fill values as they are (units
 * in UDUNITS' syntax, time in model years "since" year 0 of a noleap
 * calendar), NaN as _FillValue, provenance as global attributes, and
 * the whole file or none, written only over a regular file (file.h).
 * libnetcdf is loaded by the first file written (raster.h).
 */
#ifndef DFLE_NETCDF_H
#define DFLE_NETCDF_H

#include <stddef.h>

#include "dfle/error.h"
#include "dfle/raster.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A global attribute: provenance (history, source, parameters, ...). */
typedef struct dfle_nc_attr {
    const char *name;
    const char *value;
} dfle_nc_attr;

/* A profile's states at nt times: dimensions (time, x), x the distance
 * from the channel head [m] (a coordinate variable, increasing), A(x)
 * the drainage area [m^2] as an auxiliary coordinate, time [yr] of
 * model time; variable k holds nt * n values, time-major.  opts (may be
 * NULL): title, provenance, float32, deflate (mask is for grids). */
int dfle_nc_write_profiles(const char *path, size_t n, const double *x, const double *A,
                           size_t nt, const double *t, size_t nvars, const dfle_nc_var *vars,
                           const double *const *values, const dfle_nc_opts *opts,
                           dfle_error *err);

/* A table of nrows rows along the dimension `dim` ("sample"): numeric
 * columns (NaN where empty) and text columns (as character arrays, which
 * xarray decodes to strings). */
typedef struct dfle_nc_text {
    const char *name;      /* "status", "reason"           */
    const char *long_name;
    const char *const *values; /* nrows strings (NULL = "") */
} dfle_nc_text;

int dfle_nc_write_table(const char *path, const char *dim, size_t nrows, size_t ncols,
                        const dfle_nc_var *cols, const double *const *values, size_t ntext,
                        const dfle_nc_text *text, size_t nattrs, const dfle_nc_attr *attrs,
                        dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
