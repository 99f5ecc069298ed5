/*
 * sensitivity_internal.h - what the files of PAWN (dfle/sensitivity.h)
 * share: the sorted orders and scratch of one analysis, and the calls
 * between the files.  Not installed.
 *
 * The files, each calling only the ones below it:
 *   sensitivity.c            the entry point: checks, results, options
 *   sensitivity_bootstrap.c  bootstrap replicates on threads, intervals
 *   sensitivity_slices.c     one analysis: slice edges, KS statistics,
 *                            the six indices
 *   sensitivity_work.c       sorted orders and scratch of one table
 *   sensitivity_numpy.c      numpy's quantile and sum, shared helpers
 */
#ifndef DFLE_SENSITIVITY_INTERNAL_H
#define DFLE_SENSITIVITY_INTERNAL_H

#include "dfle/sensitivity.h"

/* No fused multiply-adds: numpy and the documented algorithms round every
 * product and sum.  GCC in ISO C mode never contracts across or within
 * expressions; clang would within one, so it is told not to (here, so
 * that every file of PAWN that includes this header is). */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

#include <stddef.h>
#include <stdint.h>

/* What every analysis of one table shares, read-only once built: the
 * sorted orders, and where the runs of equal y end. */
typedef struct pawn_work {
    size_t N, D, S;
    const double *const *x;
    const double *y;
    size_t *perm_y;        /* N: rows by ascending y                       */
    size_t *perm_x;        /* D x N: rows by ascending x_d                 */
    double *x_by_y;        /* D x N: x_d[r] for rows r by ascending y      */
    unsigned char *group_end; /* N: position j ends a run of equal y        */
    size_t *first_end;     /* N: the first run end at or after position j  */
    size_t *end_before;    /* N: the last run end before position j (N: none) */
    int per_slice;         /* the per-slice passes (dfle_pawn_opts)        */
} pawn_work;

/* One slice during the fused pass (slices_fused). */
typedef struct slice_walk {
    uint64_t n1;     /* rows in the slice (with multiplicities)           */
    uint64_t c1;     /* of those, at or before the current position       */
    uint64_t a1, a2; /* N / g and n1 / g, g = gcd(n1, N): the exact scale */
    uint64_t h;      /* largest |c1 a1 - c2 a2| so far                    */
    size_t start;    /* where the current run of constant c1 began        */
    double dmax, dmin; /* above DFLE_PAWN_EXACT_MAX_N: the CDF differences */
} slice_walk;

/* What one analysis writes as it goes: one per thread. */
typedef struct pawn_scratch {
    uint32_t *mult;        /* N: multiplicity of each row (bootstrap)       */
    uint32_t *m_by_y;      /* N: multiplicity of the row at y position j    */
    uint64_t *c2;          /* N: sum of m_by_y[0 .. j]                       */
    double *sorted;        /* N: the (resampled) x_d in ascending order     */
    unsigned char *in;     /* N: row at y position j is in the slice        */
    int32_t *slice;        /* N: slice of each row, -1: none                */
    uint64_t *cum_x;       /* N: multiplicities summed over rows in x order */
    slice_walk *walk;      /* S + 1                                          */
    double *tmp;           /* S: statistics scratch                          */
    double *edges;         /* S + 1 (bootstrap)                              */
    double *ks;            /* S (bootstrap)                                  */
    size_t *count;         /* S                                              */
} pawn_scratch;

/* ---- sensitivity_numpy.c ---- */

/* The k-th smallest of n values, however they are held. */
typedef double (*order_stat_fn)(const void *ctx, size_t k);
/* numpy's linear quantile at level q of the n values order_stat gives
 * (the arithmetic of dfle_quantile_linear). */
double dfle_pawn_quantile_of(order_stat_fn order_stat, const void *ctx, size_t n, double q);
/* qsort's comparison of doubles, ascending. */
int dfle_pawn_compare_doubles(const void *pa, const void *pb);

/* ---- sensitivity_work.c ---- */

/* Sorted orders of y and of every input (DFLE_OK, DFLE_ENOMEM). */
int dfle_pawn_work_init(pawn_work *w, size_t N, size_t D, size_t S, const double *const *x,
                        const double *y);
void dfle_pawn_work_free(pawn_work *w);
/* The scratch of one analysis for N rows and S slices (DFLE_OK,
 * DFLE_ENOMEM); freeing zeroes it. */
int dfle_pawn_scratch_init(pawn_scratch *sc, size_t N, size_t S);
void dfle_pawn_scratch_free(pawn_scratch *sc);
/* Set the multiplicities (NULL: all 1) in y order and their running sums. */
void dfle_pawn_scratch_set_mult(pawn_scratch *sc, const pawn_work *w, const uint32_t *mult);

/* ---- sensitivity_slices.c ---- */

/* One full analysis with row multiplicities `mult` (NULL: all 1), which
 * dfle_pawn_scratch_set_mult has already put in y order.  index: D x 6.
 * edges, ks, count, h, lcm: D x (S+1) / D x S, or NULL to use the
 * scratch (bootstrap replicates keep only the indices). */
void dfle_pawn_analyse(const pawn_work *w, pawn_scratch *sc, const uint32_t *mult, double *index,
                       double *edges_all, double *ks_all, size_t *count_all, uint64_t *h_all,
                       uint64_t *lcm_all);

/* ---- sensitivity_bootstrap.c ---- */

/* opts->bootstrap replicates on opts->threads threads; their percentile
 * intervals into res->lo and res->hi. */
int dfle_pawn_bootstrap(const pawn_work *w, const dfle_pawn_opts *opts, dfle_pawn_result *res,
                        dfle_error *err);

#endif
