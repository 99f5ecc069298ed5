/*
 * netcdf_1d.c - NetCDF files of profile records and sample tables
 * (netcdf.h).
 *
 * Both are written in one go, from results already in memory: a run's
 * records and an ensemble's rows are complete when they are written, so
 * there is nothing to append and the file is put in place (renamed over
 * the target) only once it is whole.  netCDF-4 with deflate, CF
 * attributes from netcdf_cf.c.  The records are a grid of (time, x),
 * not one of CF's discrete sampling geometries: a long profile along a
 * channel is none of them ("profile" is a vertical one), so the file
 * has no featureType.
 */
#include "dfle/netcdf.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/file.h"
#include "io/netcdf_internal.h" /* libnetcdf, loaded by the first file (out_begin) */

/* One file being written: its temporary name and netCDF id. */
typedef struct nc_out {
    dfle_file file;
    int ncid;
} nc_out;

static int out_fail(nc_out *o, int status, const char *what, dfle_error *err)
{
    return nc_cf_fail(o->file.path, status, what, err);
}

#define NC_DO(call, what)                                                     \
    do {                                                                      \
        int s_ = (call);                                                      \
        if (s_ != NC_NOERR) {                                                 \
            st = out_fail(o, s_, what, err);                                  \
            goto fail;                                                        \
        }                                                                     \
    } while (0)

static int text_att(int ncid, int var, const char *name, const char *text)
{
    return nc_cf_put_text(ncid, var, name, text);
}

static int out_begin(nc_out *o, const char *path, dfle_error *err)
{
    const char *write_to;
    int st, s;
    o->ncid = -1;
    if ((st = dfle_netcdf_load("netcdf", err)) != DFLE_OK)
        return st;
    if ((st = dfle_file_begin_regular(&o->file, path, "netcdf", &write_to, err)) != DFLE_OK)
        return st;
    if ((s = nc_create(write_to, NC_CLOBBER | NC_NETCDF4, &o->ncid)) != NC_NOERR) {
        o->ncid = -1;
        st = out_fail(o, s, "create", err);
        dfle_file_abort(&o->file);
        return st;
    }
    return DFLE_OK;
}

/* Global attributes: CF, dfle, the record, then the caller's own. */
static int out_globals(nc_out *o, const char *title, const dfle_record *rec, size_t nattrs,
                       const dfle_nc_attr *attrs, dfle_error *err)
{
    int st = DFLE_OK;
    int has_history = rec != NULL;
    NC_DO(nc_cf_put_globals(o->ncid, title, rec), "global attributes");
    for (size_t k = 0; k < nattrs; k++)
        if (attrs[k].name != NULL && attrs[k].value != NULL) {
            NC_DO(text_att(o->ncid, NC_GLOBAL, attrs[k].name, attrs[k].value), attrs[k].name);
            has_history |= strcmp(attrs[k].name, "history") == 0;
        }
    if (!has_history) /* when, and what wrote it */
        NC_DO(nc_cf_put_provenance(o->ncid, NULL), "history");
fail:
    return st;
}

static int def_var(nc_out *o, const dfle_nc_var *v, int ndims, const int *dims, int float32,
                   int deflate, int *id, dfle_error *err)
{
    double fill = NAN;
    nc_type type = float32 ? NC_FLOAT : NC_DOUBLE;
    int st = DFLE_OK;
    NC_DO(nc_def_var(o->ncid, v->name, type, ndims, dims, id), v->name);
    NC_DO(nc_cf_deflate(o->ncid, *id, deflate), v->name);
    NC_DO(nc_cf_put_units(o->ncid, *id, v->units), v->name);
    if (v->long_name != NULL)
        NC_DO(text_att(o->ncid, *id, "long_name", v->long_name), v->name);
    if (v->standard_name != NULL)
        NC_DO(text_att(o->ncid, *id, "standard_name", v->standard_name), v->name);
    NC_DO(nc_put_att_double(o->ncid, *id, "_FillValue", type, 1, &fill), v->name);
fail:
    return st;
}

static int out_finish(nc_out *o, dfle_error *err)
{
    int s = nc_close(o->ncid);
    o->ncid = -1;
    if (s != NC_NOERR) {
        int st = out_fail(o, s, "close", err);
        dfle_file_abort(&o->file);
        return st;
    }
    return dfle_file_commit(&o->file, err);
}

static void out_abort(nc_out *o)
{
    if (o->ncid >= 0)
        nc_close(o->ncid);
    o->ncid = -1;
    dfle_file_abort(&o->file);
}

