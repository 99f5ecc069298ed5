/*
 * netcdf.c - NetCDF time series of grids, CF conventions (raster.h).
 *
 * One file with an unlimited time dimension, appended record by record
 * as a landscape runs.  netCDF-4 (HDF5) with shuffle and deflate: a
 * DEM catchment's file covered the whole DEM in the classic format,
 * 37 MB for 3 records of 2 fields of which 1.5% held data; it now covers
 * the data's bounding box only, compressed, each record a chunk.  The
 * file is written to a temporary regular file of dfle_file_begin_regular
 * (libnetcdf removes what it "created" when a write fails: it is never
 * given a node dfle did not make) and renamed over the target by
 * dfle_nc_close, so a killed run leaves no torn file.  The time units
 * are written at the close, when the last time is known (netCDF-4
 * changes attributes without rewriting data).
 */
#include "dfle/raster.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/crs.h"
#include "dfle/file.h"
#include "io/netcdf_internal.h"

struct dfle_nc {
    dfle_file file;
    int ncid, tvar, *vid, float32;
    int provenance;            /* history and the record are written */
    unsigned char *flags;      /* nvars: 1 for a flag (byte) field */
    size_t nx, ny, nvars, steps;
    size_t c0, r0, wx, wy;     /* the window of the grid in the file */
    double t_max;
    void *buf;                 /* wx * wy values of one field, as stored */
};

#define NC_TRY(call, what)                                                    \
    do {                                                                      \
        int s_ = (call);                                                      \
        if (s_ != NC_NOERR) {                                                 \
            st = nc_cf_fail(nc->file.path, s_, what, err);                    \
            goto fail;                                                        \
        }                                                                     \
    } while (0)

void dfle_nc_opts_default(dfle_nc_opts *o)
{
    memset(o, 0, sizeof *o);
    o->deflate = 4;
}

/* The bounding box of the cells whose mask is not NaN. */
static int data_window(dfle_nc *nc, const double *mask, dfle_error *err)
{
    size_t cmin = nc->nx, cmax = 0, rmin = nc->ny, rmax = 0;
    nc->c0 = nc->r0 = 0, nc->wx = nc->nx, nc->wy = nc->ny;
    if (mask == NULL)
        return DFLE_OK;
    for (size_t r = 0; r < nc->ny; r++)
        for (size_t c = 0; c < nc->nx; c++)
            if (!isnan(mask[r * nc->nx + c])) {
                cmin = c < cmin ? c : cmin, cmax = c > cmax ? c : cmax;
                rmin = r < rmin ? r : rmin, rmax = r > rmax ? r : rmax;
            }
    if (cmin > cmax)
        return dfle_error_set(err, DFLE_EINVAL, "netcdf: every cell is NoData: nothing to write");
    nc->c0 = cmin, nc->r0 = rmin, nc->wx = cmax - cmin + 1, nc->wy = rmax - rmin + 1;
    return DFLE_OK;
}

/* Number of flags in "a b c". */
static int count_words(const char *s)
{
    int n = 0, in = 0;
    for (; *s != '\0'; s++) {
        n += !in && *s != ' ';
        in = *s != ' ';
    }
    return n;
}

static int def_field(dfle_nc *nc, const dfle_nc_var *v, const int dims[3], int crs, int deflate,
                     int *id, dfle_error *err)
{
    /* One record a chunk, up to 1024 x 1024 cells (8 MB of doubles). */
    size_t chunk[3] = {1, nc->wy < 1024 ? nc->wy : 1024, nc->wx < 1024 ? nc->wx : 1024};
    int st = DFLE_OK;
    if (v->flag_meanings != NULL) {
        signed char fill = -1, values[32];
        int n = count_words(v->flag_meanings);
        if (n < 1 || n > 32)
            return dfle_error_set(err, DFLE_EINVAL, "netcdf: %s: flag_meanings must name 1 to 32 "
                                  "flags", v->name);
        for (int k = 0; k < n; k++)
            values[k] = (signed char)k;
        NC_TRY(nc_def_var(nc->ncid, v->name, NC_BYTE, 3, dims, id), v->name);
        NC_TRY(nc_put_att_schar(nc->ncid, *id, "_FillValue", NC_BYTE, 1, &fill), v->name);
        NC_TRY(nc_put_att_schar(nc->ncid, *id, "flag_values", NC_BYTE, (size_t)n, values),
               v->name);
        NC_TRY(nc_cf_put_text(nc->ncid, *id, "flag_meanings", v->flag_meanings), v->name);
    } else {
        double fill = NAN;
        nc_type type = nc->float32 ? NC_FLOAT : NC_DOUBLE;
        NC_TRY(nc_def_var(nc->ncid, v->name, type, 3, dims, id), v->name);
        NC_TRY(nc_put_att_double(nc->ncid, *id, "_FillValue", type, 1, &fill), v->name);
        NC_TRY(nc_cf_put_units(nc->ncid, *id, v->units), v->name);
    }
    NC_TRY(nc_def_var_chunking(nc->ncid, *id, NC_CHUNKED, chunk), v->name);
    NC_TRY(nc_cf_deflate(nc->ncid, *id, deflate), v->name);
    if (v->long_name != NULL)
        NC_TRY(nc_cf_put_text(nc->ncid, *id, "long_name", v->long_name), v->name);
    if (v->standard_name != NULL)
        NC_TRY(nc_cf_put_text(nc->ncid, *id, "standard_name", v->standard_name), v->name);
    if (crs >= 0) {
        NC_TRY(nc_cf_put_text(nc->ncid, *id, "grid_mapping", "crs"), v->name);
        NC_TRY(nc_cf_put_text(nc->ncid, *id, "coordinates", "lat lon"), v->name);
    }
fail:
    return st;
}

