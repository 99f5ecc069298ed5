/*
 * dem_profile.c - channels on a routed DEM: a profile traced upstream
 * from an outlet or downstream from a channel head, the channel network
 * above an area threshold, and the slope-area data along them.
 *
 * A profile is stored like a model channel, head first (x = 0) and
 * outlet last, so `A(x)` can become a dfle_channel and the slope-area
 * data go to the same fit as a model's.  A network is stored in
 * topological order (each cell before its receiver), which for a
 * single path is the same head-to-outlet order.
 *
 * Slope is measured over a fixed horizontal interval `ds` (default) or
 * a fixed vertical interval `dz`, centred on each cell, along the flow
 * path through it: upstream along the largest-area donor (for a
 * profile, along the profile itself), downstream along D8 receivers.  Elevations
 * between cell centres are interpolated linearly in flow distance.  The
 * window is cut short where the path ends (a divide, the grid's edge).
 * Because a filled DEM never rises downstream, S >= 0 everywhere.
 */
#include "dem/dem_internal.h"

#include "dfle/record.h"
#include "dfle/file.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void dfle_profile_opts_default(dfle_profile_opts *o)
{
    memset(o, 0, sizeof *o);
    o->radius = -1.0;
}

void dfle_network_opts_default(dfle_network_opts *o)
{
    memset(o, 0, sizeof *o);
    o->radius = -1.0;
}

void dfle_profile_free(dfle_profile *p)
{
    if (p == NULL)
        return;
    for (int k = 0; k < DFLE_PROFILE_NFIELDS; k++)
        free(p->f[k]);
    free(p->receiver);
    free(p->dem);
    free(p->crs);
    free(p);
}

static dfle_profile *profile_alloc(size_t n)
{
    dfle_profile *p = calloc(1, sizeof *p);
    int ok = p != NULL;
    for (int k = 0; ok && k < DFLE_PROFILE_NFIELDS; k++)
        ok = (p->f[k] = malloc(n * sizeof(double))) != NULL;
    if (ok)
        ok = (p->receiver = malloc(n * sizeof *p->receiver)) != NULL;
    if (!ok) {
        dfle_profile_free(p);
        return NULL;
    }
    p->n = n;
    return p;
}

/* ---------------------------------------------------------------- */
/* Preconditions and snapping                                       */
/* ---------------------------------------------------------------- */

static int check_slope_opts(const dfle_dem *d, dfle_slope_opts *s, dfle_error *err)
{
    if (!(isfinite(s->ds) && s->ds >= 0 && isfinite(s->dz) && s->dz >= 0))
        return dfle_error_set(err, DFLE_EINVAL, "dem: slope interval must be >= 0 m (got ds = %g, "
                              "dz = %g)", s->ds, s->dz);
    if (s->ds > 0 && s->dz > 0)
        return dfle_error_set(err, DFLE_EINVAL, "dem: give a horizontal (ds) or a vertical (dz) "
                              "slope interval, not both");
    if (s->ds == 0 && s->dz == 0)
        s->ds = 3.0 * (d->dx > d->dy ? d->dx : d->dy);
    return DFLE_OK;
}

/* Route if needed; refuse a DEM whose pits would cut drainage short. */
static int ready(dfle_dem *d, const char *what, dfle_error *err)
{
    int st;
    if ((st = dfle_dem_check_metric(d, what, err)) != DFLE_OK ||
        (st = dfle_dem_route(d, err)) != DFLE_OK)
        return st;
    if (dfle_dem_sink_count(d) > 0)
        return dfle_error_set(err, DFLE_EINVAL, "dem: %s: the DEM has %zu pit cell%s (no lower "
                              "neighbour, not on the edge), where drainage area would stop "
                              "short; fill it first (dem:fill())", what, dfle_dem_sink_count(d),
                              dfle_dem_sink_count(d) == 1 ? "" : "s");
    return DFLE_OK;
}

/* The snapping radius [m]: as given, or two cell diagonals. */
static double snap_radius(const dfle_dem *d, double radius)
{
    return radius < 0 ? 2.0 * sqrt(d->dx * d->dx + d->dy * d->dy) : radius;
}

