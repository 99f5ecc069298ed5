/*
 * netcdf_read.c - one record of a NetCDF grid file back onto a grid
 * (raster.h, dfle_nc_read_grid): a run restarted from its own output.
 *
 * The file says where its cells are (x and y at cell centres, cropped
 * to the data's bounding box), so it is placed on the grid by its
 * coordinates, not assumed to be the whole grid; a file whose cells are
 * not cells of the grid (another cell size, an offset of part of a
 * cell, a window outside it) or whose CRS differs is refused, naming
 * what does not match.
 */
#include "dfle/raster.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "base/netcdf_lib.h" /* libnetcdf, loaded by the first read */
#include "dfle/crs.h"

typedef struct reader {
    const char *path;
    int ncid;
    dfle_error *err;
} reader;

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static int bad(reader *r, const char *fmt, ...)
{
    char what[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return dfle_error_set(r->err, DFLE_EINVAL, "netcdf: '%s': %s", r->path, what);
}

static int nc_bad(reader *r, int s, const char *what)
{
    return dfle_error_set(r->err, DFLE_EIO, "netcdf: cannot read '%s' (%s): %s", r->path, what,
                          nc_strerror(s));
}

/* A 1-D variable `name` of n values (malloc'd into *out). */
static int read_axis(reader *r, const char *name, size_t n, double **out)
{
    int v, nd, s;
    size_t len;
    int dim;
    *out = NULL;
    if ((s = nc_inq_varid(r->ncid, name, &v)) != NC_NOERR)
        return nc_bad(r, s, name);
    if ((s = nc_inq_varndims(r->ncid, v, &nd)) != NC_NOERR || nd != 1 ||
        (s = nc_inq_vardimid(r->ncid, v, &dim)) != NC_NOERR ||
        (s = nc_inq_dimlen(r->ncid, dim, &len)) != NC_NOERR || len != n)
        return s != NC_NOERR ? nc_bad(r, s, name)
                             : bad(r, "'%s' is not the coordinate of its dimension", name);
    if ((*out = malloc((n > 0 ? n : 1) * sizeof **out)) == NULL)
        return dfle_error_set(r->err, DFLE_ENOMEM, "netcdf: out of memory");
    if ((s = nc_get_var_double(r->ncid, v, *out)) != NC_NOERR) {
        free(*out);
        *out = NULL;
        return nc_bad(r, s, name);
    }
    return DFLE_OK;
}

/* The offset (in cells) of coordinates c[0..n) on the grid's centres
 * `origin + (k + 0.5) step`, step > 0 along x and < 0 along y. */
static int place(reader *r, const char *axis, const double *c, size_t n, double origin,
                 double step, size_t cells, size_t *off)
{
    double k0 = (c[0] - origin) / step - 0.5, first = round(k0);
    if (!(fabs(k0 - first) < 1e-6) || first < 0 || first + (double)n > (double)cells)
        return bad(r, "its %s coordinates (from %.10g) are not centres of cells of the grid, or lie "
                   "outside it (the grid's first centre is at %.10g)", axis, c[0],
                   origin + 0.5 * step);
    for (size_t j = 0; j < n; j++) {
        double want = origin + (first + (double)j + 0.5) * step;
        if (!(fabs(c[j] - want) < 1e-6 * fabs(step)))
            return bad(r, "its %s coordinate %.10g is not the grid's cell centre %.10g", axis,
                       c[j], want);
    }
    *off = (size_t)first;
    return DFLE_OK;
}

/* The file's CRS (the crs variable's crs_wkt) against the grid's. */
static int check_crs(reader *r, const char *grid_wkt)
{
    int v;
    size_t len;
    char *wkt;
    int st = DFLE_OK;
    if (grid_wkt == NULL || nc_inq_varid(r->ncid, "crs", &v) != NC_NOERR ||
        nc_inq_attlen(r->ncid, v, "crs_wkt", &len) != NC_NOERR)
        return DFLE_OK; /* nothing to compare */
    if ((wkt = malloc(len + 1)) == NULL)
        return dfle_error_set(r->err, DFLE_ENOMEM, "netcdf: out of memory");
    if (nc_get_att_text(r->ncid, v, "crs_wkt", wkt) == NC_NOERR) {
        wkt[len] = '\0';
        if (!dfle_crs_same(wkt, grid_wkt)) {
            dfle_crs_info a, b;
            char la[320] = "?", lb[320] = "?";
            if (dfle_crs_info_of(wkt, &a, r->err) == DFLE_OK)
                dfle_crs_label(&a, la, sizeof la);
            if (dfle_crs_info_of(grid_wkt, &b, r->err) == DFLE_OK)
                dfle_crs_label(&b, lb, sizeof lb);
            st = dfle_error_set(r->err, DFLE_EINVAL, "netcdf: '%s' is in %s, the grid in %s",
                                r->path, la, lb);
        }
    }
    free(wkt);
    return st;
}

int dfle_nc_read_grid(const char *path, const char *var, size_t index, double t,
                      const dfle_raster_geo *grid, size_t nx, size_t ny, double *out,
                      double *t_found, dfle_error *err)
{
    reader r = {path, -1, err};
    struct stat sb;
    int v, nd, dims[3], s, st;
    size_t len[3], c0 = 0, r0 = 0;
    double *tv = NULL, *xs = NULL, *ys = NULL, *slab = NULL;

    if ((st = dfle_netcdf_load("netcdf", err)) != DFLE_OK)
        return st;
    if (stat(path, &sb) != 0)
        return dfle_error_set(err, DFLE_EIO, "netcdf: cannot read '%s': no such file", path);
    if (!S_ISREG(sb.st_mode))
        return dfle_error_set(err, DFLE_EIO, "netcdf: cannot read '%s': not a regular file",
                              path);
    if ((s = nc_open(path, NC_NOWRITE, &r.ncid)) != NC_NOERR)
        return nc_bad(&r, s, "open");
    if ((s = nc_inq_varid(r.ncid, var, &v)) != NC_NOERR) {
        st = dfle_error_set(err, DFLE_EINVAL, "netcdf: '%s' has no field '%s' (was it recorded? "
                            "fields = {\"%s\", ...})", path, var, var);
        goto done;
    }
    if ((s = nc_inq_varndims(r.ncid, v, &nd)) != NC_NOERR || nd != 3) {
        st = s != NC_NOERR ? nc_bad(&r, s, var)
                           : bad(&r, "'%s' is not a field of (time, y, x)", var);
        goto done;
    }
    if ((s = nc_inq_vardimid(r.ncid, v, dims)) != NC_NOERR) {
        st = nc_bad(&r, s, var);
        goto done;
    }
    for (int k = 0; k < 3; k++)
        if ((s = nc_inq_dimlen(r.ncid, dims[k], &len[k])) != NC_NOERR) {
            st = nc_bad(&r, s, var);
            goto done;
        }
    if (len[0] == 0) {
        st = bad(&r, "it holds no records");
        goto done;
    }
    if ((st = read_axis(&r, "time", len[0], &tv)) != DFLE_OK ||
        (st = read_axis(&r, "y", len[1], &ys)) != DFLE_OK ||
        (st = read_axis(&r, "x", len[2], &xs)) != DFLE_OK)
        goto done;
    if (index == (size_t)-1) {
        for (index = 0; index < len[0]; index++)
            if (fabs(tv[index] - t) <= 1e-9 * (fabs(t) > 1 ? fabs(t) : 1))
                break;
        if (index == len[0]) {
            st = dfle_error_set(err, DFLE_EINVAL, "netcdf: '%s' has no record at t = %g yr (its "
                                "%zu records run from %g to %g yr)", path, t, len[0], tv[0],
                                tv[len[0] - 1]);
            goto done;
        }
    } else if (index >= len[0]) {
        st = dfle_error_set(err, DFLE_EINVAL, "netcdf: '%s' has %zu records (1 to %zu); there is "
                            "no record %zu", path, len[0], len[0], index + 1);
        goto done;
    }
    if ((st = place(&r, "x", xs, len[2], grid->x0, grid->dx, nx, &c0)) != DFLE_OK ||
        (st = place(&r, "y", ys, len[1], grid->y0, -grid->dy, ny, &r0)) != DFLE_OK ||
        (st = check_crs(&r, grid->crs_wkt)) != DFLE_OK)
        goto done;
    if ((slab = malloc(len[1] * len[2] * sizeof *slab)) == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "netcdf: out of memory");
        goto done;
    }
    {
        size_t start[3] = {index, 0, 0}, count[3] = {1, len[1], len[2]};
        if ((s = nc_get_vara_double(r.ncid, v, start, count, slab)) != NC_NOERR) {
            st = nc_bad(&r, s, var);
            goto done;
        }
    }
    for (size_t i = 0; i < nx * ny; i++)
        out[i] = NAN;
    for (size_t row = 0; row < len[1]; row++)
        memcpy(out + (row + r0) * nx + c0, slab + row * len[2], len[2] * sizeof *out);
    if (t_found != NULL)
        *t_found = tv[index];
done:
    free(tv), free(xs), free(ys), free(slab);
    nc_close(r.ncid);
    return st;
}
