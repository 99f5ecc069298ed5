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
 * median's) is not flagged.  A prior may pile at its bound itself (an
 * exponential at 0; a log-uniform prior is flat in ln x), and a
 * posterior that is that prior says nothing about the bound: so the
 * share of samples within h of the bound must also clearly exceed the
 * prior's share there (twice it, and three standard errors of a share
 * counted on the effective samples more).  A point estimate within 1e-3
 * of the prior's width of a bound flags it too: the least-squares fit
 * ran into the bound.
 */
#include "drive/invert_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define BAND 0.1     /* h as a fraction of the 95 % width       */
#define RATIO 0.25   /* density at the bound / at the median     */
#define ON_BOUND 1e-3 /* a point this close (of the width) sits on it */
#define PRIOR_FACTOR 2 /* the samples' share near a bound, over the prior's */
#define GRID 2000      /* intervals of the prior's integral over its support */

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

/* ln of prior j's density in the sampler's coordinate u, up to a
 * constant (-inf where it is zero). */
static double prior_lpu(const inv_run *R, size_t j, double u)
{
    const dfle_prior *p = &R->o.priors[j];
    const int lg = dfle_prior_log_scale(p);
    double x = lg ? exp(u) : u, v = dfle_prior_logpdf(p, x);
    if (p->kind == DFLE_PRIOR_CUSTOM && R->o.custom_logpdf != NULL && v > -INFINITY)
        v += R->o.custom_logpdf(R->o.custom_ud, j, x);
    if (isnan(v))
        return -INFINITY;
    return v + (lg ? u : 0); /* dx = x du */
}

/* Simpson's sum of exp(lpu - ref) over [a, b] in n (even) intervals. */
static double prior_integral(const inv_run *R, size_t j, double a, double b, size_t n, double ref)
{
    double h = (b - a) / (double)n, sum = 0;
    for (size_t i = 0; i <= n; i++) {
        double w = i == 0 || i == n ? 1 : i % 2 ? 4 : 2, v = prior_lpu(R, j, a + h * (double)i);
        if (v > -INFINITY)
            sum += w * exp(v - ref);
    }
    return sum * h / 3;
}

/* The prior's share of its mass within h of its bounds lo and hi (in u;
 * NaN for an infinite bound, or where it cannot be told). */
static void prior_shares(const inv_run *R, size_t j, double lo, double hi, double h,
                         double *share_lo, double *share_hi)
{
    const dfle_prior *p = &R->o.priors[j];
    double a = lo, b = hi, ref = -INFINITY, total;
    *share_lo = *share_hi = NAN;
    /* an infinite end: the prior's mass lies within 12 of its widths */
    if (!isfinite(a))
        a = dfle_prior_center(p) - 12 * dfle_prior_width(p);
    if (!isfinite(b))
        b = dfle_prior_center(p) + 12 * dfle_prior_width(p);
    if (!(b > a) || !(h > 0))
        return;
    for (size_t i = 0; i <= GRID; i++)
        ref = fmax(ref, prior_lpu(R, j, a + (b - a) * (double)i / GRID));
    if (!isfinite(ref) || !((total = prior_integral(R, j, a, b, GRID, ref)) > 0))
        return;
    if (isfinite(lo))
        *share_lo = prior_integral(R, j, lo, fmin(lo + h, b), 200, ref) / total;
    if (isfinite(hi))
        *share_hi = prior_integral(R, j, fmax(hi - h, a), hi, 200, ref) / total;
}

/* Whether the samples' share near a bound clearly exceeds the prior's
 * there, for n effective samples (an unknown prior share: yes). */
static int above_prior(double share, double prior_share, double n)
{
    if (!isfinite(prior_share))
        return 1;
    return share > PRIOR_FACTOR * prior_share +
                       3 * sqrt(prior_share * (1 - prior_share) / n);
}

/* The flags of parameter j from its sorted samples u (m of them, n
 * effective) and the point estimate pu (NaN: none), in the sampler's
 * coordinate; *ratio_lo, *ratio_hi the density ratios (NaN for an
 * infinite bound); *piled: the sides flagged by the samples; *flat:
 * their density is high at both bounds, but no higher than the prior's. */