/* The cell of largest drainage area whose centre is within `radius` of
 * (E, N), or the cell containing the point; ties go to the nearer. */
static int snap_outlet(const dfle_dem *d, double E, double N, double radius, size_t *out,
                       dfle_error *err)
{
    size_t home, best = (size_t)-1;
    double best_A = -1, best_d2 = 0, e, n;
    long long r0, r1, c0, c1;
    int st;

    if ((st = dfle_dem_cell_at(d, E, N, "outlet", &home, err)) != DFLE_OK)
        return st;
    radius = snap_radius(d, radius);
    r0 = (long long)floor((d->y0 - N - radius) / d->dy);
    r1 = (long long)floor((d->y0 - N + radius) / d->dy);
    c0 = (long long)floor((E - radius - d->x0) / d->dx);
    c1 = (long long)floor((E + radius - d->x0) / d->dx);
    for (long long r = r0 < 0 ? 0 : r0; r <= r1 && r < (long long)d->ny; r++)
        for (long long c = c0 < 0 ? 0 : c0; c <= c1 && c < (long long)d->nx; c++) {
            size_t i = (size_t)r * d->nx + (size_t)c;
            double d2;
            if (isnan(d->z[i]))
                continue;
            dfle_dem_cell_centre(d, i, &e, &n);
            d2 = (e - E) * (e - E) + (n - N) * (n - N);
            if (d2 > radius * radius && i != home)
                continue;
            if (dfle_dem_area(d)[i] > best_A || (dfle_dem_area(d)[i] == best_A && d2 < best_d2)) {
                best = i;
                best_A = dfle_dem_area(d)[i];
                best_d2 = d2;
            }
        }
    if (best == (size_t)-1)
        return dfle_error_set(err, DFLE_EINVAL, "dem: outlet (%.10g E, %.10g N) is on NoData "
                              "and no cell within radius = %g m has data", E, N, radius);
    *out = best;
    return DFLE_OK;
}

/* The donor of largest area (first in neighbour order on ties), or -1. */
static long long main_donor(const dfle_dem *d, size_t c)
{
    const double *A = dfle_dem_area(d);
    long long best = -1;
    /* Neighbour order, not the donor list's index order: it breaks the
     * ties, as doc/dem.md says. */
    for (int k = 0; k < 8; k++) {
        long long nb = dfle_drainage_neighbour(d->flow, c, k);
        if (nb < 0 || dfle_dem_receiver(d, (size_t)nb) != (long long)c)
            continue;
        if (best < 0 || A[nb] > A[best])
            best = nb;
    }
    return best;
}

/* Distance from cell c to its receiver [m]. */
static double step_length(const dfle_dem *d, size_t c)
{
    return dfle_drainage_length(d->flow, dfle_dem_dir(d)[c]);
}

/* ---------------------------------------------------------------- */
/* Paths and slope windows                                          */
/* ---------------------------------------------------------------- */

/* Cells along a flow path with their flow distance s [m] (increasing
 * downstream) and elevation z. */
typedef struct { uint32_t *c; double *s, *z; size_t n, cap; } flowpath;

static int path_push(flowpath *p, size_t c, double s, double z)
{
    if (p->n == p->cap) {
        size_t cap = p->cap ? 2 * p->cap : 256;
        uint32_t *nc = realloc(p->c, cap * sizeof *nc);
        double *ns, *nz;
        if (nc == NULL)
            return -1;
        p->c = nc;
        if ((ns = realloc(p->s, cap * sizeof *ns)) == NULL)
            return -1;
        p->s = ns;
        if ((nz = realloc(p->z, cap * sizeof *nz)) == NULL)
            return -1;
        p->z = nz;
        p->cap = cap;
    }
    p->c[p->n] = (uint32_t)c;
    p->s[p->n] = s;
    p->z[p->n] = z;
    p->n++;
    return 0;
}

static void path_free(flowpath *p)
{
    free(p->c);
    free(p->s);
    free(p->z);
}

/* Append to p the cells beyond `start` (flow distance s0) going
 * upstream (main donors; s decreasing) or downstream (receivers), until
 * the window's half-width is covered or the path ends. */
