/*
 * drainage_flats.c - directions across flats: Garbrecht and Martz
 * (1997), J. Hydrology 193, in the linear-time form of Barnes, Lehman
 * and Mulla (2014b), Computers & Geosciences 62.
 *
 * A flat's low edges are cells that drain and touch a sink of their
 * elevation; its high edges are sinks that touch higher ground.  Flats
 * are labelled by flooding equal elevations from their low edges (a
 * flat with none is a pit and stays a sink); then each flat cell gets
 *   mask = 2 * towards + (height - away),
 * with towards the breadth-first distance to the low edges, away the
 * distance to the high edges and height the flat's largest away, and
 * drains to the same-label neighbour of least mask.  That neighbour is
 * always lower than its own mask, because towards falls by 1 (2 in the
 * mask) at each step and away changes by at most 1.
 *
 * Only the cells around the sinks are looked at, so a grid with many
 * one-cell pits and no flat (a landscape model's random initial
 * surface) costs a pass over its pits, not over the grid.  Every result
 * is a function of the sets of edges and labels, never of the order in
 * which they are found, so the DEM's counts and codes do not depend on
 * how this file walks the grid.
 */
#include "drainage/drainage_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A low edge found but not yet labelled (labels are 1, 2, ...). */
#define SEED UINT32_MAX
/* Marks a low edge found, in the direction code of a draining cell
 * (0..8) while the sinks are scanned: no n-cell array to clear. */
#define FOUND 0x80

/* Breadth-first distance (1 at the seeds) over sinks of the same label;
 * q holds the seeds on entry and room for every sink of their flats. */
static void flat_bfs(const dfle_drainage *dr, const uint32_t *label, uint32_t *q, size_t n_seeds,
                     int32_t *dist)
{
    size_t head = 0, tail = n_seeds;
    for (size_t s = 0; s < n_seeds; s++)
        dist[q[s]] = 1;
    while (head < tail) {
        size_t c = q[head++], r = c / dr->o.nx, cc = c % dr->o.nx;
        for (int k = 0; k < 8; k++) {
            long long nb = drainage_nb(dr, r, cc, k);
            if (nb < 0 || label[nb] != label[c] || dr->dir[nb] != DIR_SINK || dist[nb] != 0)
                continue;
            dist[nb] = dist[c] + 1;
            q[tail++] = (uint32_t)nb;
        }
    }
}

static int32_t mask(const uint32_t *label, const int32_t *towards, const int32_t *away,
                    const int32_t *height, size_t i)
{
    return 2 * towards[i] + (away[i] > 0 ? height[label[i]] - away[i] : 0);
}

/* Flood equal elevations from each low edge; the labelled cells are
 * appended to `cells`.  Returns the number of labels. */
static uint32_t label_flats(const dfle_drainage *dr, const double *z, const uint32_t *low,
                            size_t n_low, uint32_t *label, uint32_t *cells, size_t *n_cells)
{
    uint32_t n_labels = 0;
    size_t tail = 0;
    for (size_t s = 0; s < n_low; s++) {
        size_t head = tail;
        if (label[low[s]] != SEED) /* reached by an earlier flood */
            continue;
        label[low[s]] = ++n_labels;
        cells[tail++] = low[s];
        while (head < tail) {
            size_t c = cells[head++], r = c / dr->o.nx, cc = c % dr->o.nx;
            for (int k = 0; k < 8; k++) {
                long long nb = drainage_nb(dr, r, cc, k);
                if (nb < 0 || isnan(z[nb]) || (label[nb] != 0 && label[nb] != SEED) ||
                    z[nb] != z[c])
                    continue;
                label[nb] = n_labels;
                cells[tail++] = (uint32_t)nb;
            }
        }
    }
    *n_cells = tail;
    return n_labels;
}