/* A coordinate variable x or y [m]. */
static int def_axis(dfle_nc *nc, int dim, int is_x, int *id, dfle_error *err)
{
    const char *name = is_x ? "x" : "y";
    int st = DFLE_OK;
    NC_TRY(nc_def_var(nc->ncid, name, NC_DOUBLE, 1, &dim, id), name);
    NC_TRY(nc_cf_put_text(nc->ncid, *id, "units", "m"), name);
    NC_TRY(nc_cf_put_text(nc->ncid, *id, "standard_name",
                          is_x ? "projection_x_coordinate" : "projection_y_coordinate"), name);
    NC_TRY(nc_cf_put_text(nc->ncid, *id, "long_name",
                          is_x ? "easting of the cell centre" : "northing of the cell centre"),
           name);
    NC_TRY(nc_cf_put_text(nc->ncid, *id, "axis", is_x ? "X" : "Y"), name);
fail:
    return st;
}

/* lat and lon (y, x) of the window's cell centres, on the CRS's datum. */
static int put_lonlat(dfle_nc *nc, const dfle_raster_geo *geo, int lat_v, int lon_v,
                      dfle_error *err)
{
    const size_t n = nc->wx * nc->wy;
    double *E = malloc(n * sizeof *E), *N = malloc(n * sizeof *N);
    double *lon = malloc(n * sizeof *lon), *lat = malloc(n * sizeof *lat);
    int st = DFLE_OK;
    if (E == NULL || N == NULL || lon == NULL || lat == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "netcdf: out of memory for longitude and latitude");
        goto fail;
    }
    for (size_t r = 0; r < nc->wy; r++)
        for (size_t c = 0; c < nc->wx; c++) {
            E[r * nc->wx + c] = geo->x0 + ((double)(c + nc->c0) + 0.5) * geo->dx;
            N[r * nc->wx + c] = geo->y0 - ((double)(r + nc->r0) + 0.5) * geo->dy;
        }
    if ((st = dfle_crs_lonlat(geo->crs_wkt, n, E, N, lon, lat, err)) != DFLE_OK)
        goto fail;
    NC_TRY(nc_put_var_double(nc->ncid, lat_v, lat), "lat");
    NC_TRY(nc_put_var_double(nc->ncid, lon_v, lon), "lon");
fail:
    free(E), free(N), free(lon), free(lat);
    return st;
}

static int def_lonlat(dfle_nc *nc, const int dims[3], int deflate, int *lat_v, int *lon_v,
                      dfle_error *err)
{
    int st = DFLE_OK;
    for (int k = 0; k < 2; k++) {
        const char *name = k == 0 ? "lat" : "lon";
        int *id = k == 0 ? lat_v : lon_v;
        NC_TRY(nc_def_var(nc->ncid, name, NC_DOUBLE, 2, dims + 1, id), name);
        NC_TRY(nc_cf_deflate(nc->ncid, *id, deflate), name);
        NC_TRY(nc_cf_put_text(nc->ncid, *id, "units", k == 0 ? "degrees_north" : "degrees_east"),
               name);
        NC_TRY(nc_cf_put_text(nc->ncid, *id, "standard_name", k == 0 ? "latitude" : "longitude"),
               name);
        NC_TRY(nc_cf_put_text(nc->ncid, *id, "long_name",
                              k == 0 ? "latitude of the cell centre (the CRS's datum)"
                                     : "longitude of the cell centre (the CRS's datum)"),
               name);
    }
fail:
    return st;
}

