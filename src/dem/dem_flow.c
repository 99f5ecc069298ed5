/*
 * dem_flow.c - hydrologic conditioning and routing on a DEM:
 * priority-flood depression filling, D8 flow directions, resolution of
 * flats, and drainage area in topological order.
 *
 * Written from the published descriptions (doc/dem.md has the
 * references and the reasons for each choice):
 *  - Barnes, Lehman and Mulla (2014a), Priority-Flood, Computers &
 *    Geosciences 62: fill from the boundary inwards in order of
 *    elevation; cells found lower than the cell that reached them are in
 *    a depression and are raised to it (a plain FIFO suffices for them).
 *  - Garbrecht and Martz (1997), J. Hydrology 193, as made linear-time
 *    by Barnes, Lehman and Mulla (2014b), Computers & Geosciences 62:
 *    on a flat, flow goes towards lower terrain (distance to the flat's
 *    outlets, counted double) and away from higher terrain.
 * Every loop is iterative (heaps and queues), so a large DEM cannot
 * overflow the stack.
 */
#include "dem/dem_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NOFLOW DFLE_DEM_DIR_SINK

static int is_data(const dfle_dem *d, long long i)
{
    return i >= 0 && !isnan(d->z[i]);
}

/* A data cell on the grid's edge or next to NoData: water may leave the
 * grid there, so it seeds the flood and may be an outlet. */
static int is_boundary(const dfle_dem *d, size_t i)
{
    size_t r = i / d->nx, c = i % d->nx;
    if (r == 0 || c == 0 || r + 1 == d->ny || c + 1 == d->nx)
        return 1;
    for (int k = 0; k < 8; k++)
        if (!is_data(d, dfle_dem_nb(d, r, c, k)))
            return 1;
    return 0;
}

void dfle_dem_unroute(dfle_dem *d)
{
    free(d->dir);
    free(d->area);
    free(d->order);
    d->dir = NULL;
    d->area = NULL;
    d->order = NULL;
    d->n_order = d->n_sinks = d->n_flat = 0;
    d->routed = 0;
}

/* ---------------------------------------------------------------- */
/* Priority-flood                                                   */
/* ---------------------------------------------------------------- */

/* Binary min-heap on (z, index): the index breaks ties so the order of
 * visits, and hence the statistics, never depend on the platform. */
typedef struct { double z; uint32_t i; } heap_item;
typedef struct { heap_item *a; size_t n, cap; } heap;

static int item_less(heap_item x, heap_item y)
{
    return x.z < y.z || (x.z == y.z && x.i < y.i);
}

static int heap_push(heap *h, double z, uint32_t i)
{
    size_t k;
    if (h->n == h->cap) {
        size_t cap = h->cap ? 2 * h->cap : 1024;
        heap_item *a = realloc(h->a, cap * sizeof *a);
        if (a == NULL)
            return -1;
        h->a = a;
        h->cap = cap;
    }
    k = h->n++;
    h->a[k] = (heap_item){z, i};
    while (k > 0 && item_less(h->a[k], h->a[(k - 1) / 2])) {
        heap_item t = h->a[k];
        h->a[k] = h->a[(k - 1) / 2];
        h->a[(k - 1) / 2] = t;
        k = (k - 1) / 2;
    }
    return 0;
}

static heap_item heap_pop(heap *h)
{
    heap_item top = h->a[0];
    size_t k = 0;
    h->a[0] = h->a[--h->n];
    for (;;) {
        size_t l = 2 * k + 1, r = l + 1, m = k;
        if (l < h->n && item_less(h->a[l], h->a[m]))
            m = l;
        if (r < h->n && item_less(h->a[r], h->a[m]))
            m = r;
        if (m == k)
            break;
        heap_item t = h->a[k];
        h->a[k] = h->a[m];
        h->a[m] = t;
        k = m;
    }
    return top;
}