int drainage_flats(dfle_drainage *dr, const double *z, size_t n_sinks, dfle_error *err)
{
    /* Borrowed until the donors and the stack are built: the sinks come
     * in stack[]; low edges go to don[], high edges to don_off[] (each
     * a set of distinct cells, so n fits), the labelled cells to
     * stack[] once the sinks have been read. */
    const uint32_t *sinks = dr->stack;
    uint32_t *low = dr->don, *high = dr->don_off, *cells = dr->stack, *label, n_labels;
    int32_t *away, *towards;
    size_t n_low = 0, n_high = 0, n_kept = 0, n_cells = 0;

    dr->counts.flats = 0;
    for (size_t s = 0; s < n_sinks; s++) {
        size_t c = sinks[s], r = c / dr->o.nx, cc = c % dr->o.nx;
        int is_high = 0;
        for (int k = 0; k < 8; k++) {
            long long nb = drainage_nb(dr, r, cc, k);
            if (nb < 0 || isnan(z[nb]))
                continue;
            if (z[nb] > z[c]) {
                is_high = 1;
            } else if (z[nb] == z[c] && dr->dir[nb] != DIR_SINK && !(dr->dir[nb] & FOUND)) {
                dr->dir[nb] |= FOUND;
                low[n_low++] = (uint32_t)nb;
            }
        }
        if (is_high)
            high[n_high++] = (uint32_t)c;
    }
    for (size_t s = 0; s < n_low; s++)
        dr->dir[low[s]] &= (unsigned char)~FOUND;
    if (n_low == 0) /* no flat drains: nothing to do */
        return DFLE_OK;
    /* Only now: a grid of one-cell pits (a landscape model's random
     * surface) never needs the labels and distances. */
    label = drainage_work(dr, 0);
    away = (int32_t *)drainage_work(dr, 1);
    towards = (int32_t *)drainage_work(dr, 2);
    if (label == NULL || away == NULL || towards == NULL)
        goto nomem;
    memset(label, 0, dr->n * sizeof *label);
    for (size_t s = 0; s < n_low; s++)
        label[low[s]] = SEED;

    n_labels = label_flats(dr, z, low, n_low, label, cells, &n_cells);
    if (n_labels + 1 > dr->height_cap) {
        int32_t *h = realloc(dr->height, ((size_t)n_labels + 1) * sizeof *h);
        if (h == NULL)
            goto nomem;
        dr->height = h;
        dr->height_cap = (size_t)n_labels + 1;
    }
    memset(dr->height, 0, ((size_t)n_labels + 1) * sizeof *dr->height);
    for (size_t j = 0; j < n_cells; j++)
        away[cells[j]] = towards[cells[j]] = 0;
    for (size_t s = 0; s < n_high; s++) /* high edges of pits sit out */
        if (label[high[s]] != 0)
            high[n_kept++] = high[s];
    flat_bfs(dr, label, high, n_kept, away);
    for (size_t j = 0; j < n_cells; j++) {
        uint32_t c = cells[j];
        if (away[c] > dr->height[label[c]])
            dr->height[label[c]] = away[c];
    }
    flat_bfs(dr, label, low, n_low, towards);

    for (size_t j = 0; j < n_cells; j++) {
        size_t i = cells[j], r = i / dr->o.nx, c = i % dr->o.nx;
        int32_t mine, best;
        long long to = -1;
        int dir = -1;
        if (dr->dir[i] != DIR_SINK)
            continue;
        mine = best = mask(label, towards, away, dr->height, i);
        for (int k = 0; k < 8; k++) {
            long long nb = drainage_nb(dr, r, c, k);
            int32_t m;
            if (nb < 0 || label[nb] != label[i])
                continue;
            m = mask(label, towards, away, dr->height, (size_t)nb);
            if (m < best) {
                best = m;
                dir = k;
                to = nb;
            }
        }
        if (dir >= 0 && best < mine) {
            dr->dir[i] = (unsigned char)dir;
            dr->rcv[i] = (uint32_t)to;
            dr->counts.flats++;
        }
    }
    return DFLE_OK;
nomem:
    return dfle_error_set(err, DFLE_ENOMEM, "drainage: out of memory resolving flats");
}
