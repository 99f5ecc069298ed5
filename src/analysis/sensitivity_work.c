/*
 * sensitivity_work.c - what every PAWN analysis of one table shares and
 * what each writes as it goes: the sorted orders of y and of each input,
 * where the runs of equal y end, and the scratch of one analysis (one
 * per bootstrap thread).
 *
 * The sorted orders are computed once per table, not per bootstrap
 * replicate: a replicate is the same rows with other multiplicities
 * (dfle_pawn_scratch_set_mult), so the KS walks of every replicate go
 * through the same rows by ascending y over contiguous arrays.
 */
#include "analysis/sensitivity_internal.h"

#include <stdlib.h>
#include <string.h>

/* Stable bottom-up merge sort of row indices idx[0..n-1] by key[idx]. */
static void sort_rows(const double *key, size_t *idx, size_t *tmp, size_t n)
{
    size_t *src = idx, *dst = tmp;

    for (size_t width = 1; width < n; width *= 2) {
        for (size_t lo = 0; lo < n; lo += 2 * width) {
            size_t mid = lo + width < n ? lo + width : n;
            size_t hi = lo + 2 * width < n ? lo + 2 * width : n;
            size_t i = lo, j = mid, k = lo;
            while (i < mid && j < hi)
                dst[k++] = key[src[j]] < key[src[i]] ? src[j++] : src[i++];
            while (i < mid)
                dst[k++] = src[i++];
            while (j < hi)
                dst[k++] = src[j++];
        }
        {
            size_t *t = src;
            src = dst;
            dst = t;
        }
    }
    if (src != idx)
        memcpy(idx, src, n * sizeof *idx);
}

void dfle_pawn_work_free(pawn_work *w)
{
    free(w->perm_y);
    free(w->perm_x);
    free(w->x_by_y);
    free(w->group_end);
    free(w->first_end);
    free(w->end_before);
}

void dfle_pawn_scratch_free(pawn_scratch *sc)
{
    free(sc->mult);
    free(sc->m_by_y);
    free(sc->c2);
    free(sc->sorted);
    free(sc->in);
    free(sc->slice);
    free(sc->cum_x);
    free(sc->walk);
    free(sc->tmp);
    free(sc->edges);
    free(sc->ks);
    free(sc->count);
    memset(sc, 0, sizeof *sc);
}

int dfle_pawn_scratch_init(pawn_scratch *sc, size_t N, size_t S)
{
    memset(sc, 0, sizeof *sc);
    sc->mult = malloc(N * sizeof *sc->mult);
    sc->m_by_y = malloc(N * sizeof *sc->m_by_y);
    sc->c2 = malloc((N + 1) * sizeof *sc->c2); /* c2[N]: read, unused, for "none" */
    sc->sorted = malloc(N * sizeof *sc->sorted);
    sc->in = malloc(N);
    sc->slice = malloc(N * sizeof *sc->slice);
    sc->cum_x = malloc(N * sizeof *sc->cum_x);
    sc->walk = malloc((S + 1) * sizeof *sc->walk);
    sc->tmp = malloc(S * sizeof *sc->tmp);
    sc->edges = malloc((S + 1) * sizeof *sc->edges);
    sc->ks = malloc(S * sizeof *sc->ks);
    sc->count = malloc(S * sizeof *sc->count);
    if (!sc->mult || !sc->m_by_y || !sc->c2 || !sc->sorted || !sc->in || !sc->slice ||
        !sc->cum_x || !sc->walk || !sc->tmp || !sc->edges || !sc->ks || !sc->count) {
        dfle_pawn_scratch_free(sc);
        return DFLE_ENOMEM;
    }
    return DFLE_OK;
}

/* Set the multiplicities in y order and their running sums. */
void dfle_pawn_scratch_set_mult(pawn_scratch *sc, const pawn_work *w, const uint32_t *mult)
{
    uint64_t c = 0;
    for (size_t j = 0; j < w->N; j++) {
        sc->m_by_y[j] = mult != NULL ? mult[w->perm_y[j]] : 1;
        c += sc->m_by_y[j];
        sc->c2[j] = c;
    }
    sc->c2[w->N] = 0;
}

/* Sorted orders of y and of every input, computed once: the KS walks go
 * through rows by ascending y over contiguous arrays. */
int dfle_pawn_work_init(pawn_work *w, size_t N, size_t D, size_t S, const double *const *x,
                        const double *y)
{
    size_t *scratch, *perm_y;

    memset(w, 0, sizeof *w);
    w->perm_y = perm_y = malloc(N * sizeof *perm_y);
    w->N = N;
    w->D = D;
    w->S = S;
    w->x = x;
    w->y = y;
    w->perm_x = malloc(D * N * sizeof *w->perm_x);
    w->x_by_y = malloc(D * N * sizeof *w->x_by_y);
    w->group_end = malloc(N);
    w->first_end = malloc(N * sizeof *w->first_end);
    w->end_before = malloc(N * sizeof *w->end_before);
    scratch = malloc(N * sizeof *scratch);
    if (!w->perm_x || !w->x_by_y || !w->group_end || !w->first_end || !w->end_before ||
        !scratch || !perm_y) {
        free(scratch);
        dfle_pawn_work_free(w);
        return DFLE_ENOMEM;
    }
    for (size_t i = 0; i < N; i++)
        perm_y[i] = i;
    sort_rows(y, perm_y, scratch, N);
    for (size_t j = 0; j < N; j++)
        w->group_end[j] = j + 1 == N || y[perm_y[j + 1]] != y[perm_y[j]];
    for (size_t j = 0, last = N; j < N; j++) {
        w->end_before[j] = last;
        if (w->group_end[j])
            last = j;
    }
    for (size_t j = N, first = N - 1; j-- > 0;) {
        if (w->group_end[j])
            first = j;
        w->first_end[j] = first;
    }
    for (size_t d = 0; d < D; d++) {
        size_t *p = w->perm_x + d * N;
        for (size_t i = 0; i < N; i++)
            p[i] = i;
        sort_rows(x[d], p, scratch, N);
        for (size_t j = 0; j < N; j++)
            w->x_by_y[d * N + j] = x[d][perm_y[j]];
    }
    free(scratch);
    return DFLE_OK;
}