int dfle_nc_create(const char *path, size_t nx, size_t ny, const dfle_raster_geo *geo,
                   size_t nvars, const dfle_nc_var *vars, const dfle_nc_opts *opts,
                   dfle_nc **out, dfle_error *err)
{
    dfle_nc_opts o;
    dfle_nc *nc;
    const char *write_to;
    int dims[3], crs = -1, xv, yv, lat_v = -1, lon_v = -1, st;
    double *coord = NULL;
    size_t elem;

    *out = NULL;
    if (opts != NULL)
        o = *opts;
    else
        dfle_nc_opts_default(&o);
    if (nx == 0 || ny == 0 || nvars == 0)
        return dfle_error_set(err, DFLE_EINVAL, "netcdf: nothing to write (%zu x %zu, %zu "
                              "variables)", nx, ny, nvars);
    if ((st = dfle_netcdf_load("netcdf", err)) != DFLE_OK)
        return st;
    if ((nc = calloc(1, sizeof *nc)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "netcdf: out of memory");
    nc->nx = nx, nc->ny = ny, nc->nvars = nvars, nc->float32 = o.float32 != 0;
    nc->ncid = -1;
    nc->t_max = -INFINITY;
    if ((st = data_window(nc, o.mask, err)) != DFLE_OK) {
        free(nc);
        return st;
    }
    elem = nc->float32 ? sizeof(float) : sizeof(double);
    nc->vid = calloc(nvars, sizeof(int));
    nc->flags = calloc(nvars, 1);
    nc->buf = malloc(nc->wx * nc->wy * elem);
    if (nc->vid == NULL || nc->flags == NULL || nc->buf == NULL) {
        free(nc->vid), free(nc->flags), free(nc->buf), free(nc);
        return dfle_error_set(err, DFLE_ENOMEM, "netcdf: out of memory");
    }
    if ((st = dfle_file_begin_regular(&nc->file, path, "netcdf", &write_to, err)) != DFLE_OK) {
        free(nc->vid), free(nc->flags), free(nc->buf), free(nc);
        return st;
    }
    NC_TRY(nc_create(write_to, NC_CLOBBER | NC_NETCDF4, &nc->ncid), "create");
    NC_TRY(nc_def_dim(nc->ncid, "time", NC_UNLIMITED, &dims[0]), "time");
    NC_TRY(nc_def_dim(nc->ncid, "y", nc->wy, &dims[1]), "y");
    NC_TRY(nc_def_dim(nc->ncid, "x", nc->wx, &dims[2]), "x");
    NC_TRY(nc_def_var(nc->ncid, "time", NC_DOUBLE, 1, &dims[0], &nc->tvar), "time");
    if ((st = def_axis(nc, dims[1], 0, &yv, err)) != DFLE_OK ||
        (st = def_axis(nc, dims[2], 1, &xv, err)) != DFLE_OK)
        goto fail;
    if (geo->crs_wkt != NULL && geo->crs_wkt[0] != '\0') {
        if ((st = nc_cf_def_crs(nc->ncid, geo->crs_wkt, &crs, nc->file.path, err)) != DFLE_OK ||
            (st = def_lonlat(nc, dims, o.deflate, &lat_v, &lon_v, err)) != DFLE_OK)
            goto fail;
    }
    for (size_t k = 0; k < nvars; k++) {
        nc->flags[k] = vars[k].flag_meanings != NULL;
        if ((st = def_field(nc, &vars[k], dims, crs, o.deflate, &nc->vid[k], err)) != DFLE_OK)
            goto fail;
    }
    NC_TRY(nc_cf_put_globals(nc->ncid, o.title != NULL ? o.title : "dfle", o.provenance),
           "global attributes");
    nc->provenance = o.provenance != NULL;
    NC_TRY(nc_enddef(nc->ncid), "header");
    if ((coord = malloc((nc->wx > nc->wy ? nc->wx : nc->wy) * sizeof *coord)) == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "netcdf: out of memory");
        goto fail;
    }
    for (size_t c = 0; c < nc->wx; c++)
        coord[c] = geo->x0 + ((double)(c + nc->c0) + 0.5) * geo->dx;
    NC_TRY(nc_put_var_double(nc->ncid, xv, coord), "x");
    for (size_t r = 0; r < nc->wy; r++)
        coord[r] = geo->y0 - ((double)(r + nc->r0) + 0.5) * geo->dy;
    NC_TRY(nc_put_var_double(nc->ncid, yv, coord), "y");
    free(coord);
    coord = NULL;
    if (crs >= 0 && (st = put_lonlat(nc, geo, lat_v, lon_v, err)) != DFLE_OK)
        goto fail;
    *out = nc;
    return DFLE_OK;
fail:
    free(coord);
    dfle_nc_abort(nc);
    return st;
}

