/*
 * invert_bounds.c - marginals held up by a prior bound.  When the data
 * want values beyond a prior's range, the posterior piles against its
 * bound and the interval there is the prior's, not the data's; when
 * they say nothing, the marginal is flat over the prior and both ends
 * are.  Either way the interval printed is not a result of the data, and
 * the user is told so beside it.
 *
 * The rule (invert_run.h, doc/inversion.md "Prior bounds"), in the
 * sampler's coordinate u (ln x for log-scaled parameters): with w the
 * width of the 95 % interval and h = w / 10, the density of the samples
 * within h of a finite bound, against their density within h/2 of the
 * median, is at least 1/4.  For a normal posterior that is a bound
 * within about 1.85 sd of the median, where it cuts away about 3 % of
 * the mass the data would put beyond it; a posterior whose 95 %
 * interval merely ends near the bound (density there about 0.15 of the
 * median's) is not flagged.  A point estimate within 1e-3 of the
 * prior's width of a bound flags it too: the least-squares fit ran into
 * the bound.
 */
#include "drive/invert_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define BAND 0.1     /* h as a fraction of the 95 % width       */
#define RATIO 0.25   /* density at the bound / at the median     */
#define ON_BOUND 1e-3 /* a point this close (of the width) sits on it */

const char *dfle_bound_name(int bound)
{
    static const char *const names[] = {"none", "lower", "upper", "both"};
    return bound >= 0 && bound <= 3 ? names[bound] : "unknown";
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Samples in [a, b] of the n sorted values. */
static size_t count_in(const double *v, size_t n, double a, double b)
{
    size_t lo = 0, hi = n, i, j;
    while (lo < hi) { /* first >= a */
        size_t mid = lo + (hi - lo) / 2;
        if (v[mid] < a)
            lo = mid + 1;
        else
            hi = mid;
    }
    i = lo;
    hi = n;
    while (lo < hi) { /* first > b */
        size_t mid = lo + (hi - lo) / 2;
        if (v[mid] <= b)
            lo = mid + 1;
        else
            hi = mid;
    }
    j = lo;
    return j - i;
}

/* The flags of parameter j from its sorted samples u (m of them) and the
 * point estimate pu (NaN: none), in the sampler's coordinate; *ratio_lo,
 * *ratio_hi the density ratios (NaN for an infinite bound). */
static int flags_of(const double *u, size_t m, double lo, double hi, double pu,
                    double *ratio_lo, double *ratio_hi, int *on_point)
{
    double q025 = dfle_quantile_sorted(u, m, 0.025), q975 = dfle_quantile_sorted(u, m, 0.975);
    double med = dfle_quantile_sorted(u, m, 0.5), h = BAND * (q975 - q025), f_med;
    double width = isfinite(lo) && isfinite(hi) ? hi - lo : q975 - q025;
    int flags = 0;

    *ratio_lo = *ratio_hi = NAN;
    *on_point = 0;
    if (isfinite(pu) && width > 0) {
        if (isfinite(lo) && pu - lo <= ON_BOUND * width)
            flags |= DFLE_BOUND_LOWER, *on_point |= DFLE_BOUND_LOWER;
        if (isfinite(hi) && hi - pu <= ON_BOUND * width)
            flags |= DFLE_BOUND_UPPER, *on_point |= DFLE_BOUND_UPPER;
    }
    if (!(h > 0))
        return flags; /* every sample the same: nothing to compare */
    f_med = (double)count_in(u, m, med - 0.5 * h, med + 0.5 * h) / h;
    if (!(f_med > 0))
        return flags;
    if (isfinite(lo)) {
        *ratio_lo = (double)count_in(u, m, lo, lo + h) / h / f_med;
        if (*ratio_lo >= RATIO)
            flags |= DFLE_BOUND_LOWER;
    }
    if (isfinite(hi)) {
        *ratio_hi = (double)count_in(u, m, hi - h, hi) / h / f_med;
        if (*ratio_hi >= RATIO)
            flags |= DFLE_BOUND_UPPER;
    }
    return flags;
}

int inv_bounds(inv_run *R)
{
    dfle_invert_result *r = R->r;
    const size_t K = r->walkers, d = r->d, m = r->nsamples;
    const double *post = r->x + (r->burn + 1) * K * d;
    double *u = malloc((m ? m : 1) * sizeof *u);
    int bad = 0;

    r->bounded = calloc(d, 1);
    if (u == NULL || r->bounded == NULL) {
        free(u);
        return -1;
    }
    for (size_t j = 0; j < d; j++) {
        const dfle_prior *p = &R->o.priors[j];
        const int lg = dfle_prior_log_scale(p);
        double lo, hi, pu = NAN, rlo, rhi;
        int f, on;
        dfle_prior_bounds(p, &lo, &hi);
        if (!isfinite(lo) && !isfinite(hi))
            continue;
        for (size_t i = 0; i < m; i++)
            u[i] = lg ? log(post[i * d + j]) : post[i * d + j];
        qsort(u, m, sizeof *u, cmp_double);
        if (R->point != NULL && isfinite(R->point[j]))
            pu = lg ? log(R->point[j]) : R->point[j];
        f = flags_of(u, m, lo, hi, pu, &rlo, &rhi, &on);
        r->bounded[j] = (unsigned char)f;
        if (f == DFLE_BOUND_BOTH && !on) {
            bad |= inv_warn(r, "%s is not learned: its posterior spreads over the whole prior "
                               "[%.4g, %.4g] (density at the bounds %.2f and %.2f of that at the "
                               "median): its interval is the prior's",
                            R->o.names[j], p->lo, p->hi, rlo, rhi);
        } else if (f != DFLE_BOUND_NONE) {
            for (int side = DFLE_BOUND_LOWER; side <= DFLE_BOUND_UPPER; side++) {
                double ratio = side == DFLE_BOUND_LOWER ? rlo : rhi;
                if (!(f & side))
                    continue;
                bad |= inv_warn(
                    r, "%s is held by its prior's %s bound (%.4g): %s%s%s; its interval ends "
                       "there because of the prior, not the data: widen the prior if %s values "
                       "are possible, else read it as tension between the model and the data",
                    R->o.names[j], dfle_bound_name(side),
                    side == DFLE_BOUND_LOWER ? p->lo : p->hi,
                    ratio >= RATIO ? "the samples pile against it" : "",
                    ratio >= RATIO && (on & side) ? " and " : "",
                    (on & side) ? "the least-squares estimate sits on it" : "",
                    side == DFLE_BOUND_LOWER ? "smaller" : "larger");
            }
        }
    }
    free(u);
    return bad;
}