static int walk(const dfle_dem *d, size_t start, double s0, int upstream,
                const dfle_slope_opts *o, flowpath *p)
{
    double s = s0, z0 = d->z[start];
    size_t c = start;
    for (;;) {
        long long nx = upstream ? main_donor(d, c) : dfle_dem_receiver(d, c);
        if (nx < 0)
            return 0;
        s += upstream ? -step_length(d, (size_t)nx) : step_length(d, c);
        c = (size_t)nx;
        if (path_push(p, c, s, d->z[c]) != 0)
            return -1;
        if (o->ds > 0 ? fabs(s - s0) >= 0.5 * o->ds
                      : fabs(d->z[c] - z0) >= 0.5 * o->dz)
            return 0;
    }
}

/* Slope at index k of a path (s increasing, z non-increasing): the drop
 * over the window centred on cell k, divided by its length. */
static double window_slope(const flowpath *p, size_t k, const dfle_slope_opts *o)
{
    double su = p->s[0], zu = p->z[0], sd = p->s[p->n - 1], zd = p->z[p->n - 1];
    if (o->ds > 0) {
        double h = 0.5 * o->ds;
        for (size_t j = k; j > 0; j--)
            if (p->s[j - 1] <= p->s[k] - h) {
                double t = (p->s[k] - h - p->s[j - 1]) / (p->s[j] - p->s[j - 1]);
                su = p->s[k] - h;
                zu = p->z[j - 1] + t * (p->z[j] - p->z[j - 1]);
                break;
            }
        for (size_t j = k + 1; j < p->n; j++)
            if (p->s[j] >= p->s[k] + h) {
                double t = (p->s[k] + h - p->s[j - 1]) / (p->s[j] - p->s[j - 1]);
                sd = p->s[k] + h;
                zd = p->z[j - 1] + t * (p->z[j] - p->z[j - 1]);
                break;
            }
    } else {
        double h = 0.5 * o->dz;
        for (size_t j = k; j > 0; j--)
            if (p->z[j - 1] >= p->z[k] + h) {
                double t = (p->z[k] + h - p->z[j]) / (p->z[j - 1] - p->z[j]);
                zu = p->z[k] + h;
                su = p->s[j] - t * (p->s[j] - p->s[j - 1]);
                break;
            }
        for (size_t j = k + 1; j < p->n; j++)
            if (p->z[j] <= p->z[k] - h) {
                double t = (p->z[j - 1] - (p->z[k] - h)) / (p->z[j - 1] - p->z[j]);
                zd = p->z[k] - h;
                sd = p->s[j - 1] + t * (p->s[j] - p->s[j - 1]);
                break;
            }
    }
    return sd > su ? (zu - zd) / (sd - su) : 0.0;
}

/* Slopes S[j] of every cell of `core`, after extending it upstream
 * from its first cell and downstream from its last far enough for the
 * windows of the cells at its ends.  `up` and `all` are scratch paths,
 * reused across calls (a network calls this once per cell). */
static int slopes_along(const dfle_dem *d, const flowpath *core, const dfle_slope_opts *o,
                        flowpath *up, flowpath *all, double *S)
{
    up->n = all->n = 0;
    if (walk(d, core->c[0], core->s[0], 1, o, up) != 0)
        return -1;
    for (size_t j = up->n; j > 0; j--)
        if (path_push(all, up->c[j - 1], up->s[j - 1], up->z[j - 1]) != 0)
            return -1;
    for (size_t j = 0; j < core->n; j++)
        if (path_push(all, core->c[j], core->s[j], core->z[j]) != 0)
            return -1;
    if (walk(d, core->c[core->n - 1], core->s[core->n - 1], 0, o, all) != 0)
        return -1;
    for (size_t j = 0; j < core->n; j++)
        S[j] = window_slope(all, up->n + j, o);
    return 0;
}

/* The DEM's file name and CRS, for the profile's provenance and files. */
static int keep_dem_path(dfle_profile *p, const dfle_dem *d, dfle_error *err)
{
    if (profile_copy_text(&p->dem, dfle_dem_path(d)) != 0 ||
        profile_copy_text(&p->crs, dfle_dem_crs_wkt(d)) != 0) {
        dfle_profile_free(p);
        return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory for a profile");
    }
    return DFLE_OK;
}

