/*
 * drainage_fill.c - depression filling by priority-flood: Barnes,
 * Lehman and Mulla (2014a), Computers & Geosciences 62, 117-127.
 *
 * The flood starts from every cell where water may leave the grid and
 * works inwards in order of elevation: the lowest open cell is taken and
 * its unvisited neighbours visited; one lower than (or as low as) the
 * cell lies in a depression whose spill level is the cell's elevation,
 * so it is raised to it and handled next through a plain FIFO (it sits
 * at the current, lowest level); a higher one joins the priority queue.
 * Each cell ends at its spill elevation: the least, over paths to an
 * exit, of the highest elevation on the path.  O(n log n).
 *
 * The queue orders by (z, index), a total order, so the visit order, and
 * with it the sum of rises, is the same on every platform and for any
 * heap layout.  Depressions are left exactly flat (no epsilon): the
 * routing resolves flats itself (drainage_flats.c).
 */
#include "drainage/drainage_internal.h"

#include <math.h>
#include <stdlib.h>

static int item_less(drainage_heap_item x, drainage_heap_item y)
{
    return x.z < y.z || (x.z == y.z && x.i < y.i);
}

/* Binary min-heap in dr->heap[0 .. *n), grown as needed and kept. */
static int heap_push(dfle_drainage *dr, size_t *n, double z, uint32_t i)
{
    drainage_heap_item it = {z, i};
    size_t k;
    if (*n == dr->heap_cap) {
        size_t cap = dr->heap_cap ? 2 * dr->heap_cap : 1024;
        drainage_heap_item *a = realloc(dr->heap, cap * sizeof *a);
        if (a == NULL)
            return -1;
        dr->heap = a;
        dr->heap_cap = cap;
    }
    /* Move the hole up, then drop the item in. */
    for (k = (*n)++; k > 0 && item_less(it, dr->heap[(k - 1) / 2]); k = (k - 1) / 2)
        dr->heap[k] = dr->heap[(k - 1) / 2];
    dr->heap[k] = it;
    return 0;
}

static uint32_t heap_pop(dfle_drainage *dr, size_t *n)
{
    drainage_heap_item *h = dr->heap, last = h[--*n];
    uint32_t top = h[0].i;
    size_t k = 0;
    for (;;) {
        size_t l = 2 * k + 1, m = l;
        if (l >= *n)
            break;
        if (l + 1 < *n && item_less(h[l + 1], h[l]))
            m = l + 1;
        if (!item_less(h[m], last))
            break;
        h[k] = h[m];
        k = m;
    }
    h[k] = last;
    return top;
}

int dfle_drainage_fill(dfle_drainage *dr, double *z, dfle_drainage_fill_stats *stats,
                       dfle_error *err)
{
    dfle_drainage_fill_stats st = {0, 0.0, 0.0};
    unsigned char *closed = drainage_mark(dr);
    uint32_t *pit = drainage_work(dr, 0); /* FIFO: each cell enters once */
    size_t pit_head = 0, pit_tail = 0, heap_n = 0;

    if (z == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "drainage: elevations are required");
    if (closed == NULL || pit == NULL)
        goto nomem;
    for (size_t i = 0; i < dr->n; i++) {
        closed[i] = 0;
        if (isnan(z[i])) {
            closed[i] = 1;
        } else if (drainage_exit(dr, z, i) != DFLE_DRAINAGE_CLOSED) {
            closed[i] = 1;
            if (heap_push(dr, &heap_n, z[i], (uint32_t)i) != 0)
                goto nomem;
        }
    }
    while (pit_head < pit_tail || heap_n > 0) {
        /* A cell in the FIFO lies at the current spill level, which is
         * below everything in the heap, so it goes first. */
        size_t c = pit_head < pit_tail ? pit[pit_head++] : heap_pop(dr, &heap_n);
        size_t r = c / dr->o.nx, cc = c % dr->o.nx;
        for (int k = 0; k < 8; k++) {
            long long nb = drainage_nb(dr, r, cc, k);
            if (nb < 0 || closed[nb])
                continue;
            closed[nb] = 1;
            if (z[nb] <= z[c]) {
                double rise = z[c] - z[nb];
                if (rise > 0) {
                    st.raised++;
                    st.volume += rise;
                    if (rise > st.max_raise)
                        st.max_raise = rise;
                    z[nb] = z[c];
                }
                pit[pit_tail++] = (uint32_t)nb;
            } else if (heap_push(dr, &heap_n, z[nb], (uint32_t)nb) != 0) {
                goto nomem;
            }
        }
    }
    st.volume *= dr->o.dx * dr->o.dy;
    if (stats != NULL)
        *stats = st;
    return DFLE_OK;
nomem:
    return dfle_error_set(err, DFLE_ENOMEM, "drainage: out of memory filling %zu cells", dr->n);
}
