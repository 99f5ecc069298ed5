/*
 * population_dist.c - distributions of the debris-flow volume factor f
 * and their quadratures (router_population.h).
 *
 * The expected erosion of a population is an integral over f of powers
 * of f (Eqs. 6, 15 and 16 make E_df a power of M where Theta = 1) and,
 * where runout matters, of a function with a step where the flows stop.
 * Each quadrature is the one exact for polynomials in the variable the
 * distribution is smooth in: ln f for the log-normal (Gauss-Hermite) and
 * the truncated power law (Gauss-Legendre, the density f^(1-b) carried
 * by the weights), f for the uniform one.  The nodes come from GSL's
 * fixed quadratures (Golub-Welsch), not from tables.
 */
#include "dfle/router_population.h"

#include <math.h>
#include <stdlib.h>

#include <gsl/gsl_integration.h>

#define SQRT2 1.41421356237309504880
#define TWO_PI 6.28318530717958647693

static int check_cutoffs(const dfle_dist *d, dfle_error *err)
{
    if (!(isfinite(d->f_min) && d->f_min > 0))
        return dfle_error_set(err, DFLE_EINVAL, "population: f_min must be > 0 (got %g)",
                              d->f_min);
    if (!(isfinite(d->f_max) && d->f_max >= d->f_min))
        return dfle_error_set(err, DFLE_EINVAL,
                              "population: f_max must be finite and >= f_min (got f_min = %g, "
                              "f_max = %g)", d->f_min, d->f_max);
    return DFLE_OK;
}

int dfle_dist_check(const dfle_dist *d, dfle_error *err)
{
    switch (d->kind) {
    case DFLE_DIST_LOGNORMAL:
        if (!(isfinite(d->sigma) && d->sigma >= 0))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "population: lognormal sigma must be >= 0 (got %g)", d->sigma);
        if (!(isfinite(d->median) && d->median > 0))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "population: lognormal median must be > 0 (got %g)", d->median);
        return DFLE_OK;
    case DFLE_DIST_POWER_LAW:
        if (!isfinite(d->b))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "population: power_law exponent b must be finite (got %g)", d->b);
        return check_cutoffs(d, err);
    case DFLE_DIST_UNIFORM:
        return check_cutoffs(d, err);
    case DFLE_DIST_TABLE: {
        double total = 0.0;
        if (d->n < 1 || d->values == NULL || d->weights == NULL)
            return dfle_error_set(err, DFLE_EINVAL, "population: a table needs at least one value");
        for (size_t i = 0; i < d->n; i++) {
            if (!(isfinite(d->values[i]) && d->values[i] > 0))
                return dfle_error_set(err, DFLE_EINVAL,
                                      "population: table value %zu must be > 0 (got %g)", i + 1,
                                      d->values[i]);
            if (!(isfinite(d->weights[i]) && d->weights[i] >= 0))
                return dfle_error_set(err, DFLE_EINVAL,
                                      "population: table weight %zu must be >= 0 (got %g)", i + 1,
                                      d->weights[i]);
            total += d->weights[i];
        }
        if (!(total > 0 && isfinite(total)))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "population: table weights must add up to a finite sum > 0 (got %g)",
                                  total);
        return DFLE_OK;
    }
    default:
        return dfle_error_set(err, DFLE_EINVAL, "population: unknown distribution kind %d",
                              d->kind);
    }
}

/* q Gauss nodes x and weights w of GSL type `type` on (a, b). */
static int gauss_nodes(const gsl_integration_fixed_type *type, size_t q, double a, double b,
                       double *x, double *w, dfle_error *err)
{
    gsl_integration_fixed_workspace *ws = gsl_integration_fixed_alloc(type, q, a, b, 0.0, 0.0);
    if (ws == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "population: no quadrature of order %zu", q);
    for (size_t i = 0; i < q; i++) {
        x[i] = gsl_integration_fixed_nodes(ws)[i];
        w[i] = gsl_integration_fixed_weights(ws)[i];
    }
    gsl_integration_fixed_free(ws);
    return DFLE_OK;
}

/* Scale weights to a sum of 1. */
static void normalise(double *w, size_t n)
{
    double total = 0.0;
    for (size_t i = 0; i < n; i++)
        total += w[i];
    for (size_t i = 0; i < n; i++)
        w[i] /= total;
}

/* Sort (f, w) pairs by f: few nodes, insertion sort. */
static void sort_pairs(double *f, double *w, size_t n)
{
    for (size_t i = 1; i < n; i++)
        for (size_t j = i; j > 0 && f[j - 1] > f[j]; j--) {
            double t = f[j];
            f[j] = f[j - 1], f[j - 1] = t;
            t = w[j];
            w[j] = w[j - 1], w[j - 1] = t;
        }
}

