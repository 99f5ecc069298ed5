/*
 * netcdf.c - NetCDF time series of grids, CF conventions (raster.h).
 *
 * A small writer: the landscape's records (and, later, a model's records
 * or an ensemble's rows) as one file with an unlimited time dimension.
 * The classic 64-bit-offset format is used: every netCDF reader (xarray,
 * GDAL, ncview, R) reads it, and it needs no HDF5.  The file is written to
 * the temporary file of dfle_file_begin_external and renamed over the
 * target by dfle_nc_close, so a killed run leaves no torn file.
 */
#include "dfle/raster.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/netcdf_lib.h" /* libnetcdf, loaded by the first dfle_nc_create */
#include "dfle/file.h"

struct dfle_nc {
    dfle_file file;
    int ncid, tvar, *vid;
    size_t nx, ny, nvars, steps;
    char *path;
};

static int nc_fail(dfle_nc *nc, int status, const char *what, dfle_error *err)
{
    return dfle_error_set(err, DFLE_EIO, "netcdf: cannot write '%s' (%s): %s",
                          nc->file.path != NULL ? nc->file.path : "?", what, nc_strerror(status));
}

#define NC_TRY(call, what)                                                    \
    do {                                                                      \
        int s_ = (call);                                                      \
        if (s_ != NC_NOERR) {                                                 \
            st = nc_fail(nc, s_, what, err);                                  \
            goto fail;                                                        \
        }                                                                     \
    } while (0)

static int put_text(int ncid, int var, const char *name, const char *text)
{
    return nc_put_att_text(ncid, var, name, strlen(text), text);
}