/* ---------------------------------------------------------------- */
/* Profiles                                                         */
/* ---------------------------------------------------------------- */

static int profile_from_path(const dfle_dem *d, const flowpath *pa, const dfle_slope_opts *o,
                             dfle_profile **out, dfle_error *err)
{
    dfle_profile *p = profile_alloc(pa->n);
    double L = pa->s[pa->n - 1];
    flowpath up = {0}, all = {0};
    int rc = p == NULL ? -1 : slopes_along(d, pa, o, &up, &all, p->f[DFLE_PROFILE_S]);

    path_free(&up);
    path_free(&all);
    if (rc != 0) {
        dfle_profile_free(p);
        return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory for a profile");
    }
    for (size_t i = 0; i < pa->n; i++) {
        dfle_dem_cell_centre(d, pa->c[i], &p->f[DFLE_PROFILE_E][i], &p->f[DFLE_PROFILE_N][i]);
        p->f[DFLE_PROFILE_X][i] = pa->s[i];
        p->f[DFLE_PROFILE_D][i] = L - pa->s[i];
        p->f[DFLE_PROFILE_Z][i] = pa->z[i];
        p->f[DFLE_PROFILE_A][i] = dfle_dem_area(d)[pa->c[i]];
        p->receiver[i] = i + 1 < pa->n ? i + 2 : 0;
    }
    p->slope = *o;
    *out = p;
    return DFLE_OK;
}

int dfle_dem_profile(dfle_dem *d, const dfle_profile_opts *opts, dfle_profile **out,
                     dfle_error *err)
{
    dfle_profile_opts o = *opts;
    flowpath pa = {0};
    size_t start;
    int st;

    *out = NULL;
    if ((st = check_slope_opts(d, &o.slope, err)) != DFLE_OK)
        return st;
    if (!(isfinite(o.A_min) && o.A_min >= 0 && isfinite(o.A_max) && o.A_max >= 0))
        return dfle_error_set(err, DFLE_EINVAL, "dem: A_min and A_max must be >= 0 m^2 "
                              "(got %g, %g)", o.A_min, o.A_max);
    if (!isfinite(o.radius))
        return dfle_error_set(err, DFLE_EINVAL, "dem: radius must be finite");
    if ((st = ready(d, o.from_head ? "a profile from a channel head" :
                                     "a profile from an outlet", err)) != DFLE_OK)
        return st;
    if (o.from_head) {
        if ((st = dfle_dem_cell_at(d, o.E, o.N, "head", &start, err)) != DFLE_OK)
            return st;
        if (isnan(d->z[start]))
            return dfle_error_set(err, DFLE_EINVAL, "dem: head (%.10g E, %.10g N) is on a "
                                  "NoData cell", o.E, o.N);
        /* Down the receivers; stop at the first cell reaching A_max. */
        for (size_t c = start;;) {
            long long r = dfle_dem_receiver(d, c);
            if (path_push(&pa, c, pa.n ? pa.s[pa.n - 1] + step_length(d, pa.c[pa.n - 1]) : 0.0,
                          d->z[c]) != 0)
                goto nomem;
            if (r < 0 || (o.A_max > 0 && dfle_dem_area(d)[c] >= o.A_max))
                break;
            c = (size_t)r;
        }
    } else {
        flowpath rev = {0};
        if ((st = snap_outlet(d, o.E, o.N, o.radius, &start, err)) != DFLE_OK)
            return st;
        /* Up the largest donors, then reverse into head-first order. */
        for (long long c = (long long)start; c >= 0;) {
            long long up = main_donor(d, (size_t)c);
            if (path_push(&rev, (size_t)c, 0.0, d->z[c]) != 0) {
                path_free(&rev);
                goto nomem;
            }
            c = up >= 0 && dfle_dem_area(d)[up] >= o.A_min ? up : -1;
        }
        for (size_t j = rev.n; j > 0; j--) {
            size_t c = rev.c[j - 1];
            if (path_push(&pa, c, pa.n ? pa.s[pa.n - 1] + step_length(d, pa.c[pa.n - 1]) : 0.0,
                          d->z[c]) != 0) {
                path_free(&rev);
                goto nomem;
            }
        }
        path_free(&rev);
    }
    if (pa.n < 2) {
        double e, n;
        dfle_dem_cell_centre(d, start, &e, &n);
        path_free(&pa);
        return dfle_error_set(err, DFLE_EINVAL,
                              "dem: the profile from (%.10g E, %.10g N) has a single cell "
                              "(%.10g E, %.10g N, A = %g m^2): %s", o.E, o.N, e, n,
                              dfle_dem_area(d)[start],
                              !o.from_head ? "nothing drains into it (or A_min is too large)"
                              : o.A_max > 0 && dfle_dem_area(d)[start] >= o.A_max
                                  ? "its own area already reaches A_max"
                                  : "it drains off the grid at once");
    }
    st = profile_from_path(d, &pa, &o.slope, out, err);
    if (st == DFLE_OK) {
        (*out)->given[0] = o.E;
        (*out)->given[1] = o.N;
        dfle_dem_cell_centre(d, start, &(*out)->snapped[0], &(*out)->snapped[1]);
        (*out)->from_head = o.from_head;
        (*out)->A_min = o.from_head ? 0 : o.A_min;
        (*out)->A_max = o.from_head ? o.A_max : 0;
        (*out)->radius = o.from_head ? -1 : snap_radius(d, o.radius);
        st = keep_dem_path(*out, d, err);
    }
    path_free(&pa);
    return st;
nomem:
    path_free(&pa);
    return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory for a profile");
}

