/*
 * drainage.c - the routing object: options, the grid's geometry, where
 * water may leave the grid, the order of the steps of a routing, and
 * access to the results.
 *
 * The steps live one per file (drainage_fill.c, drainage_d8.c,
 * drainage_flats.c, drainage_basins.c, drainage_tree.c); this file only
 * decides which run.  Output arrays are allocated with the object, the
 * workspace on first need, and both are kept (until dfle_drainage_trim),
 * so a landscape model that re-routes every time step allocates nothing
 * after its first step.
 */
#include "drainage/drainage_internal.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

const int dfle_drainage_dr[8] = {0, 1, 1, 1, 0, -1, -1, -1};
const int dfle_drainage_dc[8] = {1, 1, 0, -1, -1, -1, 0, 1};

void dfle_drainage_opts_default(dfle_drainage_opts *o)
{
    memset(o, 0, sizeof *o);
    o->dx = o->dy = 1.0;
    for (int s = 0; s < 4; s++)
        o->edge[s] = DFLE_DRAINAGE_OPEN;
    o->nodata = DFLE_DRAINAGE_OPEN;
    o->depressions = DFLE_DRAINAGE_KEEP;
    o->order = DFLE_DRAINAGE_KAHN;
}

static int valid_edge(enum dfle_drainage_edge e)
{
    return e == DFLE_DRAINAGE_OPEN || e == DFLE_DRAINAGE_BASE_LEVEL || e == DFLE_DRAINAGE_CLOSED;
}

static int check_opts(const dfle_drainage_opts *o, dfle_error *err)
{
    if (o->nx == 0 || o->ny == 0)
        return dfle_error_set(err, DFLE_EINVAL, "drainage: the grid has %zu x %zu cells; need at "
                              "least 1 x 1", o->nx, o->ny);
    /* Indices are uint32 on every large array: 4 bytes a cell, not 8. */
    if (o->nx > (size_t)(UINT32_MAX - 1) / o->ny)
        return dfle_error_set(err, DFLE_EINVAL, "drainage: %zu x %zu cells is more than dfle "
                              "routes (2^32 - 1)", o->nx, o->ny);
    if (!(isfinite(o->dx) && o->dx > 0 && isfinite(o->dy) && o->dy > 0))
        return dfle_error_set(err, DFLE_EINVAL, "drainage: cell size must be finite and > 0 m "
                              "(got dx = %g, dy = %g)", o->dx, o->dy);
    for (int s = 0; s < 4; s++)
        if (!valid_edge(o->edge[s]))
            return dfle_error_set(err, DFLE_EINVAL, "drainage: edge[%d] = %d is not an edge kind "
                                  "(OPEN, BASE_LEVEL, CLOSED)", s, (int)o->edge[s]);
    if (!valid_edge(o->nodata))
        return dfle_error_set(err, DFLE_EINVAL, "drainage: nodata = %d is not an edge kind "
                              "(OPEN, BASE_LEVEL, CLOSED)", (int)o->nodata);
    if (o->depressions != DFLE_DRAINAGE_KEEP && o->depressions != DFLE_DRAINAGE_FILL &&
        o->depressions != DFLE_DRAINAGE_CARVE)
        return dfle_error_set(err, DFLE_EINVAL, "drainage: depressions = %d is not a method "
                              "(KEEP, FILL, CARVE)", (int)o->depressions);
    if (o->order != DFLE_DRAINAGE_KAHN && o->order != DFLE_DRAINAGE_DEPTH_FIRST &&
        o->order != DFLE_DRAINAGE_CHAINS)
        return dfle_error_set(err, DFLE_EINVAL, "drainage: order = %d is not a stack order "
                              "(KAHN, DEPTH_FIRST, CHAINS)", (int)o->order);
    return DFLE_OK;
}

void dfle_drainage_trim(dfle_drainage *dr)
{
    drainage_basins empty = {0};
    if (dr == NULL)
        return;
    free(dr->mark);
    for (int k = 0; k < 3; k++)
        free(dr->work[k]);
    free(dr->zfill);
    free(dr->heap);
    free(dr->height);
    free(dr->bg.block); /* all the per-basin arrays */
    free(dr->bg.link);
    free(dr->bg.spare);
    dr->mark = NULL;
    for (int k = 0; k < 3; k++)
        dr->work[k] = NULL;
    dr->zfill = NULL;
    dr->heap = NULL;
    dr->heap_cap = 0;
    dr->height = NULL;
    dr->height_cap = 0;
    dr->bg = empty;
}