static int flags_of(const inv_run *R, size_t j, const double *u, size_t m, double n, double lo,
                    double hi, double pu, double *ratio_lo, double *ratio_hi, int *on_point,
                    int *piled, int *flat)
{
    double q025 = dfle_quantile_sorted(u, m, 0.025), q975 = dfle_quantile_sorted(u, m, 0.975);
    double med = dfle_quantile_sorted(u, m, 0.5), h = BAND * (q975 - q025), f_med;
    double width = isfinite(lo) && isfinite(hi) ? hi - lo : q975 - q025;
    int flags = 0;

    double plo, phi;
    int dense = 0;

    *ratio_lo = *ratio_hi = NAN;
    *on_point = *piled = *flat = 0;
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
    prior_shares(R, j, lo, hi, h, &plo, &phi);
    if (isfinite(lo)) {
        double share = (double)count_in(u, m, lo, lo + h) / (double)m;
        *ratio_lo = share * (double)m / h / f_med;
        if (*ratio_lo >= RATIO) {
            dense |= DFLE_BOUND_LOWER;
            if (above_prior(share, plo, n))
                *piled |= DFLE_BOUND_LOWER;
        }
    }
    if (isfinite(hi)) {
        double share = (double)count_in(u, m, hi - h, hi) / (double)m;
        *ratio_hi = share * (double)m / h / f_med;
        if (*ratio_hi >= RATIO) {
            dense |= DFLE_BOUND_UPPER;
            if (above_prior(share, phi, n))
                *piled |= DFLE_BOUND_UPPER;
        }
    }
    *flat = dense == DFLE_BOUND_BOTH && *piled == 0;
    return flags | *piled;
}

int inv_bounds(inv_run *R)
{
    dfle_invert_result *r = R->r;
    const size_t K = r->walkers, d = r->d, m = r->nsamples;
    const double *post = r->x + (r->burn + 1) * K * d;
    double *u = malloc((m ? m : 1) * sizeof *u);
    /* effective samples: the chain's, and never fewer than its walkers */
    const double neff = fmax((double)r->ess, (double)K);
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
        int f, on, piled, flat;
        dfle_prior_bounds(p, &lo, &hi);
        if (!isfinite(lo) && !isfinite(hi))
            continue;
        for (size_t i = 0; i < m; i++)
            u[i] = lg ? log(post[i * d + j]) : post[i * d + j];
        qsort(u, m, sizeof *u, cmp_double);
        if (R->point != NULL && isfinite(R->point[j]))
            pu = lg ? log(R->point[j]) : R->point[j];
        f = flags_of(R, j, u, m, neff, lo, hi, pu, &rlo, &rhi, &on, &piled, &flat);
        r->bounded[j] = (unsigned char)f;
        if (flat)
            bad |= inv_warn(r, "%s is not learned: its posterior spreads over the whole prior "
                               "[%.4g, %.4g] (density at the bounds %.2f and %.2f of that at the "
                               "median, as much as the prior's): its interval is the prior's",
                            R->o.names[j], p->lo, p->hi, rlo, rhi);
        if (f != DFLE_BOUND_NONE) {
            for (int side = DFLE_BOUND_LOWER; side <= DFLE_BOUND_UPPER; side++) {
                if (!(f & side))
                    continue;
                bad |= inv_warn(
                    r, "%s is held by its prior's %s bound (%.4g): %s%s%s; its interval ends "
                       "there because of the prior, not the data: widen the prior if %s values "
                       "are possible, else read it as tension between the model and the data",
                    R->o.names[j], dfle_bound_name(side),
                    side == DFLE_BOUND_LOWER ? p->lo : p->hi,
                    (piled & side) ? "the samples pile against it, more than the prior does" : "",
                    (piled & side) && (on & side) ? " and " : "",
                    (on & side) ? "the least-squares estimate sits on it" : "",
                    side == DFLE_BOUND_LOWER ? "smaller" : "larger");
            }
        }
    }
    free(u);
    return bad;
}
