/*
 * drainage_tree.c - the flow tree once receivers are final: donors in
 * compressed rows, the stack, and drainage area.
 *
 * The stack puts every cell after its receiver, roots first (Braun and
 * Willett 2013), in one of two orders.  Kahn's (cells without donors
 * first, in index order; a cell once all its donors are out), read
 * backwards, is the default: its FIFO holds independent cells, so the
 * processor overlaps their memory accesses, and it is 2-3 times faster
 * to build on a large grid than a depth-first walk, whose every step
 * waits for the last.  It is also the order the DEM has always listed
 * (dfle_dem_order, a network's rows).  Braun and Willett's depth-first
 * order, which keeps each tree contiguous, is there for work done tree
 * by tree.  Area does not depend on the order.  Every loop is a plain
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
    size_t head = 0, tail = 0;
    size_t outlets = 0, sinks = 0;
    for (size_t i = 0; i < dr->n; i++) {
        int data = dr->dir[i] != DIR_NODATA;
        outlets += dr->dir[i] == DIR_OUT; /* the counts, on the way */
        sinks += dr->dir[i] == DIR_SINK;
        left[i] = (unsigned char)(dr->don_off[i + 1] - dr->don_off[i]); /* at most 8 */
        area[i] = data ? 1.0 : NAN;
        if (left[i] == 0 && data)
            *(s - tail++) = (uint32_t)i;
    }
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
    dr->counts.outlets = outlets;
    dr->counts.sinks = sinks;
    return tail;
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
    dr->n_stack = dr->o.order == DFLE_DRAINAGE_KAHN ? kahn(dr, n_data, scratch)
                                                    : depth_first(dr, scratch);
    if (dr->n_stack != n_data) /* a cycle: the steps never make one */
        return dfle_error_set(err, DFLE_ENUMERIC, "drainage: flow directions form a cycle "
                              "(%zu of %zu cells ordered); this is a bug in dfle", dr->n_stack,
                              n_data);
    if (dr->o.order != DFLE_DRAINAGE_KAHN)
        stack_area(dr);
    return DFLE_OK;
}
