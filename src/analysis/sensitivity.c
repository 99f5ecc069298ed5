/*
 * sensitivity.c - PAWN indices on given data, bit-compatible with SALib's
 * pawn.analyze, and their bootstrap confidence intervals.
 *
 * Users compare dfle's rankings with SALib's, so every step follows the
 * arithmetic numpy and scipy perform (dfle/sensitivity.h lists it): the
 * linear quantile with its two interpolation branches, half-open slices,
 * the KS statistic as scipy's exact fraction h / lcm, numpy's pairwise
 * summation for the mean and the variance.  Each rounding step is a
 * separate statement so that no compiler contracts a product and a sum
 * into an FMA (numpy does not).
 *
 * The analysis core takes row multiplicities: 1 for every row gives the
 * point estimate; a bootstrap replicate is the same core with the counts
 * of a resample, which equals running PAWN on the materialised resampled
 * table but needs no sorting per replicate (the sorted orders of y and of
 * each input are computed once).  An input's S slices are found and their
 * KS statistics computed in one walk over the rows (slices_fused), not a
 * walk per slice (slices_per_slice, kept as the reference and for the
 * rare edges that fall).  Bootstrap replicates run on opts->threads
 * threads (pthreads); each replicate is the same block of the one
 * generator's draws whatever the number of threads (bootstrap()).
 */
#include "dfle/sensitivity.h"

/* No fused multiply-adds: numpy and the documented algorithms round every
 * product and sum.  GCC in ISO C mode never contracts across or within
 * expressions; clang would within one, so it is told not to. */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/sampling.h"

static const char *const stat_names[DFLE_PAWN_NSTATS] = {
    "minimum", "mean", "median", "maximum", "CV", "stdev"};

const char *dfle_pawn_stat_name(int stat)
{
    return stat >= 0 && stat < DFLE_PAWN_NSTATS ? stat_names[stat] : NULL;
}

void dfle_pawn_opts_default(dfle_pawn_opts *opts)
{
    opts->S = 10;
    opts->bootstrap = 0;
    opts->conf = 0.95;
    opts->seed = 1;
    opts->names = NULL;
    opts->output = NULL;
    opts->threads = 1;
    opts->per_slice = 0;
}

/* ---- numpy arithmetic ------------------------------------------- */

/* The k-th smallest of n values, however they are held. */
typedef double (*order_stat_fn)(const void *ctx, size_t k);

/* numpy's linear quantile at level q of the n values order_stat gives:
 * the arithmetic of dfle_quantile_linear, for a sorted array or for the
 * rows of a bootstrap replicate in x order (stat_of_counts). */
static double quantile_of(order_stat_fn order_stat, const void *ctx, size_t n, double q)
{
    double last, h, j, t, a, b, diff, part;
    size_t k;

    if (n == 0)
        return NAN;
    last = (double)(n - 1);
    h = last * q;
    if (!(h < last)) /* numpy: index at or above n - 1 takes the last */
        return order_stat(ctx, n - 1);
    if (h < 0.0)
        return order_stat(ctx, 0);
    j = floor(h);
    t = h - j;
    k = (size_t)j;
    a = order_stat(ctx, k);
    b = order_stat(ctx, k + 1);
    diff = b - a;
    if (t >= 0.5) {
        double rest = 1.0 - t;
        part = diff * rest;
        return b - part;
    }
    part = diff * t;
    return a + part;
}

static double stat_of_sorted(const void *ctx, size_t k) { return ((const double *)ctx)[k]; }

double dfle_quantile_linear(const double *sorted, size_t n, double q)
{
    return quantile_of(stat_of_sorted, sorted, n, q);
}

double dfle_sum_pairwise(const double *a, size_t n)
{
    if (n < 8) {
        double res = 0.0;
        for (size_t i = 0; i < n; i++)
            res += a[i];
        return res;
    }
    if (n <= 128) {
        double r[8], res, left, right;
        size_t i;
        for (int k = 0; k < 8; k++)
            r[k] = a[k];
        for (i = 8; i < n - (n % 8); i += 8)
            for (int k = 0; k < 8; k++)
                r[k] += a[i + k];
        left = (r[0] + r[1]) + (r[2] + r[3]);
        right = (r[4] + r[5]) + (r[6] + r[7]);
        res = left + right;
        for (; i < n; i++)
            res += a[i];
        return res;
    }
    {
        size_t n2 = n / 2;
        double left, right;
        n2 -= n2 % 8;
        left = dfle_sum_pairwise(a, n2);
        right = dfle_sum_pairwise(a + n2, n - n2);
        return left + right;
    }
}

