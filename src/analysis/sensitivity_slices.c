/*
 * sensitivity_slices.c - one PAWN analysis of a table: each input's
 * slice edges (numpy's quantiles), the KS statistic of every slice as
 * scipy.stats.ks_2samp computes it (the exact fraction h / lcm), and
 * the six indices of the slices' statistics (numpy's nan-functions).
 *
 * The analysis takes row multiplicities: 1 for every row gives the
 * point estimate; a bootstrap replicate is the same analysis with the
 * counts of a resample, which equals running PAWN on the materialised
 * resampled table but needs no sorting per replicate (the sorted orders
 * are sensitivity_work.c's).  An input's S slices are found and their
 * KS statistics computed in one walk over the rows (slices_fused), not a
 * walk per slice (slices_per_slice, kept as the reference and for the
 * rare edges that fall).
 */
#include "analysis/sensitivity_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static uint64_t gcd_u64(uint64_t a, uint64_t b)
{
    while (b != 0) {
        uint64_t t = a % b;
        a = b;
        b = t;
    }
    return a;
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
        qsort(tmp, m, sizeof *tmp, dfle_pawn_compare_doubles);
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

/* One full analysis (sensitivity_internal.h). */
void dfle_pawn_analyse(const pawn_work *w, pawn_scratch *sc, const uint32_t *mult, double *index,
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
                edges[s] = dfle_pawn_quantile_of(stat_of_counts, &ctx, N, (double)s * step);
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
