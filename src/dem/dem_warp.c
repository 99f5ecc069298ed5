/*
 * dem_warp.c - a DEM resampled to another cell size or cropped to a box,
 * through GDAL's own tools (gdalwarp and gdal_translate as a library):
 * dfle_dem_resample, dfle_dem_crop (dem.h).
 *
 * The grid goes to GDAL's MEM driver and comes back through the reader's
 * checks (dem_gdal.h), so a resampled or cropped DEM is a DEM like any
 * read from a file: same CRS, NoData NaN, no file of its own.
 *  - Resampling keeps the north-west corner and covers the whole old
 *    extent (the last column and row may reach past it; their cells
 *    average what lies inside).  NoData is ignored by the averages: a
 *    cell is NoData only where no data falls in it.  Coarser cells
 *    default to "average" (a mean elevation, no aliasing), finer ones
 *    to "bilinear" (average would copy cells into blocks).
 *  - Cropping cuts whole cells (no resampling): the cells that overlap
 *    the box, so the result covers it.
 */
#include "dem/dem_gdal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* GDAL's names for the methods dfle offers ("nearest" is GDAL's "near"). */
static const char *const methods[][2] = {
    {"nearest", "near"}, {"bilinear", "bilinear"}, {"cubic", "cubic"},
    {"cubicspline", "cubicspline"}, {"lanczos", "lanczos"}, {"average", "average"},
    {"min", "min"}, {"max", "max"}, {"median", "med"}, {"mode", "mode"}};

static const char *gdal_message(const char *fallback)
{
    const char *m = CPLGetLastErrorMsg();
    return m != NULL && m[0] != '\0' ? m : fallback;
}

static GDALDatasetH warp(GDALDatasetH src, char **argv)
{
    GDALWarpAppOptions *o = GDALWarpAppOptionsNew(argv, NULL);
    GDALDatasetH dst = NULL;
    int usage = 0;
    if (o != NULL) {
        dst = GDALWarp("", NULL, 1, &src, o, &usage);
        GDALWarpAppOptionsFree(o);
    }
    return dst;
}

static GDALDatasetH translate(GDALDatasetH src, char **argv)
{
    GDALTranslateOptions *o = GDALTranslateOptionsNew(argv, NULL);
    GDALDatasetH dst = NULL;
    int usage = 0;
    if (o != NULL) {
        dst = GDALTranslate("", src, o, &usage);
        GDALTranslateOptionsFree(o);
    }
    return dst;
}

/* The DEM through one of GDAL's tools (argv: its options, in memory)
 * and back as a new DEM; `what` names the result in messages. */
static int run_tool(const dfle_dem *dem, GDALDatasetH (*tool)(GDALDatasetH, char **), char **argv,
                    const char *what, dfle_dem **out, dfle_error *err)
{
    GDALDatasetH src, dst;
    int st;
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
    if ((src = dem_to_gdal(dem, err)) == NULL) {
        CPLPopErrorHandler();
        return err != NULL ? err->code : DFLE_EIO;
    }
    if ((dst = tool(src, argv)) == NULL) {
        st = dfle_error_set(err, DFLE_EIO, "dem: GDAL could not make %s: %s", what,
                            gdal_message("it failed"));
    } else {
        st = dem_from_gdal(dst, what, out, err);
        GDALClose(dst);
    }
    GDALClose(src);
    CPLPopErrorHandler();
    return st;
}

/* Cells dfle can hold, checked before GDAL allocates them. */
static int check_size(double nx, double ny, const char *what, dfle_error *err)
{
    if (!(nx >= 1 && ny >= 1 && nx * ny <= 2e9 && nx < 2147483647.0 && ny < 2147483647.0))
        return dfle_error_set(err, DFLE_EINVAL, "dem: %s would have %.0f x %.0f cells; dfle "
                              "holds at most 2e9", what, nx, ny);
    return DFLE_OK;
}