/* ---- Helpers ----------------------------------------------------- */

static uint64_t gcd_u64(uint64_t a, uint64_t b)
{
    while (b != 0) {
        uint64_t t = a % b;
        a = b;
        b = t;
    }
    return a;
}

static int compare_doubles(const void *pa, const void *pb)
{
    double a = *(const double *)pa, b = *(const double *)pb;
    return (a > b) - (a < b);
}

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

/* ---- The analysis ------------------------------------------------ */

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

static void work_free(pawn_work *w)
{
    free(w->perm_y);
    free(w->perm_x);
    free(w->x_by_y);
    free(w->group_end);
    free(w->first_end);
    free(w->end_before);
}

static void scratch_free(pawn_scratch *sc)
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

static int scratch_init(pawn_scratch *sc, size_t N, size_t S)
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
        scratch_free(sc);
        return DFLE_ENOMEM;
    }
    return DFLE_OK;
}

/* Set the multiplicities in y order and their running sums. */
static void scratch_set_mult(pawn_scratch *sc, const pawn_work *w, const uint32_t *mult)
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
static int work_init(pawn_work *w, size_t N, size_t D, size_t S, const double *const *x,
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
        work_free(w);
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

/* scipy's two-sided statistic from the extreme CDF differences. */
static double ks_from_extremes(double dmax, double dmin)
{
    double minS = -dmin;
    if (minS < 0.0)
        minS = 0.0;
    if (minS > 1.0)
        minS = 1.0;
    return minS > dmax ? minS : dmax;
}

/* KS statistic of the rows flagged in sc->in (n1 of them counting
 * multiplicities) against all N rows, as scipy.stats.ks_2samp: the
 * empirical CDFs are compared at every distinct y.  *h and *lcm receive
 * the exact fraction when N <= DFLE_PAWN_EXACT_MAX_N.  One pass per
 * slice: the reference the fused pass (slices_fused) is tested against. */
static double ks_statistic(const pawn_work *w, const pawn_scratch *sc, uint64_t n1,
                           uint64_t *h_out, uint64_t *lcm_out)
{
    const size_t N = w->N;
    const uint32_t *m = sc->m_by_y;
    const unsigned char *in = sc->in, *end = w->group_end;
    uint64_t c1 = 0, c2 = 0;

    if (N <= DFLE_PAWN_EXACT_MAX_N) {
        /* cdf1 * lcm = c1 * (N / g), cdf2 * lcm = c2 * (n1 / g). */
        uint64_t g = gcd_u64(n1, N), a1 = N / g, a2 = n1 / g, h = 0, lcm = a2 * N;
        /* Branch-free: membership and run ends are data, not jumps. */
        for (size_t j = 0; j < N; j++) {
            uint64_t p, q, diff;
            c2 += m[j];
            c1 += m[j] & (0 - (uint64_t)in[j]);
            p = c1 * a1;
            q = c2 * a2;
            diff = (p > q ? p - q : q - p) & (0 - (uint64_t)end[j]);
            h = diff > h ? diff : h;
        }
        *h_out = h;
        *lcm_out = lcm;
        return (double)h / (double)lcm;
    }
    {
        double dn1 = (double)n1, dN = (double)N, dmax = 0.0, dmin = 0.0;
        int first = 1;
        for (size_t j = 0; j < N; j++) {
            c2 += m[j];
            if (in[j])
                c1 += m[j];
            if (end[j]) {
                double f1 = (double)c1 / dn1, f2 = (double)c2 / dN;
                double diff = f1 - f2;
                if (first || diff > dmax)
                    dmax = diff;
                if (first || diff < dmin)
                    dmin = diff;
                first = 0;
            }
        }
        *h_out = 0;
        *lcm_out = 0;
        return ks_from_extremes(dmax, dmin);
    }
}

/* Input d's slices one at a time: a pass over the rows to flag each
 * slice's, then its KS walk. */
static void slices_per_slice(const pawn_work *w, pawn_scratch *sc, size_t d, const double *edges,
                             double *ks, size_t *count, uint64_t *h_all, uint64_t *lcm_all)
{
    const size_t N = w->N, S = w->S;
    const double *xy = w->x_by_y + d * N;
    for (size_t s = 0; s < S; s++) {
        const double lo = edges[s], hi = edges[s + 1];
        uint64_t n1 = 0, h = 0, lcm = 0;
        for (size_t j = 0; j < N; j++) {
            unsigned char inside = (unsigned char)((xy[j] >= lo) & (xy[j] < hi));
            sc->in[j] = inside;
            n1 += sc->m_by_y[j] & (0 - (uint64_t)inside);
        }
        count[s] = (size_t)n1;
        ks[s] = n1 == 0 ? NAN : ks_statistic(w, sc, n1, &h, &lcm);
        if (h_all != NULL) {
            h_all[s] = h;
            lcm_all[s] = lcm;
        }
    }
}

/* Where slice k's count c1 is constant, over the positions [lo, hi] by
 * ascending y, c2 only grows: |c1 a1 - c2 a2| is then largest at the
 * first or the last run end of the interval, and c1/n1 - c2/N (rounded,
 * but monotone in c2) largest at the first and smallest at the last.  So
 * a slice evaluates the CDF difference only at those two ends of each
 * interval; the run ends between cannot change its statistic. */

/* Exact regime (N <= DFLE_PAWN_EXACT_MAX_N), the rows at y positions j:
 * slice[j] (S: none), m[j] rows each.  No branch on the data: an
 * interval with no run end yields 0, which cannot raise h. */
static void walk_exact(const pawn_work *w, const pawn_scratch *sc, const int32_t *slice_by_row,
                       slice_walk *walk)
{
    const size_t N = w->N;
    const size_t *first_end = w->first_end, *end_before = w->end_before, *perm_y = w->perm_y;
    const uint64_t *c2 = sc->c2;
    const uint32_t *m = sc->m_by_y;
    for (size_t j = 0; j < N; j++) {
        slice_walk *k = &walk[slice_by_row[perm_y[j]]];
        const size_t lo = k->start, e1 = first_end[lo], e2 = end_before[j];
        const uint64_t p = k->c1 * k->a1, q1 = c2[e1] * k->a2, q2 = c2[e2] * k->a2;
        uint64_t d1 = p > q1 ? p - q1 : q1 - p, d2 = p > q2 ? p - q2 : q2 - p;
        d1 &= 0 - (uint64_t)(e1 < j);             /* a run end in [lo, j - 1] */
        d2 &= 0 - (uint64_t)(e2 < N && e2 >= lo); /* likewise                 */
        d1 = d1 > d2 ? d1 : d2;
        k->h = k->h > d1 ? k->h : d1;
        k->c1 += m[j];
        k->start = j;
    }
}

/* Floating regime (N > DFLE_PAWN_EXACT_MAX_N): c1/n1 - c2/N at run end e. */
static void walk_float_at(slice_walk *k, const uint64_t *c2, size_t e, size_t N)
{
    double f1 = (double)k->c1 / (double)k->n1, f2 = (double)c2[e] / (double)N;
    double diff = f1 - f2;
    if (diff > k->dmax)
        k->dmax = diff;
    if (diff < k->dmin)
        k->dmin = diff;
}

static void walk_float(const pawn_work *w, const pawn_scratch *sc, const int32_t *slice_by_row,
                       slice_walk *walk)
{
    const size_t N = w->N;
    for (size_t j = 0; j < N; j++) {
        slice_walk *k = &walk[slice_by_row[w->perm_y[j]]];
        size_t e1 = w->first_end[k->start], e2 = w->end_before[j];
        if (k->n1 > 0 && e1 < j)
            walk_float_at(k, sc->c2, e1, N);
        if (k->n1 > 0 && e2 < N && e2 >= k->start)
            walk_float_at(k, sc->c2, e2, N);
        k->c1 += sc->m_by_y[j];
        k->start = j;
    }
}

/* The first position i in x order with x >= v. */
static size_t first_at_least(const double *x, const size_t *perm, size_t N, double v)
{
    size_t lo = 0, hi = N;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (x[perm[mid]] < v)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* Input d's slices all at once (edges not decreasing).  Slice s is the
 * run of rows in x order from the first with x >= edges[s] to the first
 * with x >= edges[s + 1] (exactly edges[s] <= x < edges[s + 1]), so a
 * binary search per edge gives every row its slice.  Then one walk over
 * the rows by ascending y for all the slices (walk_exact, walk_float).
 * O(N + S log N) per input instead of O(S N); the same numbers as
 * slices_per_slice, bit for bit. */
static void slices_fused(const pawn_work *w, pawn_scratch *sc, size_t d, const uint32_t *mult,
                         const double *edges, double *ks, size_t *count, uint64_t *h_all,
                         uint64_t *lcm_all)
{
    const size_t N = w->N, S = w->S;
    const double *x = w->x[d];
    const size_t *perm = w->perm_x + d * N;
    slice_walk *walk = sc->walk; /* S + 1: the last for rows in no slice */
    size_t from = first_at_least(x, perm, N, edges[0]);

    memset(walk, 0, (S + 1) * sizeof *walk);
    for (size_t i = 0; i < from; i++)
        sc->slice[perm[i]] = (int32_t)S;
    for (size_t s = 0; s < S; s++) {
        size_t to = first_at_least(x, perm, N, edges[s + 1]);
        uint64_t n1 = 0;
        for (size_t i = from; i < to; i++) {
            sc->slice[perm[i]] = (int32_t)s;
            n1 += mult != NULL ? mult[perm[i]] : 1;
        }
        walk[s].n1 = n1;
        from = to;
    }
    for (size_t i = from; i < N; i++)
        sc->slice[perm[i]] = (int32_t)S;
    for (size_t s = 0; s <= S; s++) {
        slice_walk *k = &walk[s];
        if (k->n1 > 0) {
            uint64_t g = gcd_u64(k->n1, N);
            k->a1 = N / g;
            k->a2 = k->n1 / g;
        }
        k->dmax = -INFINITY;
        k->dmin = INFINITY;
    }
    if (N <= DFLE_PAWN_EXACT_MAX_N)
        walk_exact(w, sc, sc->slice, walk);
    else
        walk_float(w, sc, sc->slice, walk);
    for (size_t s = 0; s < S; s++) {
        slice_walk *k = &walk[s];
        uint64_t h = 0, lcm = 0;
        count[s] = (size_t)k->n1;
        if (k->n1 == 0) {
            ks[s] = NAN;
        } else if (N <= DFLE_PAWN_EXACT_MAX_N) {
            /* the last interval, [start, N - 1]: N - 1 ends a run */
            const uint64_t p = k->c1 * k->a1;
            const size_t ends[2] = {w->first_end[k->start], N - 1};
            for (int e = 0; e < 2; e++) {
                uint64_t q = sc->c2[ends[e]] * k->a2, diff = p > q ? p - q : q - p;
                k->h = k->h > diff ? k->h : diff;
            }
            h = k->h;
            lcm = k->a2 * N;
            ks[s] = (double)h / (double)lcm;
        } else {
            walk_float_at(k, sc->c2, w->first_end[k->start], N);
            walk_float_at(k, sc->c2, N - 1, N);
            ks[s] = ks_from_extremes(k->dmax, k->dmin);
        }
        if (h_all != NULL) {
            h_all[s] = h;
            lcm_all[s] = lcm;
        }
    }
}

/* The six statistics of S slice values (NaN = empty slice), as numpy's
 * nanmin, nanmean, nanmedian, nanmax, nanstd / nanmean, nanstd. */
static void slice_statistics(const double *ks, size_t S, double *tmp, double *out)
{
    size_t cnt = 0;
    double mn = 0.0, mx = 0.0, mean, median, var, sd;

    for (size_t s = 0; s < S; s++) {
        if (isnan(ks[s]))
            continue;
        if (cnt == 0 || ks[s] < mn)
            mn = ks[s];
        if (cnt == 0 || ks[s] > mx)
            mx = ks[s];
        cnt++;
    }
    if (cnt == 0) {
        for (int k = 0; k < DFLE_PAWN_NSTATS; k++)
            out[k] = NAN;
        return;
    }
    /* nanmean: empty slices count as 0 in the pairwise sum. */
    for (size_t s = 0; s < S; s++)
        tmp[s] = isnan(ks[s]) ? 0.0 : ks[s];
    mean = dfle_sum_pairwise(tmp, S) / (double)cnt;
    /* nanstd: squared deviations, 0 for empty slices, over the count. */
    for (size_t s = 0; s < S; s++) {
        double dev = isnan(ks[s]) ? 0.0 : ks[s] - mean;
        tmp[s] = dev * dev;
    }
    var = dfle_sum_pairwise(tmp, S) / (double)cnt;
    sd = sqrt(var);
    /* nanmedian: np.median of the non-empty values; the even case is
     * np.mean of the two middle ones, i.e. (a + b) / 2. */
    {
        size_t m = 0;
        for (size_t s = 0; s < S; s++)
            if (!isnan(ks[s]))
                tmp[m++] = ks[s];
        qsort(tmp, m, sizeof *tmp, compare_doubles);
        if (m % 2 == 1) {
            median = tmp[m / 2];
        } else {
            double sum = tmp[m / 2 - 1] + tmp[m / 2];
            median = sum / 2.0;
        }
    }
    out[DFLE_PAWN_MINIMUM] = mn;
    out[DFLE_PAWN_MEAN] = mean;
    out[DFLE_PAWN_MEDIAN] = median;
    out[DFLE_PAWN_MAXIMUM] = mx;
    out[DFLE_PAWN_CV] = sd / mean;
    out[DFLE_PAWN_STDEV] = sd;
}

/* The rows of a replicate in x order, each as often as drawn. */
typedef struct counts_in_x_order {
    const double *x;
    const size_t *perm; /* rows by ascending x                        */
    const uint64_t *cum; /* multiplicities summed along perm           */
    size_t N;
} counts_in_x_order;

/* The k-th smallest value of the replicate: the x of the first row in x
 * order whose running count exceeds k (rows drawn 0 times never are). */
static double stat_of_counts(const void *ctx, size_t k)
{
    const counts_in_x_order *c = ctx;
    size_t lo = 0, hi = c->N;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (c->cum[mid] <= k)
            lo = mid + 1;
        else
            hi = mid;
    }
    return c->x[c->perm[lo < c->N ? lo : c->N - 1]];
}

/* One full analysis with row multiplicities `mult` (NULL: all 1), which
 * scratch_set_mult has already put in y order.  index: D x 6.  edges, ks,
 * count, h, lcm: D x (S+1) / D x S, or NULL to use the scratch
 * (bootstrap replicates keep only the indices). */
static void analyse(const pawn_work *w, pawn_scratch *sc, const uint32_t *mult, double *index,
                    double *edges_all, double *ks_all, size_t *count_all, uint64_t *h_all,
                    uint64_t *lcm_all)
{
    const size_t N = w->N, S = w->S;
    const double step = 1.0 / (double)S;

    for (size_t d = 0; d < w->D; d++) {
        const double *x = w->x[d];
        const size_t *perm = w->perm_x + d * N;
        double *edges = edges_all != NULL ? edges_all + d * (S + 1) : sc->edges;
        double *ks = ks_all != NULL ? ks_all + d * S : sc->ks;
        size_t *count = count_all != NULL ? count_all + d * S : sc->count;
        uint64_t *h = h_all != NULL ? h_all + d * S : NULL;
        uint64_t *lcm = lcm_all != NULL ? lcm_all + d * S : NULL;
        int rising = 1;

        /* The quantiles of the (resampled) input at levels s * (1/S), as
         * np.arange(0, 1 + step, step) gives them: from the input sorted
         * with each row repeated as often as drawn (the reference), or
         * straight from the running counts of rows in x order. */
        if (w->per_slice) {
            size_t k = 0;
            for (size_t j = 0; j < N; j++) {
                size_t r = perm[j];
                uint32_t m = mult != NULL ? mult[r] : 1;
                for (uint32_t c = 0; c < m; c++)
                    sc->sorted[k++] = x[r];
            }
            for (size_t s = 0; s <= S; s++)
                edges[s] = dfle_quantile_linear(sc->sorted, N, (double)s * step);
        } else {
            const counts_in_x_order ctx = {x, perm, sc->cum_x, N};
            uint64_t c = 0;
            for (size_t j = 0; j < N; j++) {
                c += mult != NULL ? mult[perm[j]] : 1;
                sc->cum_x[j] = c;
            }
            for (size_t s = 0; s <= S; s++)
                edges[s] = quantile_of(stat_of_counts, &ctx, N, (double)s * step);
        }
        for (size_t s = 1; s <= S; s++)
            if (!(edges[s - 1] <= edges[s]))
                rising = 0;
        /* Rounding in numpy's interpolation could in principle make two
         * edges fall; slices may then overlap, which only the per-slice
         * passes follow. */
        if (rising && !w->per_slice)
            slices_fused(w, sc, d, mult, edges, ks, count, h, lcm);
        else
            slices_per_slice(w, sc, d, edges, ks, count, h, lcm);
        slice_statistics(ks, S, sc->tmp, index + d * DFLE_PAWN_NSTATS);
    }
}

/* Percentile intervals from B replicates of D x 6 indices. */
static int percentile_intervals(const double *reps, size_t B, size_t D, double conf,
                                double *lo, double *hi)
{
    double *buf = malloc(B * sizeof *buf);
    double qlo = (1.0 - conf) / 2.0, qhi = (1.0 + conf) / 2.0;

    if (buf == NULL)
        return DFLE_ENOMEM;
    for (size_t i = 0; i < D * DFLE_PAWN_NSTATS; i++) {
        size_t m = 0;
        for (size_t b = 0; b < B; b++) {
            double v = reps[b * D * DFLE_PAWN_NSTATS + i];
            if (!isnan(v))
                buf[m++] = v;
        }
        if (m == 0) {
            lo[i] = hi[i] = NAN;
            continue;
        }
        qsort(buf, m, sizeof *buf, compare_doubles);
        lo[i] = dfle_quantile_linear(buf, m, qlo);
        hi[i] = dfle_quantile_linear(buf, m, qhi);
    }
    free(buf);
    return DFLE_OK;
}

/* The bootstrap's replicates, shared by its threads.  Replicate b is
 * always drawn as the b-th block of N draws of the one generator: a
 * thread takes the next replicate and draws its rows under the lock, in
 * replicate order, then analyses it on its own.  So the replicates, and
 * the intervals, do not depend on how many threads there are. */
typedef struct boot_run {
    const pawn_work *w;
    size_t B;
    double *reps;          /* B x D x 6 */
    dfle_rng *rng;
    pthread_mutex_t lock;
    size_t next;           /* the next replicate to draw */
} boot_run;

typedef struct boot_thread {
    boot_run *run;
    pawn_scratch sc;
    uint32_t *draw;        /* N: the rows of the replicate being drawn */
    pthread_t id;
    int started;
} boot_thread;

static void *boot_worker(void *arg)
{
    boot_thread *t = arg;
    boot_run *run = t->run;
    const pawn_work *w = run->w;
    const size_t N = w->N, D = w->D;

    for (;;) {
        size_t b;
        pthread_mutex_lock(&run->lock);
        b = run->next;
        if (b < run->B) {
            run->next++;
            for (size_t i = 0; i < N; i++)
                t->draw[i] = (uint32_t)dfle_rng_below(run->rng, N);
        }
        pthread_mutex_unlock(&run->lock);
        if (b >= run->B)
            break;
        memset(t->sc.mult, 0, N * sizeof *t->sc.mult);
        for (size_t i = 0; i < N; i++)
            t->sc.mult[t->draw[i]]++;
        scratch_set_mult(&t->sc, w, t->sc.mult);
        analyse(w, &t->sc, t->sc.mult, run->reps + b * D * DFLE_PAWN_NSTATS, NULL, NULL, NULL,
                NULL, NULL);
    }
    return NULL;
}

static int bootstrap(const pawn_work *w, const dfle_pawn_opts *opts, dfle_pawn_result *res,
                     dfle_error *err)
{
    const size_t N = w->N, D = w->D, B = opts->bootstrap;
    size_t nt = opts->threads > 1 ? opts->threads : 1;
    boot_thread *th = NULL;
    boot_run run;
    int st = DFLE_OK, locked = 0;

    if (nt > B)
        nt = B;
    memset(&run, 0, sizeof run);
    run.w = w;
    run.B = B;
    if ((st = dfle_rng_new(opts->seed, &run.rng, err)) != DFLE_OK)
        return st;
    run.reps = malloc(B * D * DFLE_PAWN_NSTATS * sizeof *run.reps);
    th = calloc(nt, sizeof *th);
    if (run.reps == NULL || th == NULL)
        goto nomem;
    for (size_t i = 0; i < nt; i++) {
        th[i].run = &run;
        if (scratch_init(&th[i].sc, N, w->S) != DFLE_OK ||
            (th[i].draw = malloc(N * sizeof *th[i].draw)) == NULL)
            goto nomem;
    }
    if (pthread_mutex_init(&run.lock, NULL) != 0) {
        st = dfle_error_set(err, DFLE_ENOMEM, "pawn: cannot create a lock for the bootstrap");
        goto done;
    }
    locked = 1;
    /* Threads that cannot be started leave their share to the others. */
    for (size_t i = 1; i < nt; i++)
        th[i].started = pthread_create(&th[i].id, NULL, boot_worker, &th[i]) == 0;
    boot_worker(&th[0]);
    for (size_t i = 1; i < nt; i++)
        if (th[i].started)
            pthread_join(th[i].id, NULL);
    if (percentile_intervals(run.reps, B, D, opts->conf, res->lo, res->hi) != DFLE_OK)
        goto nomem;
    goto done;
nomem:
    st = dfle_error_set(err, DFLE_ENOMEM, "pawn: out of memory for %zu bootstrap replicates", B);
done:
    if (locked)
        pthread_mutex_destroy(&run.lock);
    for (size_t i = 0; th != NULL && i < nt; i++) {
        scratch_free(&th[i].sc);
        free(th[i].draw);
    }
    free(th);
    free(run.reps);
    dfle_rng_free(run.rng);
    return st;
}

void dfle_pawn_release(dfle_pawn_result *res)
{
    if (res == NULL)
        return;
    free(res->index);
    free(res->edges);
    free(res->ks);
    free(res->count);
    free(res->ks_h);
    free(res->ks_lcm);
    free(res->lo);
    free(res->hi);
    memset(res, 0, sizeof *res);
}

/* Input d's name for messages. */
static void input_label(const dfle_pawn_opts *opts, size_t d, char *buf, size_t size)
{
    if (opts->names != NULL && opts->names[d] != NULL)
        snprintf(buf, size, "input '%s'", opts->names[d]);
    else
        snprintf(buf, size, "input %zu", d + 1);
}

static int check_data(size_t N, size_t D, const double *const *x, const double *y,
                      const dfle_pawn_opts *o, dfle_error *err)
{
    char label[200];

    if (y == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "pawn: output array is NULL");
    for (size_t i = 0; i < N; i++)
        if (!isfinite(y[i])) {
            if (o->output != NULL)
                snprintf(label, sizeof label, "output '%s'", o->output);
            else
                snprintf(label, sizeof label, "output");
            return dfle_error_set(err, DFLE_EINVAL,
                                  "pawn: %s is not finite (%g) in row %zu; PAWN needs finite "
                                  "values (drop failed runs first)", label, y[i], i + 1);
        }
    for (size_t d = 0; d < D; d++) {
        input_label(o, d, label, sizeof label);
        if (x[d] == NULL)
            return dfle_error_set(err, DFLE_EINVAL, "pawn: %s: array is NULL", label);
        for (size_t i = 0; i < N; i++)
            if (!isfinite(x[d][i]))
                return dfle_error_set(err, DFLE_EINVAL,
                                      "pawn: %s is not finite (%g) in row %zu", label,
                                      x[d][i], i + 1);
    }
    return DFLE_OK;
}

static int check_args(size_t N, size_t D, const double *const *x, const dfle_pawn_opts *o,
                      dfle_error *err)
{
    if (x == NULL && D > 0)
        return dfle_error_set(err, DFLE_EINVAL, "pawn: input arrays are NULL");
    if (D == 0)
        return dfle_error_set(err, DFLE_EINVAL, "pawn: at least one input is needed");
    if (N < 2)
        return dfle_error_set(err, DFLE_EINVAL, "pawn: at least 2 rows are needed (got %zu)", N);
    if (o->S < 1)
        return dfle_error_set(err, DFLE_EINVAL, "pawn: S (slices) must be at least 1");
    if (o->S > SIZE_MAX / 8 / (D + 1) || N > SIZE_MAX / 8 / (D + 1))
        return dfle_error_set(err, DFLE_EINVAL, "pawn: %zu rows x %zu slices is too large", N,
                              o->S);
    if (!(o->conf > 0.0 && o->conf < 1.0))
        return dfle_error_set(err, DFLE_EINVAL,
                              "pawn: conf (confidence level) must be in (0, 1) (got %g)",
                              o->conf);
    if (o->seed > DFLE_SEED_MAX)
        return dfle_error_set(err, DFLE_EINVAL,
                              "pawn: seed must be a whole number in [0, %lu] (got %lu)",
                              DFLE_SEED_MAX, o->seed);
    if (o->bootstrap > 0 && (uint64_t)N > UINT32_MAX)
        return dfle_error_set(err, DFLE_EINVAL, "pawn: bootstrap needs fewer than 2^32 rows");
    if (o->threads > DFLE_PAWN_MAX_THREADS)
        return dfle_error_set(err, DFLE_EINVAL, "pawn: threads must be at most %d (got %zu)",
                              DFLE_PAWN_MAX_THREADS, o->threads);
    if (o->bootstrap > SIZE_MAX / 8 / DFLE_PAWN_NSTATS / D)
        return dfle_error_set(err, DFLE_EINVAL, "pawn: bootstrap = %zu is too large",
                              o->bootstrap);
    return DFLE_OK;
}

int dfle_pawn(size_t N, size_t D, const double *const *x, const double *y,
              const dfle_pawn_opts *opts, dfle_pawn_result *out, dfle_error *err)
{
    dfle_pawn_opts defaults;
    pawn_work w;
    pawn_scratch sc;
    size_t S;
    int st;

    if (out == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "pawn: result pointer is NULL");
    memset(out, 0, sizeof *out);
    if (opts == NULL) {
        dfle_pawn_opts_default(&defaults);
        opts = &defaults;
    }
    if ((st = check_args(N, D, x, opts, err)) != DFLE_OK ||
        (st = check_data(N, D, x, y, opts, err)) != DFLE_OK)
        return st;
    S = opts->S;

    out->N = N;
    out->D = D;
    out->S = S;
    out->conf = opts->conf;
    out->index = malloc(D * DFLE_PAWN_NSTATS * sizeof *out->index);
    out->edges = malloc(D * (S + 1) * sizeof *out->edges);
    out->ks = malloc(D * S * sizeof *out->ks);
    out->count = malloc(D * S * sizeof *out->count);
    out->ks_h = malloc(D * S * sizeof *out->ks_h);
    out->ks_lcm = malloc(D * S * sizeof *out->ks_lcm);
    if (opts->bootstrap > 0) {
        out->lo = malloc(D * DFLE_PAWN_NSTATS * sizeof *out->lo);
        out->hi = malloc(D * DFLE_PAWN_NSTATS * sizeof *out->hi);
    }
    if (!out->index || !out->edges || !out->ks || !out->count || !out->ks_h || !out->ks_lcm ||
        (opts->bootstrap > 0 && (!out->lo || !out->hi))) {
        dfle_pawn_release(out);
        return dfle_error_set(err, DFLE_ENOMEM, "pawn: out of memory");
    }
    if (work_init(&w, N, D, S, x, y) != DFLE_OK) {
        dfle_pawn_release(out);
        return dfle_error_set(err, DFLE_ENOMEM, "pawn: out of memory for %zu rows", N);
    }
    w.per_slice = opts->per_slice;
    if (scratch_init(&sc, N, S) != DFLE_OK) {
        work_free(&w);
        dfle_pawn_release(out);
        return dfle_error_set(err, DFLE_ENOMEM, "pawn: out of memory for %zu rows", N);
    }
    scratch_set_mult(&sc, &w, NULL);
    analyse(&w, &sc, NULL, out->index, out->edges, out->ks, out->count, out->ks_h, out->ks_lcm);
    scratch_free(&sc);
    if (opts->bootstrap > 0) {
        out->bootstrap = opts->bootstrap;
        if ((st = bootstrap(&w, opts, out, err)) != DFLE_OK) {
            work_free(&w);
            dfle_pawn_release(out);
            return st;
        }
    }
    work_free(&w);
    return DFLE_OK;
}