int dfle_dem_fill(dfle_dem *d, dfle_dem_fill_stats *stats, dfle_error *err)
{
    dfle_dem_fill_stats st = {0, 0.0, 0.0};
    unsigned char *closed = calloc(d->n, 1);
    uint32_t *pit = malloc(d->n * sizeof *pit); /* each cell enters once */
    size_t pit_head = 0, pit_tail = 0;
    heap h = {NULL, 0, 0};
    int rc = DFLE_OK;

    if (closed == NULL || pit == NULL) {
        rc = dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory filling %zu cells", d->n);
        goto done;
    }
    for (size_t i = 0; i < d->n; i++) {
        if (isnan(d->z[i])) {
            closed[i] = 1;
        } else if (is_boundary(d, i)) {
            closed[i] = 1;
            if (heap_push(&h, d->z[i], (uint32_t)i) != 0)
                goto nomem;
        }
    }
    while (pit_head < pit_tail || h.n > 0) {
        /* A cell in the FIFO lies at the current spill level, which is
         * below everything in the heap, so it goes first. */
        size_t c = pit_head < pit_tail ? pit[pit_head++] : heap_pop(&h).i;
        size_t r = c / d->nx, cc = c % d->nx;
        for (int k = 0; k < 8; k++) {
            long long nb = dfle_dem_nb(d, r, cc, k);
            if (nb < 0 || closed[nb])
                continue;
            closed[nb] = 1;
            if (d->z[nb] <= d->z[c]) {
                double rise = d->z[c] - d->z[nb];
                if (rise > 0) {
                    st.raised++;
                    st.volume += rise;
                    if (rise > st.max_raise)
                        st.max_raise = rise;
                    d->z[nb] = d->z[c];
                }
                pit[pit_tail++] = (uint32_t)nb;
            } else if (heap_push(&h, d->z[nb], (uint32_t)nb) != 0) {
                goto nomem;
            }
        }
    }
    st.volume *= d->dx * d->dy;
    d->filled = 1;
    if (st.raised > 0)
        dfle_dem_unroute(d); /* directions and areas were for the old z */
    if (stats != NULL)
        *stats = st;
    goto done;
nomem:
    rc = dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory filling %zu cells", d->n);
done:
    free(closed);
    free(pit);
    free(h.a);
    return rc;
}

int dfle_dem_is_filled(const dfle_dem *d) { return d->filled; }

/* ---------------------------------------------------------------- */
/* D8 and flats                                                     */
/* ---------------------------------------------------------------- */

/* Steepest descent among lower neighbours; the first of equal slopes in
 * neighbour order wins (strict >).  No lower neighbour: a boundary cell
 * drains off the grid, an interior one is NOFLOW for now. */
static void d8(dfle_dem *d)
{
    double dist[8];
    for (int k = 0; k < 8; k++)
        dist[k] = dfle_dem_nb_dist(d, k);
    for (size_t i = 0; i < d->n; i++) {
        size_t r = i / d->nx, c = i % d->nx;
        double best = 0.0;
        int dir = -1;
        if (isnan(d->z[i])) {
            d->dir[i] = DFLE_DEM_DIR_NODATA;
            continue;
        }
        for (int k = 0; k < 8; k++) {
            long long nb = dfle_dem_nb(d, r, c, k);
            double s;
            if (!is_data(d, nb))
                continue;
            s = (d->z[i] - d->z[nb]) / dist[k];
            if (s > best) {
                best = s;
                dir = k;
            }
        }
        d->dir[i] = dir >= 0 ? (unsigned char)dir
                             : is_boundary(d, i) ? DFLE_DEM_DIR_OUT : NOFLOW;
    }
}

/* Breadth-first distance (1 at the seeds) over NOFLOW cells of the same
 * flat label; `q` holds the seeds on entry (n_seeds of them). */
static void flat_bfs(const dfle_dem *d, const uint32_t *label, uint32_t *q, size_t n_seeds,
                     int32_t *dist)
{
    size_t head = 0, tail = n_seeds;
    for (size_t s = 0; s < n_seeds; s++)
        dist[q[s]] = 1;
    while (head < tail) {
        size_t c = q[head++];
        size_t r = c / d->nx, cc = c % d->nx;
        for (int k = 0; k < 8; k++) {
            long long nb = dfle_dem_nb(d, r, cc, k);
            if (nb < 0 || label[nb] != label[c] || d->dir[nb] != NOFLOW || dist[nb] != 0)
                continue;
            dist[nb] = dist[c] + 1;
            q[tail++] = (uint32_t)nb;
        }
    }
}