int dfle_dem_resample(const dfle_dem *dem, double dx, double dy, const char *method,
                      dfle_dem **out, dfle_error *err)
{
    double e[4], nx, ny, old = dfle_dem_dx(dem);
    const char *how = NULL;
    char a[6][40], *argv[20];
    int argc = 0, st;

    *out = NULL;
    if (dy == 0)
        dy = dx;
    if (!(isfinite(dx) && dx > 0 && isfinite(dy) && dy > 0 && dx <= 1e6 && dy <= 1e6))
        return dfle_error_set(err, DFLE_EINVAL, "dem: resample: dx and dy are cell sizes from "
                              "0 to 1e6 m (got %g, %g)", dx, dy);
    if (method == NULL)
        method = dx >= old ? "average" : "bilinear";
    for (size_t k = 0; k < sizeof methods / sizeof methods[0]; k++)
        if (strcmp(method, methods[k][0]) == 0)
            how = methods[k][1];
    if (how == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "dem: resample: method must be 'nearest', "
                              "'bilinear', 'cubic', 'cubicspline', 'lanczos', 'average', 'min', "
                              "'max', 'median' or 'mode' (got '%s')", method);
    dfle_dem_extent(dem, e);
    nx = ceil((e[1] - e[0]) / dx - 1e-9);
    ny = ceil((e[3] - e[2]) / dy - 1e-9);
    if ((st = check_size(nx, ny, "the resampled grid", err)) != DFLE_OK)
        return st;
    if ((st = dfle_gdal_load("dem.resample", err)) != DFLE_OK)
        return st;
    snprintf(a[0], sizeof a[0], "%.17g", dx);
    snprintf(a[1], sizeof a[1], "%.17g", dy);
    snprintf(a[2], sizeof a[2], "%.17g", e[0]);
    snprintf(a[3], sizeof a[3], "%.17g", e[3] - ny * dy);
    snprintf(a[4], sizeof a[4], "%.17g", e[0] + nx * dx);
    snprintf(a[5], sizeof a[5], "%.17g", e[3]);
    {
        char *fixed[] = {"-of", "MEM", "-r", (char *)how, "-tr", a[0], a[1], "-te", a[2], a[3],
                         a[4], a[5], "-srcnodata", "nan", "-dstnodata", "nan", "-ot", "Float64"};
        for (size_t k = 0; k < sizeof fixed / sizeof fixed[0]; k++)
            argv[argc++] = fixed[k];
        argv[argc] = NULL;
    }
    return run_tool(dem, warp, argv, "the resampled grid", out, err);
}

int dfle_dem_data_extent(const dfle_dem *dem, double box[4])
{
    const size_t nx = dfle_dem_nx(dem), ny = dfle_dem_ny(dem);
    const double *z = dfle_dem_z(dem);
    size_t c0 = nx, c1 = 0, r0 = ny, r1 = 0;
    double e[4];
    for (size_t r = 0; r < ny; r++)
        for (size_t c = 0; c < nx; c++)
            if (!isnan(z[r * nx + c])) {
                c0 = c < c0 ? c : c0, c1 = c > c1 ? c : c1;
                r0 = r < r0 ? r : r0, r1 = r > r1 ? r : r1;
            }
    if (c0 > c1)
        return 0;
    dfle_dem_extent(dem, e);
    box[0] = e[0] + (double)c0 * dfle_dem_dx(dem);
    box[1] = e[0] + (double)(c1 + 1) * dfle_dem_dx(dem);
    box[2] = e[3] - (double)(r1 + 1) * dfle_dem_dy(dem);
    box[3] = e[3] - (double)r0 * dfle_dem_dy(dem);
    return 1;
}

int dfle_dem_crop(const dfle_dem *dem, const double box[4], dfle_dem **out, dfle_error *err)
{
    const double dx = dfle_dem_dx(dem), dy = dfle_dem_dy(dem);
    double e[4], c0, c1, r0, r1;
    char a[4][32], *argv[12];
    int st;

    *out = NULL;
    dfle_dem_extent(dem, e);
    for (int k = 0; k < 4; k++)
        if (isnan(box[k]))
            return dfle_error_set(err, DFLE_EINVAL, "dem: crop: the box's edges must be numbers");
    if (!(box[0] < box[1] && box[2] < box[3]))
        return dfle_error_set(err, DFLE_EINVAL, "dem: crop: the box must have E_min < E_max and "
                              "N_min < N_max (got E %.10g..%.10g, N %.10g..%.10g)", box[0], box[1],
                              box[2], box[3]);
    /* The columns and rows of the cells that overlap the box. */
    c0 = floor((fmax(box[0], e[0]) - e[0]) / dx);
    c1 = ceil((fmin(box[1], e[1]) - e[0]) / dx);
    r0 = floor((e[3] - fmin(box[3], e[3])) / dy);
    r1 = ceil((e[3] - fmax(box[2], e[2])) / dy);
    if (!(c1 > c0 && r1 > r0))
        return dfle_error_set(err, DFLE_EINVAL, "dem: crop: the box (E %.10g..%.10g, N "
                              "%.10g..%.10g) does not overlap the grid (E %.10g..%.10g, N "
                              "%.10g..%.10g)", box[0], box[1], box[2], box[3], e[0], e[1], e[2],
                              e[3]);
    if ((st = dfle_gdal_load("dem.crop", err)) != DFLE_OK)
        return st;
    snprintf(a[0], sizeof a[0], "%.0f", c0);
    snprintf(a[1], sizeof a[1], "%.0f", r0);
    snprintf(a[2], sizeof a[2], "%.0f", c1 - c0);
    snprintf(a[3], sizeof a[3], "%.0f", r1 - r0);
    argv[0] = "-of", argv[1] = "MEM", argv[2] = "-srcwin";
    argv[3] = a[0], argv[4] = a[1], argv[5] = a[2], argv[6] = a[3], argv[7] = NULL;
    return run_tool(dem, translate, argv, "the cropped grid", out, err);
}
