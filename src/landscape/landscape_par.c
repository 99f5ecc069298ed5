/*
 * landscape_par.c - a landscape's work on threads (dfle_landscape_set_par).
 *
 * The backward-Euler sweep reads, for each cell, only its own state and
 * its receiver's new elevation, so basins that drain to different roots
 * are independent: their cells can be swept on different threads in any
 * interleaving, and every cell gets the same bytes as in one sweep down
 * the whole stack.  The basins are dealt into LS_PAR_CHUNKS chunks of
 * about equal area, in the order their roots come in the stack (a rule
 * of the routing alone), and the stack is split by chunk, keeping its
 * order within each, so that every cell still comes after its receiver.
 * The chunks are the pool's items (par.h): a thread takes the next one
 * as it finishes its last.  Each chunk sums its volumes on its own and
 * the sums are added in chunk order, so the volumes too are the same for
 * any number of threads (they may differ in the last bits from those of
 * a landscape without threads, which sums in stack order).
 *
 * A landscape on one great basin (a single outlet) has one chunk doing
 * nearly all the work: threads help where many basins share the grid,
 * as on a landscape whose borders are base level.
 */
#include "landscape/landscape_internal.h"

#include <stdlib.h>

int dfle_landscape_set_par(dfle_landscape *ls, const dfle_par *par, dfle_error *err)
{
    if (par != NULL && par->ops != NULL && par->ops->version != DFLE_PAR_VERSION)
        return dfle_error_set(err, DFLE_EINVAL, "landscape: threads of ops version %d, this "
                              "library knows %d", par->ops->version, DFLE_PAR_VERSION);
    ls->par = par;
    return DFLE_OK;
}

size_t ls_par_bytes(const dfle_landscape *ls)
{
    return (ls->par_stack != NULL) * ls->n_data * sizeof *ls->par_stack +
           (ls->par_chunk != NULL) * ls->n * sizeof *ls->par_chunk;
}

int ls_par_partition(dfle_landscape *ls, dfle_error *err)
{
    size_t n_stack, count[LS_PAR_CHUNKS] = {0};
    const uint32_t *stack = dfle_drainage_stack(ls->dr, &n_stack);
    const uint32_t *rcv = dfle_drainage_receivers(ls->dr);
    const double *A = dfle_drainage_area(ls->dr);
    const double total = (double)n_stack * ls->cell_area;
    unsigned char *chunk;
    double below = 0.0; /* area of the basins dealt so far [m^2] */

    if (ls->par_stack == NULL &&
        (ls->par_stack = malloc(ls->n_data * sizeof *ls->par_stack)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "landscape: out of memory for threads (%zu cells)",
                              ls->n_data);
    if (ls->par_chunk == NULL && (ls->par_chunk = malloc(ls->n)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "landscape: out of memory for threads (%zu cells)",
                              ls->n);
    chunk = ls->par_chunk;
    for (size_t k = 0; k < n_stack; k++) {
        const uint32_t c = stack[k], r = rcv[c];
        if (r == c) { /* a root: its basin goes where the area dealt so far says */
            double j = (below + 0.5 * A[c]) / total * LS_PAR_CHUNKS;
            chunk[c] = (unsigned char)(j < LS_PAR_CHUNKS - 1 ? (size_t)j : LS_PAR_CHUNKS - 1);
            below += A[c];
        } else {
            chunk[c] = chunk[r];
        }
        count[chunk[c]]++;
    }
    ls->par_off[0] = 0;
    for (size_t j = 0; j < LS_PAR_CHUNKS; j++)
        ls->par_off[j + 1] = ls->par_off[j] + count[j];
    {
        size_t at[LS_PAR_CHUNKS];
        memcpy(at, ls->par_off, sizeof at);
        for (size_t k = 0; k < n_stack; k++)
            ls->par_stack[at[chunk[stack[k]]]++] = stack[k];
    }
    return DFLE_OK;
}