void dfle_drainage_free(dfle_drainage *dr)
{
    if (dr == NULL)
        return;
    dfle_drainage_trim(dr);
    free(dr->rcv);
    free(dr->dir);
    free(dr->don_off);
    free(dr->don);
    free(dr->stack);
    free(dr->area);
    free(dr->outlet);
    free(dr);
}

int dfle_drainage_new(const dfle_drainage_opts *opts, dfle_drainage **out, dfle_error *err)
{
    dfle_drainage *dr;
    size_t n;
    int st;

    *out = NULL;
    if (opts == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "drainage: options are required");
    if ((st = check_opts(opts, err)) != DFLE_OK)
        return st;
    n = opts->nx * opts->ny;
    if ((dr = calloc(1, sizeof *dr)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "drainage: out of memory");
    dr->o = *opts;
    dr->n = n;
    for (int k = 0; k < 8; k++) {
        /* The diagonal as sqrt(dx^2 + dy^2), the expression the DEM's
         * slopes have always used: a tie between a diagonal and a side
         * must break the same way. */
        dr->len[k] = dfle_drainage_dr[k] == 0   ? opts->dx
                     : dfle_drainage_dc[k] == 0 ? opts->dy
                                                : sqrt(opts->dx * opts->dx + opts->dy * opts->dy);
        dr->step[k] = (long long)dfle_drainage_dr[k] * (long long)opts->nx + dfle_drainage_dc[k];
    }
    dr->inv_nx = 1.0 / (double)opts->nx;
    dr->rcv = malloc(n * sizeof *dr->rcv);
    dr->dir = malloc(n);
    dr->don_off = malloc((n + 1) * sizeof *dr->don_off);
    dr->don = malloc(n * sizeof *dr->don);
    dr->stack = malloc(n * sizeof *dr->stack);
    dr->area = malloc(n * sizeof *dr->area);
    if (dr->rcv == NULL || dr->dir == NULL || dr->don_off == NULL || dr->don == NULL ||
        dr->stack == NULL || dr->area == NULL) {
        dfle_drainage_free(dr);
        return dfle_error_set(err, DFLE_ENOMEM, "drainage: out of memory for %zu x %zu cells",
                              opts->nx, opts->ny);
    }
    *out = dr;
    return DFLE_OK;
}

uint32_t *drainage_work(dfle_drainage *dr, int k)
{
    if (dr->work[k] == NULL)
        dr->work[k] = malloc(dr->n * sizeof *dr->work[k]);
    return dr->work[k];
}

unsigned char *drainage_mark(dfle_drainage *dr)
{
    if (dr->mark == NULL)
        dr->mark = malloc(dr->n);
    return dr->mark;
}

/* ---------------------------------------------------------------- */
/* Where water may leave                                            */
/* ---------------------------------------------------------------- */

/* Openness: CLOSED < OPEN < BASE_LEVEL. */
static int openness(enum dfle_drainage_edge e)
{
    return e == DFLE_DRAINAGE_CLOSED ? 0 : e == DFLE_DRAINAGE_OPEN ? 1 : 2;
}

static enum dfle_drainage_edge more_open(enum dfle_drainage_edge a, enum dfle_drainage_edge b)
{
    return openness(b) > openness(a) ? b : a;
}

enum dfle_drainage_edge drainage_exit_known(const dfle_drainage *dr, size_t i, int nodata_nb)
{
    size_t r = i / dr->o.nx, c = i % dr->o.nx;
    enum dfle_drainage_edge e = DFLE_DRAINAGE_CLOSED;
    if (dr->outlet != NULL && dr->outlet[i])
        return DFLE_DRAINAGE_BASE_LEVEL;
    if (r == 0)
        e = more_open(e, dr->o.edge[DFLE_DRAINAGE_NORTH]);
    if (c + 1 == dr->o.nx)
        e = more_open(e, dr->o.edge[DFLE_DRAINAGE_EAST]);
    if (r + 1 == dr->o.ny)
        e = more_open(e, dr->o.edge[DFLE_DRAINAGE_SOUTH]);
    if (c == 0)
        e = more_open(e, dr->o.edge[DFLE_DRAINAGE_WEST]);
    if (nodata_nb)
        e = more_open(e, dr->o.nodata);
    return e;
}

enum dfle_drainage_edge drainage_exit(const dfle_drainage *dr, const double *z, size_t i)
{
    size_t r = i / dr->o.nx, c = i % dr->o.nx;
    int nodata_nb = 0;
    for (int k = 0; k < 8 && !nodata_nb; k++) {
        long long nb = drainage_nb(dr, r, c, k);
        nodata_nb = nb >= 0 && isnan(z[nb]);
    }
    return drainage_exit_known(dr, i, nodata_nb);
}

unsigned char drainage_code(const dfle_drainage *dr, size_t a, size_t b)
{
    /* [dr + 1][dc + 1] -> k; the centre is not a neighbour. */
    static const unsigned char code[3][3] = {{5, 6, 7}, {4, DIR_SINK, 0}, {3, 2, 1}};
    long long nx = (long long)dr->o.nx, d = (long long)b - (long long)a, drow, dcol;
    /* With 3 or more columns the index difference alone names the
     * neighbour (no division: carving asks this of every cell it
     * reverses). */
    if (nx >= 3) {
        drow = d > 1 ? 1 : d < -1 ? -1 : 0;
        dcol = d - drow * nx;
    } else {
        drow = (long long)(b / dr->o.nx) - (long long)(a / dr->o.nx);
        dcol = (long long)(b % dr->o.nx) - (long long)(a % dr->o.nx);
    }
    assert(drow >= -1 && drow <= 1 && dcol >= -1 && dcol <= 1 && (drow != 0 || dcol != 0));
    return code[drow + 1][dcol + 1];
}

int dfle_drainage_set_outlets(dfle_drainage *dr, const size_t *cells, size_t n,
                              dfle_error *err)
{
    for (size_t k = 0; k < n; k++)
        if (cells[k] >= dr->n)
            return dfle_error_set(err, DFLE_EINVAL, "drainage: outlet %zu is cell %zu, off the "
                                  "grid of %zu cells", k + 1, cells[k], dr->n);
    dr->routed = 0;
    if (cells == NULL || n == 0) {
        free(dr->outlet);
        dr->outlet = NULL;
        return DFLE_OK;
    }
    if (dr->outlet == NULL && (dr->outlet = malloc(dr->n)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "drainage: out of memory");
    memset(dr->outlet, 0, dr->n);
    for (size_t k = 0; k < n; k++)
        dr->outlet[cells[k]] = 1;
    return DFLE_OK;
}

int dfle_drainage_set_hysteresis(dfle_drainage *dr, double margin, dfle_error *err)
{
    if (!(margin >= 0 && margin < 1))
        return dfle_error_set(err, DFLE_EINVAL, "drainage: the hysteresis margin must be in [0, "
                              "1) (got %g)", margin);
    dr->hysteresis = margin;
    return DFLE_OK;
}

int dfle_drainage_keep_directions(dfle_drainage *dr, const unsigned char *dir, dfle_error *err)
{
    if (!dr->routed)
        return dfle_error_set(err, DFLE_ESTATE, "drainage: directions can be put back only "
                              "over a routing");
    memcpy(dr->dir, dir, dr->n);
    /* The other arrays belong to another routing now: route again. */
    dr->routed = 0;
    dr->dirs_given = 1;
    return DFLE_OK;
}

/* ---------------------------------------------------------------- */
/* Routing                                                          */
/* ---------------------------------------------------------------- */

/* The first infinite elevation, for the message. */
static int infinite_at(const dfle_drainage *dr, const double *z, dfle_error *err)
{
    size_t i = 0;
    while (i + 1 < dr->n && !isinf(z[i]))
        i++;
    return dfle_error_set(err, DFLE_EINVAL, "drainage: elevation of cell %zu (row %zu, column "
                          "%zu) is infinite; use NaN for NoData", i, i / dr->o.nx, i % dr->o.nx);
}

int dfle_drainage_route(dfle_drainage *dr, const double *z, dfle_error *err)
{
    size_t n_sinks, n_data;
    int st, infinite;

    if (z == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "drainage: elevations are required");
    dr->dirs_kept = dr->routed || dr->dirs_given; /* dir[] holds a whole routing (hysteresis) */
    dr->dirs_given = 0;
    dr->routed = 0;
    memset(&dr->counts, 0, sizeof dr->counts);
    if (dr->o.depressions == DFLE_DRAINAGE_FILL) {
        dfle_drainage_fill_stats fs;
        if (dr->zfill == NULL && (dr->zfill = malloc(dr->n * sizeof *dr->zfill)) == NULL)
            return dfle_error_set(err, DFLE_ENOMEM, "drainage: out of memory for the filled "
                                  "surface");
        memcpy(dr->zfill, z, dr->n * sizeof *z);
        if ((st = dfle_drainage_fill(dr, dr->zfill, &fs, err)) != DFLE_OK)
            return st;
        dr->counts.filled = fs.raised;
        z = dr->zfill;
    }
    n_sinks = drainage_d8(dr, z, &n_data, &infinite);
    if (infinite)
        return infinite_at(dr, z, err);
    if (n_data == 0)
        return dfle_error_set(err, DFLE_EINVAL, "drainage: every cell is NoData");
    dr->counts.pits = n_sinks;
    if (n_sinks > 0 && (st = drainage_flats(dr, z, n_sinks, err)) != DFLE_OK)
        return st;
    dr->counts.pits -= dr->counts.flats;
    drainage_donors(dr);
    if (dr->counts.pits > 0 && dr->o.depressions == DFLE_DRAINAGE_CARVE) {
        if ((st = drainage_carve(dr, z, err)) != DFLE_OK)
            return st;
        drainage_donors(dr);
    }
    if ((st = drainage_stack(dr, n_data, err)) != DFLE_OK)
        return st;
    dr->counts.data = n_data;
    dr->routed = 1;
    return DFLE_OK;
}

/* ---------------------------------------------------------------- */
/* Access                                                           */
/* ---------------------------------------------------------------- */

const uint32_t *dfle_drainage_receivers(const dfle_drainage *dr)
{
    return dr->routed ? dr->rcv : NULL;
}

const unsigned char *dfle_drainage_dir(const dfle_drainage *dr)
{
    return dr->routed ? dr->dir : NULL;
}

const uint32_t *dfle_drainage_donors(const dfle_drainage *dr, const uint32_t **offsets)
{
    if (offsets != NULL)
        *offsets = dr->routed ? dr->don_off : NULL;
    return dr->routed ? dr->don : NULL;
}

const uint32_t *dfle_drainage_stack(const dfle_drainage *dr, size_t *n_stack)
{
    if (n_stack != NULL)
        *n_stack = dr->routed ? dr->n_stack : 0;
    return dr->routed ? dr->stack : NULL;
}

const double *dfle_drainage_area(const dfle_drainage *dr)
{
    return dr->routed ? dr->area : NULL;
}

dfle_drainage_counts dfle_drainage_get_counts(const dfle_drainage *dr)
{
    return dr->counts;
}

void dfle_drainage_get_opts(const dfle_drainage *dr, dfle_drainage_opts *o)
{
    *o = dr->o;
}

long long dfle_drainage_neighbour(const dfle_drainage *dr, size_t i, int k)
{
    if (i >= dr->n || k < 0 || k > 7)
        return -1;
    return drainage_nb(dr, i / dr->o.nx, i % dr->o.nx, k);
}

double dfle_drainage_length(const dfle_drainage *dr, int k)
{
    return k >= 0 && k < 8 ? dr->len[k] : NAN;
}

size_t dfle_drainage_memory(const dfle_drainage *dr)
{
    size_t n = dr->n, b = dr->bg.cap, bytes = sizeof *dr;
    bytes += n * (sizeof *dr->rcv + 1 + sizeof *dr->don + sizeof *dr->stack + sizeof *dr->area);
    bytes += (n + 1) * sizeof *dr->don_off;
    bytes += dr->mark != NULL ? n : 0;
    bytes += dr->outlet != NULL ? n : 0;
    for (int k = 0; k < 3; k++)
        bytes += dr->work[k] != NULL ? n * sizeof *dr->work[k] : 0;
    bytes += dr->zfill != NULL ? n * sizeof *dr->zfill : 0;
    bytes += dr->heap_cap * sizeof *dr->heap + dr->height_cap * sizeof *dr->height;
    bytes += b > 0 ? DRAINAGE_BASIN_WORDS(b) * sizeof(uint32_t) : 0;
    bytes += 2 * dr->bg.link_cap * sizeof *dr->bg.link;
    return bytes;
}