int dfle_nc_create(const char *path, size_t nx, size_t ny, const dfle_raster_geo *geo,
                   size_t nvars, const dfle_nc_var *vars, const char *title, dfle_nc **out,
                   dfle_error *err)
{
    dfle_nc *nc;
    const char *write_to;
    int dims[3], crs = -1, xv, yv, st;
    double *coord = NULL, fill = NAN;

    *out = NULL;
    if (nx == 0 || ny == 0 || nvars == 0)
        return dfle_error_set(err, DFLE_EINVAL, "netcdf: nothing to write (%zu x %zu, %zu "
                              "variables)", nx, ny, nvars);
    if ((st = dfle_netcdf_load("netcdf", err)) != DFLE_OK)
        return st;
    if ((nc = calloc(1, sizeof *nc)) == NULL || (nc->vid = calloc(nvars, sizeof(int))) == NULL) {
        if (nc != NULL)
            free(nc);
        return dfle_error_set(err, DFLE_ENOMEM, "netcdf: out of memory");
    }
    nc->nx = nx, nc->ny = ny, nc->nvars = nvars;
    nc->ncid = -1;
    if ((st = dfle_file_begin_external(&nc->file, path, "netcdf", &write_to, err)) != DFLE_OK) {
        free(nc->vid);
        free(nc);
        return st;
    }
    NC_TRY(nc_create(write_to, NC_CLOBBER | NC_64BIT_OFFSET, &nc->ncid), "create");
    NC_TRY(nc_def_dim(nc->ncid, "time", NC_UNLIMITED, &dims[0]), "time");
    NC_TRY(nc_def_dim(nc->ncid, "y", ny, &dims[1]), "y");
    NC_TRY(nc_def_dim(nc->ncid, "x", nx, &dims[2]), "x");
    NC_TRY(nc_def_var(nc->ncid, "time", NC_DOUBLE, 1, &dims[0], &nc->tvar), "time");
    put_text(nc->ncid, nc->tvar, "units", "year");
    put_text(nc->ncid, nc->tvar, "long_name", "model time");
    put_text(nc->ncid, nc->tvar, "axis", "T");
    NC_TRY(nc_def_var(nc->ncid, "y", NC_DOUBLE, 1, &dims[1], &yv), "y");
    put_text(nc->ncid, yv, "units", "m");
    put_text(nc->ncid, yv, "standard_name", "projection_y_coordinate");
    put_text(nc->ncid, yv, "long_name", "northing of the cell centre");
    put_text(nc->ncid, yv, "axis", "Y");
    NC_TRY(nc_def_var(nc->ncid, "x", NC_DOUBLE, 1, &dims[2], &xv), "x");
    put_text(nc->ncid, xv, "units", "m");
    put_text(nc->ncid, xv, "standard_name", "projection_x_coordinate");
    put_text(nc->ncid, xv, "long_name", "easting of the cell centre");
    put_text(nc->ncid, xv, "axis", "X");
    if (geo->crs_wkt != NULL && geo->crs_wkt[0] != '\0') {
        NC_TRY(nc_def_var(nc->ncid, "crs", NC_INT, 0, NULL, &crs), "crs");
        put_text(nc->ncid, crs, "crs_wkt", geo->crs_wkt);
        put_text(nc->ncid, crs, "spatial_ref", geo->crs_wkt);
    }
    for (size_t k = 0; k < nvars; k++) {
        NC_TRY(nc_def_var(nc->ncid, vars[k].name, NC_DOUBLE, 3, dims, &nc->vid[k]), vars[k].name);
        put_text(nc->ncid, nc->vid[k], "units", vars[k].units != NULL ? vars[k].units : "1");
        if (vars[k].long_name != NULL)
            put_text(nc->ncid, nc->vid[k], "long_name", vars[k].long_name);
        if (vars[k].standard_name != NULL)
            put_text(nc->ncid, nc->vid[k], "standard_name", vars[k].standard_name);
        nc_put_att_double(nc->ncid, nc->vid[k], "_FillValue", NC_DOUBLE, 1, &fill);
        if (crs >= 0)
            put_text(nc->ncid, nc->vid[k], "grid_mapping", "crs");
    }
    put_text(nc->ncid, NC_GLOBAL, "Conventions", "CF-1.8");
    put_text(nc->ncid, NC_GLOBAL, "title", title != NULL ? title : "dfle");
    put_text(nc->ncid, NC_GLOBAL, "source", "dfle " DFLE_VERSION);
    NC_TRY(nc_enddef(nc->ncid), "header");
    if ((coord = malloc((nx > ny ? nx : ny) * sizeof *coord)) == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "netcdf: out of memory");
        goto fail;
    }
    for (size_t c = 0; c < nx; c++)
        coord[c] = geo->x0 + ((double)c + 0.5) * geo->dx;
    NC_TRY(nc_put_var_double(nc->ncid, xv, coord), "x");
    for (size_t r = 0; r < ny; r++)
        coord[r] = geo->y0 - ((double)r + 0.5) * geo->dy;
    NC_TRY(nc_put_var_double(nc->ncid, yv, coord), "y");
    free(coord);
    *out = nc;
    return DFLE_OK;
fail:
    free(coord);
    dfle_nc_abort(nc);
    return st;
}

int dfle_nc_append(dfle_nc *nc, double t, const double *const *values, dfle_error *err)
{
    size_t start[3] = {nc->steps, 0, 0}, count[3] = {1, nc->ny, nc->nx};
    int st = DFLE_OK;
    NC_TRY(nc_put_var1_double(nc->ncid, nc->tvar, start, &t), "time");
    for (size_t k = 0; k < nc->nvars; k++)
        NC_TRY(nc_put_vara_double(nc->ncid, nc->vid[k], start, count, values[k]), "values");
    NC_TRY(nc_sync(nc->ncid), "sync");
    nc->steps++;
    return DFLE_OK;
fail:
    return st;
}

size_t dfle_nc_steps(const dfle_nc *nc) { return nc->steps; }

int dfle_nc_close(dfle_nc *nc, dfle_error *err)
{
    int s = nc_close(nc->ncid), st;
    nc->ncid = -1;
    if (s != NC_NOERR) {
        st = nc_fail(nc, s, "close", err);
        dfle_nc_abort(nc);
        return st;
    }
    st = dfle_file_commit(&nc->file, err);
    free(nc->vid);
    free(nc);
    return st;
}

void dfle_nc_abort(dfle_nc *nc)
{
    if (nc == NULL)
        return;
    if (nc->ncid >= 0)
        nc_close(nc->ncid);
    dfle_file_abort(&nc->file);
    free(nc->vid);
    free(nc);
}
