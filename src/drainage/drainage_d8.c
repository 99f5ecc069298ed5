/*
 * drainage_d8.c - single-flow directions by steepest descent (D8,
 * O'Callaghan and Mark 1984), and where a cell with no lower neighbour
 * goes: off the grid or nowhere (a sink, for drainage_flats.c and the
 * depression handling to resolve).
 *
 * The slope to neighbour k is (z_i - z_k) / len[k], computed in exactly
 * that form: the DEM's direction codes are part of its interface, and
 * a tie between two slopes must break as it always has (the first in
 * the order E, SE, S, SW, W, NW, N, NE, by a strict >).  This is the
 * hottest loop of a landscape model's routing, so cells off the outer
 * ring take a path without bounds checks.
 */
#include "drainage/drainage_internal.h"

#include <math.h>

/* What a pass finds besides the directions. */
typedef struct d8_tally {
    size_t sinks, nodata;
    int infinite;
} d8_tally;

/* The neighbour to drain to: k_best (slope best), or the last routing's
 * direction k_prev (dir[i] before this pass) when it is still within the
 * hysteresis margin; keep is 1 - margin, or 2 (never) when off. */
static inline int sticky(const double *zp, double best, int k_best, unsigned char k_prev,
                         const long long *step, const double *len, double keep)
{
    if (k_prev < 8 && (int)k_prev != k_best && k_best >= 0) {
        double s = (zp[0] - zp[step[k_prev]]) / len[k_prev];
        if (s > 0 && s >= keep * best)
            return k_prev;
    }
    return k_best;
}

/* Where a data cell with steepest neighbour k_best (-1: none lower)
 * goes; a sink is appended to stack[]. */
static void settle(dfle_drainage *dr, size_t i, int k_best, enum dfle_drainage_edge exit,
                   d8_tally *t)
{
    dr->rcv[i] = (uint32_t)i;
    if (exit == DFLE_DRAINAGE_BASE_LEVEL || (k_best < 0 && exit == DFLE_DRAINAGE_OPEN)) {
        dr->dir[i] = DIR_OUT;
    } else if (k_best >= 0) {
        dr->dir[i] = (unsigned char)k_best;
        dr->rcv[i] = (uint32_t)((long long)i + dr->step[k_best]);
    } else {
        dr->dir[i] = DIR_SINK;
        dr->stack[t->sinks++] = (uint32_t)i;
    }
}

/* A cell with no elevation: outside, its own receiver. */
static int nodata(dfle_drainage *dr, double zi, size_t i, d8_tally *t)
{
    if (!isnan(zi)) {
        t->infinite |= isinf(zi);
        return 0;
    }
    dr->rcv[i] = (uint32_t)i;
    dr->dir[i] = DIR_NODATA;
    t->nodata++;
    return 1;
}

/* A cell on the outer ring: neighbours checked against the grid. */
static void ring_cell(dfle_drainage *dr, const double *z, size_t r, size_t c, double keep,
                      d8_tally *t)
{
    size_t i = r * dr->o.nx + c;
    double zi = z[i], best = 0.0;
    int k_best = -1, nodata_nb = 0;
    unsigned char k_prev = dr->dir[i];
    if (nodata(dr, zi, i, t))
        return;
    for (int k = 0; k < 8; k++) {
        long long nb = drainage_nb(dr, r, c, k);
        double s;
        if (nb < 0)
            continue;
        s = (zi - z[nb]) / dr->len[k]; /* NaN for NoData: never > best */
        if (s > best) {
            best = s;
            k_best = k;
        }
        nodata_nb |= isnan(z[nb]);
    }
    /* The last direction on the ring points to a cell on the grid. */
    if (keep <= 1.0 && k_prev < 8 && drainage_nb(dr, r, c, k_prev) >= 0)
        k_best = sticky(z + i, best, k_best, k_prev, dr->step, dr->len, keep);
    settle(dr, i, k_best, drainage_exit_known(dr, i, nodata_nb), t);
}

size_t drainage_d8(dfle_drainage *dr, const double *z, size_t *n_data, int *infinite)
{
    size_t nx = dr->o.nx, ny = dr->o.ny;
    d8_tally t = {0, 0, 0};
    const unsigned char *outlet = dr->outlet;
    long long step[8];
    double len[8];
    /* The last routing's directions are in dir[] only after a routing of
     * this grid that succeeded. */
    const double keep = dr->dirs_kept && dr->hysteresis > 0 ? 1.0 - dr->hysteresis : 2.0;

    for (int k = 0; k < 8; k++) {
        step[k] = dr->step[k];
        len[k] = dr->len[k];
    }
    for (size_t r = 0; r < ny; r++) {
        if (r == 0 || r + 1 == ny || nx < 3) {
            for (size_t c = 0; c < nx; c++)
                ring_cell(dr, z, r, c, keep, &t);
            continue;
        }
        ring_cell(dr, z, r, 0, keep, &t);
        for (size_t i = r * nx + 1, end = r * nx + nx - 1; i < end; i++) {
            const double *zp = z + i;
            double zi = *zp, best = 0.0;
            int k_best = -1, nodata_nb = 0;
            if (nodata(dr, zi, i, &t))
                continue;
            /* Random terrain makes every comparison a coin toss, so the
             * choice is written to compile to conditional moves. */
            for (int k = 0; k < 8; k++) {
                double zn = zp[step[k]], s = (zi - zn) / len[k];
                int better = s > best;
                k_best = better ? k : k_best;
                best = better ? s : best;
                nodata_nb |= isnan(zn);
            }
            if (keep <= 1.0)
                k_best = sticky(zp, best, k_best, dr->dir[i], step, len, keep);
            if (k_best >= 0 && !nodata_nb && (outlet == NULL || !outlet[i])) {
                /* the common case */
                dr->dir[i] = (unsigned char)k_best;
                dr->rcv[i] = (uint32_t)((long long)i + step[k_best]);
            } else {
                settle(dr, i, k_best, drainage_exit_known(dr, i, nodata_nb), &t);
            }
        }
        ring_cell(dr, z, r, nx - 1, keep, &t);
    }
    *n_data = nx * ny - t.nodata;
    *infinite = t.infinite;
    return t.sinks;
}