int dfle_nc_append(dfle_nc *nc, double t, const double *const *values, dfle_error *err)
{
    size_t start[3] = {nc->steps, 0, 0}, count[3] = {1, nc->wy, nc->wx};
    int st = DFLE_OK;
    NC_TRY(nc_put_var1_double(nc->ncid, nc->tvar, start, &t), "time");
    for (size_t k = 0; k < nc->nvars; k++) {
        const double *v = values[k];
        int s;
        for (size_t r = 0; r < nc->wy; r++) {
            const double *row = v + (r + nc->r0) * nc->nx + nc->c0;
            size_t at = r * nc->wx;
            if (nc->flags[k]) {
                signed char *b = (signed char *)nc->buf + at;
                for (size_t c = 0; c < nc->wx; c++)
                    b[c] = isnan(row[c]) || row[c] < 0 || row[c] > 127 ? (signed char)-1
                                                                       : (signed char)row[c];
            } else if (nc->float32) {
                float *b = (float *)nc->buf + at;
                for (size_t c = 0; c < nc->wx; c++)
                    b[c] = (float)row[c];
            } else {
                memcpy((double *)nc->buf + at, row, nc->wx * sizeof *row);
            }
        }
        if (nc->flags[k])
            s = nc_put_vara_schar(nc->ncid, nc->vid[k], start, count, nc->buf);
        else if (nc->float32)
            s = nc_put_vara_float(nc->ncid, nc->vid[k], start, count, nc->buf);
        else
            s = nc_put_vara_double(nc->ncid, nc->vid[k], start, count, nc->buf);
        NC_TRY(s, "values");
    }
    NC_TRY(nc_sync(nc->ncid), "sync");
    nc->steps++;
    if (t > nc->t_max)
        nc->t_max = t;
    return DFLE_OK;
fail:
    return st;
}

size_t dfle_nc_steps(const dfle_nc *nc) { return nc->steps; }

void dfle_nc_window(const dfle_nc *nc, size_t *c0, size_t *r0, size_t *nx, size_t *ny)
{
    *c0 = nc->c0, *r0 = nc->r0, *nx = nc->wx, *ny = nc->wy;
}

int dfle_nc_annotate(dfle_nc *nc, const dfle_record *rec, dfle_error *err)
{
    int st = DFLE_OK;
    if (nc->provenance)
        return dfle_error_set(err, DFLE_ESTATE, "netcdf: '%s' has its provenance already: give "
                              "the record once, at dfle_nc_create or here", nc->file.path);
    NC_TRY(nc_redef(nc->ncid), "global attributes");
    NC_TRY(nc_cf_put_provenance(nc->ncid, rec), "global attributes");
    NC_TRY(nc_enddef(nc->ncid), "global attributes");
    nc->provenance = 1;
fail:
    return st;
}

int dfle_nc_close(dfle_nc *nc, dfle_error *err)
{
    int st = DFLE_OK, s;
    /* The time units for the times written (netcdf_cf.c: "since" while
     * readers can decode it). */
    NC_TRY(nc_redef(nc->ncid), "time");
    NC_TRY(nc_cf_put_time(nc->ncid, nc->tvar, nc->steps > 0 ? nc->t_max : 0.0), "time");
    if (!nc->provenance)
        NC_TRY(nc_cf_put_provenance(nc->ncid, NULL), "history");
    NC_TRY(nc_enddef(nc->ncid), "time");
    s = nc_close(nc->ncid);
    nc->ncid = -1;
    NC_TRY(s, "close");
    st = dfle_file_commit(&nc->file, err);
    free(nc->vid), free(nc->flags), free(nc->buf), free(nc);
    return st;
fail:
    dfle_nc_abort(nc);
    return st;
}

void dfle_nc_abort(dfle_nc *nc)
{
    if (nc == NULL)
        return;
    if (nc->ncid >= 0)
        nc_close(nc->ncid);
    dfle_file_abort(&nc->file);
    free(nc->vid), free(nc->flags), free(nc->buf), free(nc);
}
