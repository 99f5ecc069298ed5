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
 * each input are computed once).
 */
#include "dfle/sensitivity.h"

/* No fused multiply-adds: numpy and the documented algorithms round every
 * product and sum.  GCC in ISO C mode never contracts across or within
 * expressions; clang would within one, so it is told not to. */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

#include <math.h>
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
}

/* ---- numpy arithmetic ------------------------------------------- */

double dfle_quantile_linear(const double *sorted, size_t n, double q)
{
    double last, h, j, t, a, b, diff, part;
    size_t k;

    if (n == 0)
        return NAN;
    last = (double)(n - 1);
    h = last * q;
    if (!(h < last)) /* numpy: index at or above n - 1 takes the last */
        return sorted[n - 1];
    if (h < 0.0)
        return sorted[0];
    j = floor(h);
    t = h - j;
    k = (size_t)j;
    a = sorted[k];
    b = sorted[k + 1];
    diff = b - a;
    if (t >= 0.5) {
        double rest = 1.0 - t;
        part = diff * rest;
        return b - part;
    }
    part = diff * t;
    return a + part;
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

typedef struct pawn_work {
    size_t N, D, S;
    const double *const *x;
    const double *y;
    size_t *perm_y;        /* N: rows by ascending y                     */
    size_t *perm_x;        /* D x N: rows by ascending x_d               */
    double *x_by_y;        /* D x N: x_d[r] for rows r by ascending y    */
    unsigned char *group_end; /* N: position j ends a run of equal y      */
    uint32_t *m_by_y;      /* N: multiplicity of the row at y position j */
    double *sorted;        /* N: the (resampled) x_d in ascending order  */
    unsigned char *in;     /* N: row at y position j is in the slice     */
    double *tmp;           /* S: statistics scratch                      */
    double *edges;         /* S + 1 scratch (bootstrap)                  */
    double *ks;            /* S scratch (bootstrap)                      */
    size_t *count;         /* S scratch                                  */
} pawn_work;

static void work_free(pawn_work *w)
{
    free(w->perm_y);
    free(w->perm_x);
    free(w->x_by_y);
    free(w->group_end);
    free(w->m_by_y);
    free(w->sorted);
    free(w->in);
    free(w->tmp);
    free(w->edges);
    free(w->ks);
    free(w->count);
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
    w->m_by_y = malloc(N * sizeof *w->m_by_y);
    w->sorted = malloc(N * sizeof *w->sorted);
    w->in = malloc(N);
    w->tmp = malloc(S * sizeof *w->tmp);
    w->edges = malloc((S + 1) * sizeof *w->edges);
    w->ks = malloc(S * sizeof *w->ks);
    w->count = malloc(S * sizeof *w->count);
    scratch = malloc(N * sizeof *scratch);
    if (!w->perm_x || !w->x_by_y || !w->group_end || !w->m_by_y || !w->sorted || !w->in ||
        !w->tmp || !w->edges || !w->ks || !w->count || !scratch || !perm_y) {
        free(scratch);
        work_free(w);
        return DFLE_ENOMEM;
    }
    for (size_t i = 0; i < N; i++)
        perm_y[i] = i;
    sort_rows(y, perm_y, scratch, N);
    for (size_t j = 0; j < N; j++) {
        w->group_end[j] = j + 1 == N || y[perm_y[j + 1]] != y[perm_y[j]];
        w->m_by_y[j] = 1;
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

/* KS statistic of the rows flagged in w->in (n1 of them counting
 * multiplicities) against all N rows, as scipy.stats.ks_2samp: the
 * empirical CDFs are compared at every distinct y.  *h and *lcm receive
 * the exact fraction when N <= DFLE_PAWN_EXACT_MAX_N. */
static double ks_statistic(const pawn_work *w, uint64_t n1, uint64_t *h_out, uint64_t *lcm_out)
{
    const size_t N = w->N;
    const uint32_t *m = w->m_by_y;
    const unsigned char *in = w->in, *end = w->group_end;
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
        double dn1 = (double)n1, dN = (double)N, dmax = 0.0, dmin = 0.0, minS;
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
        minS = -dmin;
        if (minS < 0.0)
            minS = 0.0;
        if (minS > 1.0)
            minS = 1.0;
        return minS > dmax ? minS : dmax;
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

/* One full analysis with row multiplicities `mult` (NULL: all 1).
 * index: D x 6.  edges, ks, count, h, lcm: D x (S+1) / D x S, or NULL
 * to use the work scratch (bootstrap replicates keep only the indices).
 * w->m_by_y must hold the multiplicities in y order. */
static void analyse(pawn_work *w, const uint32_t *mult, double *index, double *edges_all,
                    double *ks_all, size_t *count_all, uint64_t *h_all, uint64_t *lcm_all)
{
    const size_t N = w->N, S = w->S;
    const double step = 1.0 / (double)S;

    for (size_t d = 0; d < w->D; d++) {
        const double *x = w->x[d], *xy = w->x_by_y + d * N;
        const size_t *perm = w->perm_x + d * N;
        double *edges = edges_all != NULL ? edges_all + d * (S + 1) : w->edges;
        double *ks = ks_all != NULL ? ks_all + d * S : w->ks;
        size_t *count = count_all != NULL ? count_all + d * S : w->count;
        size_t k = 0;

        /* The (resampled) input in ascending order, then its quantiles at
         * levels s * (1/S), as np.arange(0, 1 + step, step) gives them. */
        for (size_t j = 0; j < N; j++) {
            size_t r = perm[j];
            uint32_t m = mult != NULL ? mult[r] : 1;
            for (uint32_t c = 0; c < m; c++)
                w->sorted[k++] = x[r];
        }
        for (size_t s = 0; s <= S; s++)
            edges[s] = dfle_quantile_linear(w->sorted, N, (double)s * step);

        for (size_t s = 0; s < S; s++) {
            const double lo = edges[s], hi = edges[s + 1];
            uint64_t n1 = 0, h = 0, lcm = 0;
            for (size_t j = 0; j < N; j++) {
                unsigned char inside = (unsigned char)((xy[j] >= lo) & (xy[j] < hi));
                w->in[j] = inside;
                n1 += w->m_by_y[j] & (0 - (uint64_t)inside);
            }
            count[s] = (size_t)n1;
            ks[s] = n1 == 0 ? NAN : ks_statistic(w, n1, &h, &lcm);
            if (h_all != NULL) {
                h_all[d * S + s] = h;
                lcm_all[d * S + s] = lcm;
            }
        }
        slice_statistics(ks, S, w->tmp, index + d * DFLE_PAWN_NSTATS);
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

static int bootstrap(pawn_work *w, const dfle_pawn_opts *opts, dfle_pawn_result *res,
                     dfle_error *err)
{
    const size_t N = w->N, D = w->D, B = opts->bootstrap;
    double *reps = NULL;
    uint32_t *mult = NULL;
    dfle_rng *rng = NULL;
    int st;

    if ((st = dfle_rng_new(opts->seed, &rng, err)) != DFLE_OK)
        return st;
    reps = malloc(B * D * DFLE_PAWN_NSTATS * sizeof *reps);
    mult = malloc(N * sizeof *mult);
    if (reps == NULL || mult == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "pawn: out of memory for %zu bootstrap replicates",
                            B);
        goto done;
    }
    for (size_t b = 0; b < B; b++) {
        memset(mult, 0, N * sizeof *mult);
        for (size_t i = 0; i < N; i++)
            mult[dfle_rng_below(rng, N)]++;
        for (size_t j = 0; j < N; j++)
            w->m_by_y[j] = mult[w->perm_y[j]];
        analyse(w, mult, reps + b * D * DFLE_PAWN_NSTATS, NULL, NULL, NULL, NULL, NULL);
    }
    if (percentile_intervals(reps, B, D, opts->conf, res->lo, res->hi) != DFLE_OK)
        st = dfle_error_set(err, DFLE_ENOMEM, "pawn: out of memory");
done:
    free(reps);
    free(mult);
    dfle_rng_free(rng);
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
    analyse(&w, NULL, out->index, out->edges, out->ks, out->count, out->ks_h, out->ks_lcm);
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
