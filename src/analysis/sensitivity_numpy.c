/*
 * sensitivity_numpy.c - the arithmetic numpy performs, step for step, as
 * PAWN needs it (dfle/sensitivity.h lists it): the linear quantile with
 * its two interpolation branches and numpy's pairwise summation.
 *
 * Users compare dfle's PAWN rankings with SALib's, which calls numpy, so
 * these follow numpy's rounding exactly.  Each rounding step is a
 * separate statement so that no compiler contracts a product and a sum
 * into an FMA (numpy does not; sensitivity_internal.h turns contraction
 * off).  The quantile takes its values through order_stat, so that a
 * bootstrap replicate can be read in x order without materialising it
 * (sensitivity_slices.c).
 */
#include "analysis/sensitivity_internal.h"

#include <math.h>

/* numpy's linear quantile at level q of the n values order_stat gives:
 * the arithmetic of dfle_quantile_linear, for a sorted array or for the
 * rows of a bootstrap replicate in x order (stat_of_counts). */
double dfle_pawn_quantile_of(order_stat_fn order_stat, const void *ctx, size_t n, double q)
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
    return dfle_pawn_quantile_of(stat_of_sorted, sorted, n, q);
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

int dfle_pawn_compare_doubles(const void *pa, const void *pb)
{
    double a = *(const double *)pa, b = *(const double *)pb;
    return (a > b) - (a < b);
}
