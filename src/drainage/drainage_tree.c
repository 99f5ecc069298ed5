/*
 * drainage_tree.c - the flow tree once receivers are final: donors in
 * compressed rows, the stack, and drainage area.
 *
 * The stack puts every cell after its receiver, roots first (Braun and
 * Willett 2013), in one of three orders.  Kahn's (cells without donors
 * first, in index order; a cell once all its donors are out), read
 * backwards, is the default: its FIFO holds independent cells, so the
 * processor overlaps their memory accesses, and it is 2-3 times faster
 * to build on a large grid than a depth-first walk, whose every step
 * waits for the last.  It is also the order the DEM has always listed
 * (dfle_dem_order, a network's rows).  Chains (each cell without
 * donors in index order, then down its receivers as far as it completes
 * them) builds as fast and keeps each step beside the last, so a sweep
 * in that order (the landscape model's, every time step) reads the grid
 * through the cache rather than all over it: on 2000^2 cells the
 * implicit erosion sweep took a third less time than in Kahn's order.
 * Braun and Willett's depth-first order, which keeps each tree
 * contiguous, is there for work done tree by tree.  Area does not
 * depend on the order.  Every loop is a plain
 * pass, a FIFO or a walk along receivers, so no tree is too deep for
 * the C stack.
 */
#include "drainage/drainage_internal.h"

#include <math.h>
#include <string.h>

void drainage_donors(dfle_drainage *dr)
{
    uint32_t *off = dr->don_off;
    size_t n = dr->n;

    memset(off, 0, (n + 1) * sizeof *off);
    for (size_t i = 0; i < n; i++)
        if (dr->rcv[i] != i)
            off[dr->rcv[i]]++;
    for (size_t i = 1; i < n; i++)
        off[i] += off[i - 1];
    off[n] = off[n - 1];
    /* off[r] is now the end of r's donors and serves as its cursor,
     * filled backwards: it ends at r's start, and each list ascends. */
    for (size_t i = n; i-- > 0;)
        if (dr->rcv[i] != i)
            dr->don[--off[dr->rcv[i]]] = (uint32_t)i;
}

/* What the orders from the leaves start with: donors left per cell
 * (at most 8), area 1 cell (NaN on NoData) and the counts of outlets
 * and sinks; with a FIFO (s[-t], t = 0 ..), the leaves go into it.
 * Returns how many went in. */
static size_t from_leaves(dfle_drainage *dr, unsigned char *left, uint32_t *s)
{
    double *area = dr->area;
    size_t tail = 0, outlets = 0, sinks = 0;
    for (size_t i = 0; i < dr->n; i++) {
        int data = dr->dir[i] != DIR_NODATA;
        outlets += dr->dir[i] == DIR_OUT;
        sinks += dr->dir[i] == DIR_SINK;
        left[i] = (unsigned char)(dr->don_off[i + 1] - dr->don_off[i]);
        area[i] = data ? 1.0 : NAN;
        if (s != NULL && left[i] == 0 && data)
            *(s - tail++) = (uint32_t)i;
    }
    dr->counts.outlets = outlets;
    dr->counts.sinks = sinks;
    return tail;
}

/* Kahn's algorithm, written from the end of the stack so that it reads
 * roots first with no reversal; the FIFO is the stack itself.  A cell
 * enters the FIFO once all its donors have left it, so its area in
 * whole cells is complete when it leaves: area is summed on the way,
 * with no second pass down the stack (the sums are of whole numbers,
 * exact in a double in any order, as stack_area's).  The FIFO visits
 * the grid in no spatial order, so the receivers of coming cells are
 * fetched ahead (two stages: the receiver's data needs the receiver). */
static size_t kahn(dfle_drainage *dr, size_t n_data, unsigned char *left)
{
    uint32_t *s = dr->stack + n_data - 1; /* s[-t]: the t-th cell out */
    const uint32_t *rcv = dr->rcv;
    double *area = dr->area, cell = dr->o.dx * dr->o.dy;
    size_t head = 0, tail = from_leaves(dr, left, s);
    while (head < tail) {
        uint32_t c = *(s - head++), r = rcv[c];
        double cells = area[c];
        if (head + 2 * DRAINAGE_AHEAD < tail) {
            DRAINAGE_PREFETCH(&rcv[*(s - head - 2 * DRAINAGE_AHEAD)]);
            r = rcv[*(s - head - DRAINAGE_AHEAD)];
            DRAINAGE_PREFETCH(&area[r]);
            DRAINAGE_PREFETCH(&left[r]);
            r = rcv[c];
        }
        area[c] = cells * cell;
        if (r != c) {
            area[r] += cells;
            if (--left[r] == 0)
                *(s - tail++) = r;
        }
    }
    return tail;
}

