/*
 * prior.h - prior distributions of one model parameter, for inversion.
 *
 * A prior gives the log density of a value (up to a constant shared by
 * all values: only differences matter to a sampler) and draws starting
 * points.  Kinds:
 *
 *   UNIFORM      on [lo, hi]                        log p = -ln(hi - lo)
 *   LOG_UNIFORM  uniform in ln x on [lo, hi], lo > 0 log p = -ln x - ln ln(hi/lo)
 *   NORMAL       N(mean, sd), truncated to [lo, hi] (lo, hi may be -inf, inf)
 *   LOG_NORMAL   ln x ~ N(mean, sd), truncated to [lo, hi], lo >= 0
 *   CUSTOM       a density the caller evaluates (the Lua binding calls a
 *                Lua function); here only its support [lo, hi], finite,
 *                in which starting points are drawn uniformly (in ln x
 *                when log_scale is set)
 *
 * Densities are with respect to x itself (not ln x), so a log-uniform
 * prior is p(x) ~ 1/x.  Log-scaled kinds (LOG_UNIFORM, LOG_NORMAL, and
 * CUSTOM with log_scale) are sampled in ln x by the sampler (mcmc.h),
 * which accounts for the change of variable itself.  A truncated normal's
 * density is not renormalised: the constant does not depend on x.
 */
#ifndef DFLE_PRIOR_H
#define DFLE_PRIOR_H

#include "dfle/error.h"
#include "dfle/stream.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum dfle_prior_kind {
    DFLE_PRIOR_UNIFORM,
    DFLE_PRIOR_LOG_UNIFORM,
    DFLE_PRIOR_NORMAL,
    DFLE_PRIOR_LOG_NORMAL,
    DFLE_PRIOR_CUSTOM
} dfle_prior_kind;

typedef struct dfle_prior {
    dfle_prior_kind kind;
    double lo, hi;    /* support, in the parameter's units            */
    double mean, sd;  /* NORMAL: of x; LOG_NORMAL: of ln x (sd > 0)   */
    int log_scale;    /* CUSTOM only: sample and start in ln x        */
} dfle_prior;

/* Check the numbers of a prior; the message starts with `name`. */
int dfle_prior_check(const dfle_prior *p, const char *name, dfle_error *err);

/* ln p(x) up to a constant; -inf outside the support.  CUSTOM gives 0
 * inside its support (the caller adds its own density). */
double dfle_prior_logpdf(const dfle_prior *p, double x);

/* Whether the sampler works in ln x for this prior. */
int dfle_prior_log_scale(const dfle_prior *p);

/* A starting point drawn from the prior (CUSTOM: uniform on the support,
 * in ln x when log-scaled).  A normal truncated far into its tail is
 * drawn by rejection, at most 10000 times; NaN if that fails. */
double dfle_prior_draw(const dfle_prior *p, dfle_stream *s);

/* A central value (start of a point estimate) and a typical width, both
 * in the sampler's coordinate (ln x when log-scaled): the middle and a
 * quarter of a bounded support, the mean and one sd of a normal. */
double dfle_prior_center(const dfle_prior *p);
double dfle_prior_width(const dfle_prior *p);

/* The support in the sampler's coordinate (ln lo, ln hi when log-scaled). */
void dfle_prior_bounds(const dfle_prior *p, double *lo, double *hi);

/* Short text of a prior, e.g. "log-uniform[0.0001,0.001]" (for file
 * headers: every number with 17 significant digits).  Returns the length
 * snprintf would write. */
int dfle_prior_describe(const dfle_prior *p, char *buf, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