/* ---------------------------------------------------------------- */
/* Networks                                                         */
/* ---------------------------------------------------------------- */

int dfle_dem_network(dfle_dem *d, const dfle_network_opts *opts, dfle_profile **out,
                     dfle_error *err)
{
    dfle_network_opts o = *opts;
    unsigned char *keep = NULL;
    uint32_t *slot = NULL; /* cell -> 1-based network index, 0 = out */
    const uint32_t *order;
    size_t outlet = 0, count = 0, n_order;
    dfle_profile *p = NULL;
    flowpath core = {0}, up = {0}, all = {0}; /* slope windows, reused */
    int st;

    *out = NULL;
    if ((st = check_slope_opts(d, &o.slope, err)) != DFLE_OK)
        return st;
    if (!(isfinite(o.A_min) && o.A_min > 0))
        return dfle_error_set(err, DFLE_EINVAL, "dem: network A_min must be > 0 m^2 (got %g)",
                              o.A_min);
    if (!isfinite(o.radius))
        return dfle_error_set(err, DFLE_EINVAL, "dem: radius must be finite");
    if ((st = ready(d, "a channel network", err)) != DFLE_OK)
        return st;
    order = dfle_dem_order(d, &n_order);
    if (o.has_outlet && (st = snap_outlet(d, o.E, o.N, o.radius, &outlet, err)) != DFLE_OK)
        return st;
    if ((keep = calloc(d->n, 1)) == NULL || (slot = calloc(d->n, sizeof *slot)) == NULL)
        goto nomem;
    /* Receivers come after donors in `order`, so walking it backwards
     * marks a catchment from its outlet up. */
    if (o.has_outlet) {
        keep[outlet] = 1;
        for (size_t j = n_order; j > 0; j--) {
            size_t c = order[j - 1];
            long long r = dfle_dem_receiver(d, c);
            if (r >= 0 && keep[r])
                keep[c] = 1;
        }
    }
    for (size_t j = 0; j < n_order; j++) {
        size_t c = order[j];
        if ((!o.has_outlet || keep[c]) && dfle_dem_area(d)[c] >= o.A_min)
            slot[c] = (uint32_t)++count;
    }
    if (count < 2) {
        st = dfle_error_set(err, DFLE_EINVAL, "dem: the network has %zu cell%s with A >= A_min "
                            "= %g m^2; lower A_min", count, count == 1 ? "" : "s", o.A_min);
        goto done;
    }
    if ((p = profile_alloc(count)) == NULL)
        goto nomem;
    p->network = 1;
    p->slope = o.slope;
    for (size_t j = 0, i = 0; j < n_order; j++) {
        size_t c = order[j];
        long long r;
        if (slot[c] == 0)
            continue;
        r = dfle_dem_receiver(d, c);
        dfle_dem_cell_centre(d, c, &p->f[DFLE_PROFILE_E][i], &p->f[DFLE_PROFILE_N][i]);
        p->f[DFLE_PROFILE_Z][i] = d->z[c];
        p->f[DFLE_PROFILE_A][i] = dfle_dem_area(d)[c];
        p->receiver[i] = r >= 0 ? slot[r] : 0;
        /* Each cell's own path: main donors upstream, receivers down. */
        core.n = 0;
        if (path_push(&core, c, 0.0, d->z[c]) != 0 ||
            slopes_along(d, &core, &p->slope, &up, &all, &p->f[DFLE_PROFILE_S][i]) != 0)
            goto nomem;
        i++;
    }
    /* Distance to the outlet: receivers first (backwards). */
    for (size_t i = count; i > 0; i--) {
        size_t k = i - 1, r = p->receiver[k];
        double step = 0.0;
        if (r != 0) {
            double dE = p->f[DFLE_PROFILE_E][r - 1] - p->f[DFLE_PROFILE_E][k];
            double dN = p->f[DFLE_PROFILE_N][r - 1] - p->f[DFLE_PROFILE_N][k];
            step = sqrt(dE * dE + dN * dN);
        }
        p->f[DFLE_PROFILE_D][k] = r != 0 ? p->f[DFLE_PROFILE_D][r - 1] + step : 0.0;
        p->f[DFLE_PROFILE_X][k] = p->f[DFLE_PROFILE_D][k];
    }
    if (o.has_outlet) {
        p->given[0] = o.E;
        p->given[1] = o.N;
        dfle_dem_cell_centre(d, outlet, &p->snapped[0], &p->snapped[1]);
    } else {
        p->given[0] = p->given[1] = p->snapped[0] = p->snapped[1] = NAN;
    }
    p->A_min = o.A_min;
    p->radius = o.has_outlet ? snap_radius(d, o.radius) : -1;
    if ((st = keep_dem_path(p, d, err)) != DFLE_OK)
        goto done;
    *out = p;
    p = NULL;
    st = DFLE_OK;
    goto done;
nomem:
    st = dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory for a channel network");
done:
    dfle_profile_free(p);
    free(keep);
    free(slot);
    path_free(&core);
    path_free(&up);
    path_free(&all);
    return st;
}