/* Cells without donors in index order, each followed down its receivers
 * by every cell it is the last donor of (then complete, as in Kahn's
 * order, so area is summed on the way); the stack is written from its
 * end.  Each step reads the cell just done or a neighbour of it, where
 * Kahn's FIFO reads cells anywhere on the grid: faster on grids larger
 * than the cache, and so is a sweep in this order. */
static size_t chains(dfle_drainage *dr, size_t n_data, unsigned char *left)
{
    uint32_t *s = dr->stack + n_data - 1; /* s[-t]: the t-th cell out */
    const uint32_t *rcv = dr->rcv, *off = dr->don_off;
    double *area = dr->area, cell = dr->o.dx * dr->o.dy;
    size_t t = 0;
    from_leaves(dr, left, NULL);
    for (size_t i = 0; i < dr->n; i++) {
        uint32_t c = (uint32_t)i;
        if (off[i + 1] != off[i] || dr->dir[i] == DIR_NODATA)
            continue;
        for (;;) {
            uint32_t r = rcv[c];
            double cells = area[c];
            *(s - t++) = c;
            area[c] = cells * cell;
            if (r == c)
                break;
            area[r] += cells;
            if (--left[r] != 0)
                break;
            c = r;
        }
    }
    return t;
}

/* Braun and Willett's order: each root (in index order), then its tree
 * depth-first, donors in index order.  No stack of our own: a cell's
 * next donor to visit is counted in next[], and the walk climbs back
 * down the receivers, so the memory touched follows the tree. */
static size_t depth_first(dfle_drainage *dr, unsigned char *next)
{
    const uint32_t *off = dr->don_off;
    uint32_t *s = dr->stack;
    size_t t = 0;
    for (size_t root = 0; root < dr->n; root++) {
        uint32_t c = (uint32_t)root;
        if (dr->dir[root] == DIR_NODATA) {
            dr->area[root] = NAN;
            continue;
        }
        if (dr->rcv[root] != root)
            continue;
        dr->counts.outlets += dr->dir[root] == DIR_OUT;
        dr->counts.sinks += dr->dir[root] == DIR_SINK;
        s[t++] = c;
        next[c] = 0;
        dr->area[c] = 1.0;
        for (;;) {
            uint32_t k = off[c] + next[c];
            if (k < off[c + 1]) {
                next[c]++;
                c = dr->don[k];
                s[t++] = c;
                next[c] = 0;
                dr->area[c] = 1.0;
            } else if (c == root) {
                break;
            } else {
                c = dr->rcv[c];
            }
        }
    }
    return t;
}

/* Area after depth_first: whole cells, passed down the stack from its
 * end (every donor before its receiver) and scaled as each is complete:
 * exact in a double, so the areas leaving the grid add up to exactly
 * cells x cell area, in any order. */
static void stack_area(dfle_drainage *dr)
{
    double cell = dr->o.dx * dr->o.dy;
    for (size_t j = dr->n_stack; j > 0; j--) {
        uint32_t c = dr->stack[j - 1], r = dr->rcv[c];
        double cells = dr->area[c];
        dr->area[c] = cells * cell;
        if (r != c)
            dr->area[r] += cells;
    }
}

int drainage_stack(dfle_drainage *dr, size_t n_data, dfle_error *err)
{
    unsigned char *scratch = drainage_mark(dr);
    if (scratch == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "drainage: out of memory ordering %zu cells",
                              dr->n);
    dr->n_stack = dr->o.order == DFLE_DRAINAGE_KAHN     ? kahn(dr, n_data, scratch)
                  : dr->o.order == DFLE_DRAINAGE_CHAINS ? chains(dr, n_data, scratch)
                                                        : depth_first(dr, scratch);
    if (dr->n_stack != n_data) /* a cycle: the steps never make one */
        return dfle_error_set(err, DFLE_ENUMERIC, "drainage: flow directions form a cycle "
                              "(%zu of %zu cells ordered); this is a bug in dfle", dr->n_stack,
                              n_data);
    if (dr->o.order == DFLE_DRAINAGE_DEPTH_FIRST)
        stack_area(dr);
    return DFLE_OK;
}
