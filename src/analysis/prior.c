/*
 * prior.c - prior distributions of one parameter: log density, starting
 * draws, the support in the sampler's coordinate (see dfle/prior.h).
 *
 * Log-scaled priors work in u = ln x, where a parameter that spans
 * decades (k_df, U, k_e) has a compact, roughly symmetric posterior: the
 * stretch move is then efficient and a point estimate's steps comparable
 * across parameters.
 */
#include "dfle/prior.h"

#include <math.h>
#include <stdio.h>

int dfle_prior_check(const dfle_prior *p, const char *name, dfle_error *err)
{
    if (isnan(p->lo) || isnan(p->hi) || !(p->lo < p->hi))
        return dfle_error_set(err, DFLE_EINVAL, "%s: the range needs lo < hi (got lo = %g, "
                              "hi = %g)", name, p->lo, p->hi);
    switch (p->kind) {
    case DFLE_PRIOR_UNIFORM:
        if (!(isfinite(p->lo) && isfinite(p->hi) && isfinite(p->hi - p->lo)))
            return dfle_error_set(err, DFLE_EINVAL, "%s: a uniform prior needs finite lo < hi "
                                  "(got %g, %g)", name, p->lo, p->hi);
        return DFLE_OK;
    case DFLE_PRIOR_LOG_UNIFORM:
        if (!(p->lo > 0 && isfinite(p->hi)))
            return dfle_error_set(err, DFLE_EINVAL, "%s: a log-uniform prior needs 0 < lo < hi "
                                  "< inf (got lo = %g, hi = %g)", name, p->lo, p->hi);
        return DFLE_OK;
    case DFLE_PRIOR_NORMAL:
    case DFLE_PRIOR_LOG_NORMAL:
        if (!(isfinite(p->mean) && isfinite(p->sd) && p->sd > 0))
            return dfle_error_set(err, DFLE_EINVAL, "%s: a normal prior needs a finite mean and "
                                  "sd > 0 (got mean = %g, sd = %g)", name, p->mean, p->sd);
        if (p->kind == DFLE_PRIOR_LOG_NORMAL && !(p->lo >= 0))
            return dfle_error_set(err, DFLE_EINVAL, "%s: a log-normal prior lives on x > 0; lo "
                                  "must be >= 0 (got %g)", name, p->lo);
        return DFLE_OK;
    case DFLE_PRIOR_CUSTOM:
        if (!(isfinite(p->lo) && isfinite(p->hi)))
            return dfle_error_set(err, DFLE_EINVAL, "%s: a prior given as a density needs a "
                                  "finite range {lo, hi} where it is non-zero (walkers start "
                                  "there; got %g, %g)", name, p->lo, p->hi);
        if (p->log_scale && !(p->lo > 0))
            return dfle_error_set(err, DFLE_EINVAL, "%s: a log-scaled range needs lo > 0 "
                                  "(got %g)", name, p->lo);
        return DFLE_OK;
    }
    return dfle_error_set(err, DFLE_EINVAL, "%s: unknown kind of prior (%d)", name, (int)p->kind);
}

double dfle_prior_logpdf(const dfle_prior *p, double x)
{
    double z;
    if (!(x >= p->lo && x <= p->hi))
        return -INFINITY; /* also NaN */
    switch (p->kind) {
    case DFLE_PRIOR_UNIFORM:
        return -log(p->hi - p->lo);
    case DFLE_PRIOR_LOG_UNIFORM:
        return -log(x) - log(log(p->hi / p->lo));
    case DFLE_PRIOR_NORMAL:
        z = (x - p->mean) / p->sd;
        return -0.5 * z * z - log(p->sd) - 0.9189385332046727;
    case DFLE_PRIOR_LOG_NORMAL:
        if (!(x > 0))
            return -INFINITY;
        z = (log(x) - p->mean) / p->sd;
        return -0.5 * z * z - log(p->sd) - 0.9189385332046727 - log(x);
    case DFLE_PRIOR_CUSTOM:
        return 0.0;
    }
    return -INFINITY;
}