/* Barnes et al. (2014b): low edges are cells that drain and touch a
 * NOFLOW cell of their elevation; high edges are NOFLOW cells that touch
 * higher ground.  Flats are labelled from their low edges (a flat with
 * none is a pit and stays NOFLOW); then each flat cell gets
 *   mask = 2 * towards + (height - away),
 * where towards is the distance to the low edges, away the distance to
 * the high edges and height the flat's largest away; a flat cell drains
 * to the same-label neighbour of least mask, which is always lower than
 * its own because towards falls by 1 (2 in mask) at each step and away
 * changes by at most 1. */
static int resolve_flats(dfle_dem *d)
{
    uint32_t *label = NULL, *low = NULL, *high = NULL, *q = NULL, nlabels = 0;
    int32_t *away = NULL, *towards = NULL, *height = NULL;
    size_t n_low = 0, n_high = 0, n_high_kept = 0;
    int rc = -1;

    if ((label = calloc(d->n, sizeof *label)) == NULL || (low = malloc(d->n * sizeof *low)) == NULL ||
        (high = malloc(d->n * sizeof *high)) == NULL)
        goto done;
    for (size_t i = 0; i < d->n; i++) {
        size_t r = i / d->nx, c = i % d->nx;
        if (d->dir[i] == DFLE_DEM_DIR_NODATA)
            continue;
        for (int k = 0; k < 8; k++) {
            long long nb = dfle_dem_nb(d, r, c, k);
            if (!is_data(d, nb))
                continue;
            if (d->dir[i] == NOFLOW && d->z[nb] > d->z[i]) {
                high[n_high++] = (uint32_t)i;
                break;
            }
            if (d->dir[i] != NOFLOW && d->dir[nb] == NOFLOW && d->z[nb] == d->z[i]) {
                low[n_low++] = (uint32_t)i;
                break;
            }
        }
    }
    if (n_low == 0) { /* no flat drains: nothing to do */
        rc = 0;
        goto done;
    }
    /* Label each drainable flat by flooding equal elevations from its
     * low edges (reusing `high`'s tail is not possible: use q). */
    if ((q = malloc(d->n * sizeof *q)) == NULL)
        goto done;
    for (size_t s = 0; s < n_low; s++) {
        size_t head = 0, tail = 0;
        if (label[low[s]] != 0)
            continue;
        label[low[s]] = ++nlabels;
        q[tail++] = low[s];
        while (head < tail) {
            size_t c = q[head++], r = c / d->nx, cc = c % d->nx;
            for (int k = 0; k < 8; k++) {
                long long nb = dfle_dem_nb(d, r, cc, k);
                if (!is_data(d, nb) || label[nb] != 0 || d->z[nb] != d->z[c])
                    continue;
                label[nb] = nlabels;
                q[tail++] = (uint32_t)nb;
            }
        }
    }
    if ((away = calloc(d->n, sizeof *away)) == NULL ||
        (towards = calloc(d->n, sizeof *towards)) == NULL ||
        (height = calloc((size_t)nlabels + 1, sizeof *height)) == NULL)
        goto done;
    for (size_t s = 0; s < n_high; s++) /* high edges of pits sit out */
        if (label[high[s]] != 0)
            q[n_high_kept++] = high[s];
    flat_bfs(d, label, q, n_high_kept, away);
    for (size_t i = 0; i < d->n; i++)
        if (label[i] != 0 && away[i] > height[label[i]])
            height[label[i]] = away[i];
    memcpy(q, low, n_low * sizeof *q);
    flat_bfs(d, label, q, n_low, towards);
    for (size_t i = 0; i < d->n; i++) {
        size_t r = i / d->nx, c = i % d->nx;
        int32_t mine, best;
        int dir = -1;
        if (d->dir[i] != NOFLOW || label[i] == 0)
            continue;
        mine = best = 2 * towards[i] + (away[i] > 0 ? height[label[i]] - away[i] : 0);
        for (int k = 0; k < 8; k++) {
            long long nb = dfle_dem_nb(d, r, c, k);
            int32_t m;
            if (nb < 0 || label[nb] != label[i])
                continue;
            m = 2 * towards[nb] + (away[nb] > 0 ? height[label[nb]] - away[nb] : 0);
            if (m < best) {
                best = m;
                dir = k;
            }
        }
        if (dir >= 0 && best < mine) {
            d->dir[i] = (unsigned char)dir;
            d->n_flat++;
        }
    }
    rc = 0;
done:
    free(label);
    free(low);
    free(high);
    free(q);
    free(away);
    free(towards);
    free(height);
    return rc;
}