int dfle_nc_write_profiles(const char *path, size_t n, const double *x, const double *A,
                           size_t nt, const double *t, size_t nvars, const dfle_nc_var *vars,
                           const double *const *values, const dfle_nc_opts *opts,
                           dfle_error *err)
{
    static const dfle_nc_var A_var = {"A", "m^2", "drainage area", NULL, NULL};
    dfle_nc_opts op;
    nc_out out, *o = &out;
    int dims[2], tv, xv, av, *vid = NULL, st;
    double t_max = 0;

    if (opts != NULL)
        op = *opts;
    else
        dfle_nc_opts_default(&op);
    if (n == 0 || nt == 0 || nvars == 0)
        return dfle_error_set(err, DFLE_EINVAL, "netcdf: nothing to write (%zu nodes, %zu times, "
                              "%zu variables)", n, nt, nvars);
    for (size_t k = 0; k < nt; k++)
        t_max = t[k] > t_max ? t[k] : t_max;
    if ((vid = malloc(nvars * sizeof *vid)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "netcdf: out of memory");
    if ((st = out_begin(o, path, err)) != DFLE_OK) {
        free(vid);
        return st;
    }
    NC_DO(nc_def_dim(o->ncid, "time", nt, &dims[0]), "time");
    NC_DO(nc_def_dim(o->ncid, "x", n, &dims[1]), "x");
    NC_DO(nc_def_var(o->ncid, "time", NC_DOUBLE, 1, &dims[0], &tv), "time");
    NC_DO(nc_cf_put_time(o->ncid, tv, t_max), "time");
    NC_DO(nc_def_var(o->ncid, "x", NC_DOUBLE, 1, &dims[1], &xv), "x");
    NC_DO(text_att(o->ncid, xv, "units", "m"), "x");
    NC_DO(text_att(o->ncid, xv, "long_name", "distance from the channel head"), "x");
    NC_DO(text_att(o->ncid, xv, "axis", "X"), "x");
    if ((st = def_var(o, &A_var, 1, &dims[1], 0, op.deflate, &av, err)) != DFLE_OK)
        goto fail;
    for (size_t k = 0; k < nvars; k++) {
        if ((st = def_var(o, &vars[k], 2, dims, op.float32, op.deflate, &vid[k], err)) !=
            DFLE_OK)
            goto fail;
        NC_DO(text_att(o->ncid, vid[k], "coordinates", "A"), vars[k].name);
    }
    if ((st = out_globals(o, op.title, op.provenance, 0, NULL, err)) != DFLE_OK)
        goto fail;
    NC_DO(nc_enddef(o->ncid), "header");
    NC_DO(nc_put_var_double(o->ncid, tv, t), "time");
    NC_DO(nc_put_var_double(o->ncid, xv, x), "x");
    NC_DO(nc_put_var_double(o->ncid, av, A), "A");
    for (size_t k = 0; k < nvars; k++)
        NC_DO(nc_put_var_double(o->ncid, vid[k], values[k]), vars[k].name);
    free(vid);
    return out_finish(o, err);
fail:
    free(vid);
    out_abort(o);
    return st;
}

int dfle_nc_write_table(const char *path, const char *dim, size_t nrows, size_t ncols,
                        const dfle_nc_var *cols, const double *const *values, size_t ntext,
                        const dfle_nc_text *text, size_t nattrs, const dfle_nc_attr *attrs,
                        dfle_error *err)
{
    nc_out out, *o = &out;
    int rows, *vid = NULL, *tid = NULL, st;
    char *buf = NULL;

    if (nrows == 0 || ncols + ntext == 0)
        return dfle_error_set(err, DFLE_EINVAL, "netcdf: nothing to write (%zu rows, %zu "
                              "columns)", nrows, ncols + ntext);
    vid = malloc((ncols + 1) * sizeof *vid);
    tid = malloc((ntext + 1) * sizeof *tid);
    if (vid == NULL || tid == NULL) {
        free(vid);
        free(tid);
        return dfle_error_set(err, DFLE_ENOMEM, "netcdf: out of memory");
    }
    if ((st = out_begin(o, path, err)) != DFLE_OK) {
        free(vid);
        free(tid);
        return st;
    }
    NC_DO(nc_def_dim(o->ncid, dim, nrows, &rows), dim);
    for (size_t k = 0; k < ncols; k++)
        if ((st = def_var(o, &cols[k], 1, &rows, 0, 4, &vid[k], err)) != DFLE_OK)
            goto fail;
    /* Text as char[row][len], len the longest value (at least 1). */
    for (size_t k = 0; k < ntext; k++) {
        size_t len = 1;
        int d[2];
        char lname[128];
        for (size_t r = 0; r < nrows; r++)
            if (text[k].values[r] != NULL && strlen(text[k].values[r]) > len)
                len = strlen(text[k].values[r]);
        snprintf(lname, sizeof lname, "%s_length", text[k].name);
        d[0] = rows;
        NC_DO(nc_def_dim(o->ncid, lname, len, &d[1]), lname);
        NC_DO(nc_def_var(o->ncid, text[k].name, NC_CHAR, 2, d, &tid[k]), text[k].name);
        if (text[k].long_name != NULL)
            NC_DO(text_att(o->ncid, tid[k], "long_name", text[k].long_name), text[k].name);
    }
    if ((st = out_globals(o, NULL, NULL, nattrs, attrs, err)) != DFLE_OK)
        goto fail;
    NC_DO(nc_enddef(o->ncid), "header");
    for (size_t k = 0; k < ncols; k++)
        NC_DO(nc_put_var_double(o->ncid, vid[k], values[k]), cols[k].name);
    for (size_t k = 0; k < ntext; k++) {
        int d[2];
        size_t len;
        NC_DO(nc_inq_vardimid(o->ncid, tid[k], d), text[k].name);
        NC_DO(nc_inq_dimlen(o->ncid, d[1], &len), text[k].name);
        if ((buf = calloc(nrows, len)) == NULL) {
            st = dfle_error_set(err, DFLE_ENOMEM, "netcdf: out of memory");
            goto fail;
        }
        for (size_t r = 0; r < nrows; r++)
            if (text[k].values[r] != NULL)
                memcpy(buf + r * len, text[k].values[r], strlen(text[k].values[r]));
        NC_DO(nc_put_var_text(o->ncid, tid[k], buf), text[k].name);
        free(buf);
        buf = NULL;
    }
    free(vid);
    free(tid);
    return out_finish(o, err);
fail:
    free(buf);
    free(vid);
    free(tid);
    out_abort(o);
    return st;
}