/* ---------------------------------------------------------------- */
/* Access, CSV, model channel                                       */
/* ---------------------------------------------------------------- */

size_t dfle_profile_size(const dfle_profile *p) { return p->n; }
int dfle_profile_is_network(const dfle_profile *p) { return p->network; }
const size_t *dfle_profile_receiver(const dfle_profile *p) { return p->receiver; }
dfle_slope_opts dfle_profile_slope(const dfle_profile *p) { return p->slope; }

const double *dfle_profile_field(const dfle_profile *p, enum dfle_profile_field f)
{
    return (int)f >= 0 && f < DFLE_PROFILE_NFIELDS ? p->f[f] : NULL;
}

void dfle_profile_point(const dfle_profile *p, double given[2], double snapped[2])
{
    given[0] = p->given[0];
    given[1] = p->given[1];
    snapped[0] = p->snapped[0];
    snapped[1] = p->snapped[1];
}

int dfle_profile_main_stem(const dfle_profile *p, dfle_profile **out, dfle_error *err)
{
    const double *A = p->f[DFLE_PROFILE_A];
    size_t *best = NULL, *path = NULL, outlet = 0, n = 0, c;
    dfle_profile *q = NULL;
    int have = 0;

    *out = NULL;
    /* best[c]: the donor of largest area of cell c, plus one (0: none). */
    best = calloc(p->n, sizeof *best);
    path = malloc(p->n * sizeof *path);
    if (best == NULL || path == NULL)
        goto nomem;
    for (size_t i = 0; i < p->n; i++) {
        size_t r = p->receiver[i];
        if (r == 0) {
            if (!have || A[i] > A[outlet])
                outlet = i;
            have = 1;
        } else if (best[r - 1] == 0 || A[i] > A[best[r - 1] - 1]) {
            best[r - 1] = i + 1;
        }
    }
    if (!have)
        return dfle_error_set(err, DFLE_EINVAL, "profile: no outlet (every cell drains to "
                              "another)");
    for (c = outlet;; c = best[c] - 1) {
        path[n++] = c;
        if (best[c] == 0 || n == p->n)
            break;
    }
    if (n < 2) {
        free(best);
        free(path);
        return dfle_error_set(err, DFLE_EINVAL, "profile: the main stem is a single cell");
    }
    if ((q = profile_alloc(n)) == NULL)
        goto nomem;
    for (size_t i = 0; i < n; i++) {
        size_t k = path[n - 1 - i]; /* head first */
        for (int f = 0; f < DFLE_PROFILE_NFIELDS; f++)
            q->f[f][i] = p->f[f][k];
        q->f[DFLE_PROFILE_D][i] = p->f[DFLE_PROFILE_D][k] - p->f[DFLE_PROFILE_D][outlet];
        q->receiver[i] = i + 1 < n ? i + 2 : 0;
    }
    for (size_t i = 0; i < n; i++)
        q->f[DFLE_PROFILE_X][i] = q->f[DFLE_PROFILE_D][0] - q->f[DFLE_PROFILE_D][i];
    memcpy(q->given, p->given, sizeof q->given);
    memcpy(q->snapped, p->snapped, sizeof q->snapped);
    q->slope = p->slope;
    q->A_min = p->A_min, q->A_max = p->A_max, q->radius = p->radius;
    /* provenance: the same DEM */
    if (profile_copy_text(&q->dem, p->dem) != 0 || profile_copy_text(&q->crs, p->crs) != 0) {
        dfle_profile_free(q);
        goto nomem;
    }
    free(best);
    free(path);
    *out = q;
    return DFLE_OK;
nomem:
    free(best);
    free(path);
    return dfle_error_set(err, DFLE_ENOMEM, "profile: out of memory for a main stem");
}