int dfle_dist_quadrature(const dfle_dist *d, size_t q, double *f, double *w, size_t *n_out,
                         dfle_error *err)
{
    int st;
    *n_out = 0;
    if ((st = dfle_dist_check(d, err)) != DFLE_OK)
        return st;
    if (d->kind == DFLE_DIST_TABLE) {
        for (size_t i = 0; i < d->n; i++)
            f[i] = d->values[i], w[i] = d->weights[i];
        normalise(w, d->n);
        sort_pairs(f, w, d->n);
        *n_out = d->n;
        return DFLE_OK;
    }
    if (q < 1)
        return dfle_error_set(err, DFLE_EINVAL, "population: order must be >= 1 (got %zu)", q);
    /* A distribution of zero width is one flow, exactly: one node, no
     * rounding of f through exp(log()) nor of q weights 1/q adding to 1. */
    if ((d->kind == DFLE_DIST_LOGNORMAL && d->sigma == 0) ||
        (d->kind != DFLE_DIST_LOGNORMAL && d->f_min == d->f_max)) {
        f[0] = d->kind == DFLE_DIST_LOGNORMAL ? d->median : d->f_min;
        w[0] = 1.0;
        *n_out = 1;
        return DFLE_OK;
    }
    switch (d->kind) {
    case DFLE_DIST_LOGNORMAL:
        /* Weight exp(-t^2) (a = 0, b = 1): ln f = ln median + sqrt(2) sigma t. */
        if ((st = gauss_nodes(gsl_integration_fixed_hermite, q, 0.0, 1.0, f, w, err)) != DFLE_OK)
            return st;
        for (size_t i = 0; i < q; i++)
            f[i] = d->median * exp(SQRT2 * d->sigma * f[i]);
        break;
    case DFLE_DIST_POWER_LAW: {
        /* In u = ln f the density is f^(-b) df = exp((1 - b) u) du. */
        const double lo = log(d->f_min), hi = log(d->f_max);
        if ((st = gauss_nodes(gsl_integration_fixed_legendre, q, lo, hi, f, w, err)) != DFLE_OK)
            return st;
        for (size_t i = 0; i < q; i++) {
            /* Relative to the middle of the range: no overflow for large |b|. */
            w[i] *= exp((1.0 - d->b) * (f[i] - 0.5 * (lo + hi)));
            f[i] = exp(f[i]);
        }
        break;
    }
    case DFLE_DIST_UNIFORM:
        if ((st = gauss_nodes(gsl_integration_fixed_legendre, q, d->f_min, d->f_max, f, w, err)) !=
            DFLE_OK)
            return st;
        break;
    }
    normalise(w, q);
    sort_pairs(f, w, q);
    *n_out = q;
    return DFLE_OK;
}

double dfle_dist_moment(const dfle_dist *d, double k)
{
    switch (d->kind) {
    case DFLE_DIST_LOGNORMAL:
        return exp(k * log(d->median) + 0.5 * k * k * d->sigma * d->sigma);
    case DFLE_DIST_POWER_LAW: {
        /* int f^(k-b) df / int f^(-b) df on [f_min, f_max], each as
         * (f_max^p - f_min^p) / p, or its limit ln(f_max / f_min) at p = 0. */
        const double L = log(d->f_max / d->f_min);
        double num, den, p;
        if (L == 0)
            return pow(d->f_min, k);
        p = k + 1.0 - d->b;
        num = p == 0 ? L : expm1(p * L) / p;
        p = 1.0 - d->b;
        den = p == 0 ? L : expm1(p * L) / p;
        return pow(d->f_min, k) * num / den;
    }
    case DFLE_DIST_UNIFORM:
        if (d->f_max == d->f_min)
            return pow(d->f_min, k);
        if (k == -1)
            return log(d->f_max / d->f_min) / (d->f_max - d->f_min);
        return (pow(d->f_max, k + 1) - pow(d->f_min, k + 1)) / ((k + 1) * (d->f_max - d->f_min));
    case DFLE_DIST_TABLE: {
        double s = 0.0, total = 0.0;
        for (size_t i = 0; i < d->n; i++) {
            s += d->weights[i] * pow(d->values[i], k);
            total += d->weights[i];
        }
        return s / total;
    }
    default:
        return NAN;
    }
}

double dfle_dist_draw(const dfle_dist *d, double u, double u2)
{
    switch (d->kind) {
    case DFLE_DIST_LOGNORMAL:
        return d->median * exp(d->sigma * sqrt(-2.0 * log(u)) * cos(TWO_PI * u2));
    case DFLE_DIST_POWER_LAW: {
        const double L = log(d->f_max / d->f_min), p = 1.0 - d->b;
        /* Inverse CDF in ln f: F(u) = (exp(p u) - 1) / (exp(p L) - 1). */
        if (p == 0)
            return d->f_min * exp(u * L);
        return d->f_min * exp(log1p(u * expm1(p * L)) / p);
    }
    case DFLE_DIST_UNIFORM:
        return d->f_min + u * (d->f_max - d->f_min);
    case DFLE_DIST_TABLE: {
        double total = 0.0, acc = 0.0;
        for (size_t i = 0; i < d->n; i++)
            total += d->weights[i];
        for (size_t i = 0; i < d->n; i++) {
            acc += d->weights[i];
            if (u * total < acc)
                return d->values[i];
        }
        return d->values[d->n - 1];
    }
    default:
        return NAN;
    }
}

int dfle_dist_is_point(const dfle_dist *d)
{
    switch (d->kind) {
    case DFLE_DIST_LOGNORMAL:
        return d->sigma == 0;
    case DFLE_DIST_POWER_LAW:
    case DFLE_DIST_UNIFORM:
        return d->f_min == d->f_max;
    case DFLE_DIST_TABLE:
        return d->n == 1;
    default:
        return 0;
    }
}