int dfle_prior_log_scale(const dfle_prior *p)
{
    return p->kind == DFLE_PRIOR_LOG_UNIFORM || p->kind == DFLE_PRIOR_LOG_NORMAL ||
           (p->kind == DFLE_PRIOR_CUSTOM && p->log_scale);
}

void dfle_prior_bounds(const dfle_prior *p, double *lo, double *hi)
{
    if (dfle_prior_log_scale(p)) {
        *lo = p->lo > 0 ? log(p->lo) : -INFINITY;
        *hi = log(p->hi);
    } else {
        *lo = p->lo;
        *hi = p->hi;
    }
}

double dfle_prior_draw(const dfle_prior *p, dfle_stream *s)
{
    double lo, hi;
    dfle_prior_bounds(p, &lo, &hi);
    switch (p->kind) {
    case DFLE_PRIOR_UNIFORM:
        return fmin(p->hi, fmax(p->lo, p->lo + dfle_stream_uniform(s) * (p->hi - p->lo)));
    case DFLE_PRIOR_LOG_UNIFORM:
    case DFLE_PRIOR_CUSTOM: {
        double u = lo + dfle_stream_uniform(s) * (hi - lo);
        return fmin(p->hi, fmax(p->lo, dfle_prior_log_scale(p) ? exp(u) : u));
    }
    case DFLE_PRIOR_NORMAL:
    case DFLE_PRIOR_LOG_NORMAL:
        for (int k = 0; k < 10000; k++) {
            double v = p->mean + p->sd * dfle_stream_normal(s);
            if (p->kind == DFLE_PRIOR_LOG_NORMAL)
                v = exp(v);
            if (v >= p->lo && v <= p->hi)
                return v;
        }
        return NAN;
    }
    return NAN;
}

double dfle_prior_center(const dfle_prior *p)
{
    double lo, hi;
    dfle_prior_bounds(p, &lo, &hi);
    if (p->kind == DFLE_PRIOR_NORMAL || p->kind == DFLE_PRIOR_LOG_NORMAL)
        return fmin(hi, fmax(lo, p->mean));
    return 0.5 * (lo + hi);
}

double dfle_prior_width(const dfle_prior *p)
{
    double lo, hi, w;
    dfle_prior_bounds(p, &lo, &hi);
    if (p->kind == DFLE_PRIOR_NORMAL || p->kind == DFLE_PRIOR_LOG_NORMAL) {
        w = p->sd;
        if (isfinite(hi - lo) && 0.25 * (hi - lo) < w)
            w = 0.25 * (hi - lo);
        return w;
    }
    return 0.25 * (hi - lo);
}

int dfle_prior_describe(const dfle_prior *p, char *buf, size_t cap)
{
    switch (p->kind) {
    case DFLE_PRIOR_UNIFORM:
        return snprintf(buf, cap, "uniform[%.17g,%.17g]", p->lo, p->hi);
    case DFLE_PRIOR_LOG_UNIFORM:
        return snprintf(buf, cap, "log-uniform[%.17g,%.17g]", p->lo, p->hi);
    case DFLE_PRIOR_NORMAL:
        return snprintf(buf, cap, "normal(%.17g,%.17g)[%.17g,%.17g]", p->mean, p->sd, p->lo, p->hi);
    case DFLE_PRIOR_LOG_NORMAL:
        return snprintf(buf, cap, "log-normal(%.17g,%.17g)[%.17g,%.17g]", p->mean, p->sd, p->lo,
                        p->hi);
    case DFLE_PRIOR_CUSTOM:
        return snprintf(buf, cap, "density%s[%.17g,%.17g]", p->log_scale ? "-log" : "", p->lo,
                        p->hi);
    }
    return snprintf(buf, cap, "?");
}