int dfle_profile_channel(const dfle_profile *p, double dx, double k_w, double b,
                         dfle_channel **out, dfle_error *err)
{
    const double *x = p->f[DFLE_PROFILE_X], *A = p->f[DFLE_PROFILE_A];
    double L, *nA, *nw;
    size_t n;
    int st;

    *out = NULL;
    if (p->network)
        return dfle_error_set(err, DFLE_EINVAL, "profile: a channel network has no single "
                              "A(x); take a profile (dem:profile) for a model channel");
    if (!(isfinite(dx) && dx > 0))
        return dfle_error_set(err, DFLE_EINVAL, "profile: dx must be > 0 m (got %g)", dx);
    if (!(isfinite(k_w) && k_w > 0 && isfinite(b)))
        return dfle_error_set(err, DFLE_EINVAL, "profile: k_w must be > 0 and b finite "
                              "(got %g, %g)", k_w, b);
    L = x[p->n - 1];
    if (L / dx > 1e8)
        return dfle_error_set(err, DFLE_EINVAL, "profile: dx = %g m gives more than 1e8 nodes "
                              "over %g m", dx, L);
    n = (size_t)floor(L / dx + 1e-9) + 1;
    if (n < 3)
        return dfle_error_set(err, DFLE_EINVAL, "profile: the profile is %g m long, less than "
                              "2 dx = %g m; use a smaller dx", L, 2 * dx);
    nA = malloc(n * sizeof *nA);
    nw = malloc(n * sizeof *nw);
    if (nA == NULL || nw == NULL) {
        free(nA);
        free(nw);
        return dfle_error_set(err, DFLE_ENOMEM, "profile: out of memory");
    }
    /* Piecewise-linear A(x) between cell centres: non-decreasing as
     * the profile's areas are. */
    for (size_t i = 0, j = 0; i < n; i++) {
        double xi = (double)i * dx;
        while (j + 2 < p->n && x[j + 1] <= xi)
            j++;
        {
            double t = (xi - x[j]) / (x[j + 1] - x[j]);
            if (t > 1)
                t = 1;
            nA[i] = A[j] + t * (A[j + 1] - A[j]);
        }
        nw[i] = k_w * pow(nA[i], b);
    }
    st = dfle_channel_new_from_arrays(n, dx, nA, nw, out, err);
    free(nA);
    free(nw);
    return st;
}