/* ---------------------------------------------------------------- */
/* Drainage area                                                    */
/* ---------------------------------------------------------------- */

long long dfle_dem_receiver(const dfle_dem *d, size_t i)
{
    if (d->dir == NULL || i >= d->n || d->dir[i] >= 8)
        return -1;
    return dfle_dem_nb(d, i / d->nx, i % d->nx, d->dir[i]);
}

/* Kahn's algorithm: cells without donors first; a cell is released once
 * all its donors have passed their area on.  Counts are accumulated as
 * whole numbers (exact in a double) and scaled once, so the total area
 * is exactly cells x cell area. */
static int accumulate(dfle_dem *d, dfle_error *err)
{
    unsigned char *ndon = calloc(d->n, 1);
    size_t head = 0, tail = 0, n_data = d->n - d->n_nodata;
    double cell = d->dx * d->dy;

    if (ndon == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory routing %zu cells", d->n);
    for (size_t i = 0; i < d->n; i++) {
        long long r = dfle_dem_receiver(d, i);
        d->area[i] = isnan(d->z[i]) ? NAN : 1.0;
        if (r >= 0)
            ndon[r]++;
    }
    for (size_t i = 0; i < d->n; i++)
        if (!isnan(d->z[i]) && ndon[i] == 0)
            d->order[tail++] = (uint32_t)i;
    while (head < tail) {
        size_t c = d->order[head++];
        long long r = dfle_dem_receiver(d, c);
        if (r < 0)
            continue;
        d->area[r] += d->area[c];
        if (--ndon[r] == 0)
            d->order[tail++] = (uint32_t)r;
    }
    free(ndon);
    d->n_order = tail;
    if (tail != n_data) /* a cycle: cannot happen with the rules above */
        return dfle_error_set(err, DFLE_ENUMERIC, "dem: flow directions form a cycle "
                              "(%zu of %zu cells ordered); this is a bug in dfle", tail, n_data);
    for (size_t i = 0; i < d->n; i++)
        d->area[i] *= cell;
    return DFLE_OK;
}

int dfle_dem_route(dfle_dem *d, dfle_error *err)
{
    int st;
    if (d->routed)
        return DFLE_OK;
    if ((st = dfle_dem_check_metric(d, "flow routing (D8, drainage area)", err)) != DFLE_OK)
        return st;
    dfle_dem_unroute(d);
    d->dir = malloc(d->n);
    d->area = malloc(d->n * sizeof *d->area);
    d->order = malloc(d->n * sizeof *d->order);
    if (d->dir == NULL || d->area == NULL || d->order == NULL) {
        dfle_dem_unroute(d);
        return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory routing %zu cells", d->n);
    }
    d8(d);
    if (resolve_flats(d) != 0) {
        dfle_dem_unroute(d);
        return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory resolving flats");
    }
    for (size_t i = 0; i < d->n; i++)
        d->n_sinks += d->dir[i] == NOFLOW;
    if ((st = accumulate(d, err)) != DFLE_OK) {
        dfle_dem_unroute(d);
        return st;
    }
    d->routed = 1;
    return DFLE_OK;
}

int dfle_dem_is_routed(const dfle_dem *d) { return d->routed; }
const unsigned char *dfle_dem_dir(const dfle_dem *d) { return d->routed ? d->dir : NULL; }
const double *dfle_dem_area(const dfle_dem *d) { return d->routed ? d->area : NULL; }
size_t dfle_dem_sink_count(const dfle_dem *d) { return d->n_sinks; }
size_t dfle_dem_flat_count(const dfle_dem *d) { return d->n_flat; }

const uint32_t *dfle_dem_order(const dfle_dem *d, size_t *n_order)
{
    if (n_order != NULL)
        *n_order = d->routed ? d->n_order : 0;
    return d->routed ? d->order : NULL;
}
