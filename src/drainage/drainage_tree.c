/*
 * drainage_tree.c - the flow tree once receivers are final: donors in
 * compressed rows, then the stack order and drainage area in one pass.
 *
 * The stack is Kahn's topological order (cells without donors first, in
 * index order; a cell once all its donors are out), read backwards so
 * that roots come first and every cell follows its receiver, as Braun
 * and Willett (2013) need it.  Kahn's order rather than their
 * depth-first one because it is the order the DEM has always listed
 * (dfle_dem_order, and a network's rows, are that order), and both
 * serve the landscape model alike: any order with receivers first is
 * a valid stack.  Every loop is a plain pass or a FIFO, so no tree is
 * too deep for the C stack.
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
            off[dr->rcv[i] + 1]++;
    for (size_t i = 0; i < n; i++)
        off[i + 1] += off[i];
    /* off[r] serves as r's cursor, ending at r + 1's start; shifting
     * back by one restores the starts without a second array. */
    for (size_t i = 0; i < n; i++)
        if (dr->rcv[i] != i)
            dr->don[off[dr->rcv[i]]++] = (uint32_t)i;
    memmove(off + 1, off, n * sizeof *off);
    off[0] = 0;
}

int drainage_order(dfle_drainage *dr, size_t n_data, dfle_error *err)
{
    unsigned char *left = drainage_mark(dr); /* donors not yet passed */
    uint32_t *s = dr->stack;
    double *A = dr->area, cell = dr->o.dx * dr->o.dy;
    size_t head = 0, tail = 0;

    if (left == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "drainage: out of memory ordering %zu cells",
                              dr->n);
    for (size_t i = 0; i < dr->n; i++) {
        left[i] = (unsigned char)(dr->don_off[i + 1] - dr->don_off[i]); /* at most 8 */
        A[i] = dr->dir[i] == DIR_NODATA ? NAN : 1.0;
        if (left[i] == 0 && dr->dir[i] != DIR_NODATA)
            s[tail++] = (uint32_t)i;
    }
    /* Area in whole cells, passed on as each cell leaves the queue (all
     * its donors have passed theirs), scaled once at the end: exact in
     * a double, so the areas leaving the grid add up to exactly cells x
     * cell area, whatever the order. */
    while (head < tail) {
        uint32_t c = s[head++], r = dr->rcv[c];
        if (r == c)
            continue;
        A[r] += A[c];
        if (--left[r] == 0)
            s[tail++] = r;
    }
    dr->n_stack = tail;
    if (tail != n_data) /* a cycle: the steps never make one */
        return dfle_error_set(err, DFLE_ENUMERIC, "drainage: flow directions form a cycle "
                              "(%zu of %zu cells ordered); this is a bug in dfle", tail, n_data);
    for (size_t i = 0; i < dr->n; i++)
        A[i] *= cell;
    for (size_t a = 0, b = tail; a + 1 < b; a++, b--) {
        uint32_t t = s[a];
        s[a] = s[b - 1];
        s[b - 1] = t;
    }
    return DFLE_OK;
}
