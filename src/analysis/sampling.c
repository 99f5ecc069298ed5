/*
 * sampling.c - seeded Latin hypercube designs (see dfle/sampling.h for
 * the exact algorithm, which this file must keep to the letter: designs
 * are part of a user's experiment record, and a sharded runner rebuilds
 * the same design on every machine).
 *
 * Only GSL's MT19937 word stream is taken from the library; bounded
 * integers and unit numbers are derived here so that the design does not
 * depend on how a GSL version implements gsl_rng_uniform_int.  Products
 * and sums are written as separate statements so that no compiler may
 * fuse them into an FMA, which would change last bits on some machines.
 */
#include "dfle/sampling.h"

/* No fused multiply-adds: numpy and the documented algorithms round every
 * product and sum.  GCC in ISO C mode never contracts across or within
 * expressions; clang would within one, so it is told not to. */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_rng.h>

/* ---- Generator --------------------------------------------------- */

struct dfle_rng {
    gsl_rng *r;
};

int dfle_rng_new(unsigned long seed, dfle_rng **out, dfle_error *err)
{
    dfle_rng *g;

    if (out == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "rng: output pointer is NULL");
    *out = NULL;
    if (seed > DFLE_SEED_MAX)
        return dfle_error_set(err, DFLE_EINVAL,
                              "rng: seed must be a whole number in [0, %lu] (got %lu)",
                              DFLE_SEED_MAX, seed);
    g = malloc(sizeof *g);
    if (g == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "rng: out of memory");
    g->r = gsl_rng_alloc(gsl_rng_mt19937);
    if (g->r == NULL) {
        free(g);
        return dfle_error_set(err, DFLE_ENOMEM, "rng: out of memory");
    }
    gsl_rng_set(g->r, seed);
    *out = g;
    return DFLE_OK;
}

void dfle_rng_free(dfle_rng *rng)
{
    if (rng != NULL) {
        gsl_rng_free(rng->r);
        free(rng);
    }
}

uint32_t dfle_rng_u32(dfle_rng *rng)
{
    /* MT19937's range is [0, 2^32 - 1], so the word is returned as is. */
    return (uint32_t)gsl_rng_get(rng->r);
}

uint64_t dfle_rng_below(dfle_rng *rng, uint64_t m)
{
    const uint64_t span = UINT64_C(1) << 32;
    uint64_t limit, w;

    if (m <= 1)
        return 0;
    if (m > span)
        m = span; /* documented range is m <= 2^32 */
    limit = span - span % m;
    do
        w = dfle_rng_u32(rng);
    while (w >= limit);
    return w % m;
}

double dfle_rng_uniform(dfle_rng *rng)
{
    return (double)dfle_rng_u32(rng) / 4294967296.0;
}

/* ---- Designs ----------------------------------------------------- */

struct dfle_lhs {
    size_t n, D;
    char **names;          /* D copied names                           */
    dfle_lhs_kind *kind;   /* D kinds                                  */
    double *lo, *hi;       /* D ranges                                 */
    double **values;       /* D copied value lists (NULL if not discrete) */
    size_t *nvalues;       /* D                                        */
    double *unit;          /* n x D, row-major                         */
    double *x;             /* n x D, row-major                         */
    size_t *choice;        /* n x D value indices (discrete dims)      */
};

void dfle_lhs_opts_default(dfle_lhs_opts *opts)
{
    opts->n = 100;
    opts->seed = 1;
    opts->centered = 0;
}

static const char *param_name(const dfle_lhs_param *p)
{
    return p->name != NULL ? p->name : "(unnamed)";
}

int dfle_lhs_param_check(const dfle_lhs_param *p, dfle_error *err)
{
    const char *nm;

    if (p == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "lhs: parameter description is NULL");
    nm = param_name(p);
    if (p->name == NULL || p->name[0] == '\0')
        return dfle_error_set(err, DFLE_EINVAL, "lhs: every parameter needs a non-empty name");
    switch (p->kind) {
    case DFLE_LHS_UNIFORM:
    case DFLE_LHS_LOG_UNIFORM:
        if (!isfinite(p->lo) || !isfinite(p->hi))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "lhs: parameter '%s': range bounds must be finite "
                                  "(got lo = %g, hi = %g)", nm, p->lo, p->hi);
        if (!(p->lo < p->hi))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "lhs: parameter '%s': range needs lo < hi "
                                  "(got lo = %g, hi = %g)", nm, p->lo, p->hi);
        if (p->kind == DFLE_LHS_UNIFORM && !isfinite(p->hi - p->lo))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "lhs: parameter '%s': range hi - lo overflows "
                                  "(lo = %g, hi = %g)", nm, p->lo, p->hi);
        if (p->kind == DFLE_LHS_LOG_UNIFORM && !(p->lo > 0.0))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "lhs: parameter '%s': a log-uniform range needs lo > 0 "
                                  "(got lo = %g)", nm, p->lo);
        return DFLE_OK;
    case DFLE_LHS_DISCRETE:
        if (p->values == NULL || p->nvalues == 0)
            return dfle_error_set(err, DFLE_EINVAL,
                                  "lhs: parameter '%s': a list of values needs at least one "
                                  "value", nm);
        for (size_t k = 0; k < p->nvalues; k++)
            if (!isfinite(p->values[k]))
                return dfle_error_set(err, DFLE_EINVAL,
                                      "lhs: parameter '%s': value %zu is not finite (%g)", nm,
                                      k + 1, p->values[k]);
        return DFLE_OK;
    }
    return dfle_error_set(err, DFLE_EINVAL, "lhs: parameter '%s': unknown kind %d", nm,
                          (int)p->kind);
}

void dfle_lhs_free(dfle_lhs *design)
{
    if (design == NULL)
        return;
    for (size_t d = 0; d < design->D; d++) {
        if (design->names != NULL)
            free(design->names[d]);
        if (design->values != NULL)
            free(design->values[d]);
    }
    free(design->names);
    free(design->kind);
    free(design->lo);
    free(design->hi);
    free(design->values);
    free(design->nvalues);
    free(design->unit);
    free(design->x);
    free(design->choice);
    free(design);
}

static char *copy_string(const char *s)
{
    size_t len = strlen(s) + 1;
    char *c = malloc(len);
    if (c != NULL)
        memcpy(c, s, len);
    return c;
}

/* Copy the parameter descriptions; 0 or DFLE_ENOMEM. */
static int copy_params(dfle_lhs *g, const dfle_lhs_param *params)
{
    size_t D = g->D;

    g->names = calloc(D, sizeof *g->names);
    g->kind = calloc(D, sizeof *g->kind);
    g->lo = calloc(D, sizeof *g->lo);
    g->hi = calloc(D, sizeof *g->hi);
    g->values = calloc(D, sizeof *g->values);
    g->nvalues = calloc(D, sizeof *g->nvalues);
    if (!g->names || !g->kind || !g->lo || !g->hi || !g->values || !g->nvalues)
        return DFLE_ENOMEM;
    for (size_t d = 0; d < D; d++) {
        const dfle_lhs_param *p = &params[d];
        if ((g->names[d] = copy_string(p->name)) == NULL)
            return DFLE_ENOMEM;
        g->kind[d] = p->kind;
        g->lo[d] = p->lo;
        g->hi[d] = p->hi;
        if (p->kind == DFLE_LHS_DISCRETE) {
            g->values[d] = malloc(p->nvalues * sizeof *g->values[d]);
            if (g->values[d] == NULL)
                return DFLE_ENOMEM;
            memcpy(g->values[d], p->values, p->nvalues * sizeof *g->values[d]);
            g->nvalues[d] = p->nvalues;
        }
    }
    return DFLE_OK;
}

static double clamp(double v, double lo, double hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

/* Map unit value u of dimension d to the parameter; *choice receives the
 * value index for a discrete dimension. */
static double map_unit(const dfle_lhs *g, size_t d, double u, size_t *choice)
{
    double width, step, v;

    *choice = 0;
    switch (g->kind[d]) {
    case DFLE_LHS_UNIFORM:
        width = g->hi[d] - g->lo[d];
        step = u * width;
        v = g->lo[d] + step;
        return clamp(v, g->lo[d], g->hi[d]);
    case DFLE_LHS_LOG_UNIFORM: {
        double a = log(g->lo[d]), b = log(g->hi[d]);
        width = b - a;
        step = u * width;
        v = a + step;
        return clamp(exp(v), g->lo[d], g->hi[d]);
    }
    case DFLE_LHS_DISCRETE: {
        double k = (double)g->nvalues[d];
        double f = floor(u * k);
        size_t c = f < 0.0 ? 0 : (size_t)f;
        if (c >= g->nvalues[d])
            c = g->nvalues[d] - 1;
        *choice = c;
        return g->values[d][c];
    }
    }
    return NAN;
}

/* Fill the unit design and the values, drawing from a fresh generator. */
static int fill_design(dfle_lhs *g, const dfle_lhs_opts *opts, dfle_error *err)
{
    size_t n = g->n, D = g->D;
    size_t *perm;
    dfle_rng *rng;
    int st;

    if ((st = dfle_rng_new(opts->seed, &rng, err)) != DFLE_OK)
        return st;
    perm = malloc(n * sizeof *perm);
    if (perm == NULL) {
        dfle_rng_free(rng);
        return dfle_error_set(err, DFLE_ENOMEM, "lhs: out of memory for %zu samples", n);
    }
    for (size_t d = 0; d < D; d++) {
        for (size_t i = 0; i < n; i++)
            perm[i] = i;
        for (size_t i = n - 1; i >= 1; i--) {
            size_t j = (size_t)dfle_rng_below(rng, (uint64_t)i + 1);
            size_t t = perm[i];
            perm[i] = perm[j];
            perm[j] = t;
        }
        for (size_t i = 0; i < n; i++) {
            double v = opts->centered ? 0.5 : dfle_rng_uniform(rng);
            double pos = (double)perm[i] + v;
            double u = pos / (double)n;
            g->unit[i * D + d] = u;
            g->x[i * D + d] = map_unit(g, d, u, &g->choice[i * D + d]);
        }
    }
    free(perm);
    dfle_rng_free(rng);
    return DFLE_OK;
}

int dfle_lhs_new(const dfle_lhs_opts *opts, size_t np, const dfle_lhs_param *params,
                 dfle_lhs **out, dfle_error *err)
{
    dfle_lhs *g;
    int st;

    if (out == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "lhs: output pointer is NULL");
    *out = NULL;
    if (opts == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "lhs: options are NULL");
    if (opts->n < 1 || (uint64_t)opts->n > UINT64_C(4294967295))
        return dfle_error_set(err, DFLE_EINVAL,
                              "lhs: n (number of samples) must be in [1, 4294967295] (got %zu)",
                              opts->n);
    if (opts->seed > DFLE_SEED_MAX)
        return dfle_error_set(err, DFLE_EINVAL,
                              "lhs: seed must be a whole number in [0, %lu] (got %lu)",
                              DFLE_SEED_MAX, opts->seed);
    if (np == 0 || params == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "lhs: at least one parameter is needed");
    for (size_t d = 0; d < np; d++) {
        if ((st = dfle_lhs_param_check(&params[d], err)) != DFLE_OK)
            return st;
        for (size_t e = 0; e < d; e++)
            if (strcmp(params[d].name, params[e].name) == 0)
                return dfle_error_set(err, DFLE_EINVAL, "lhs: parameter '%s' is given twice",
                                      params[d].name);
    }
    if (opts->n > SIZE_MAX / np / sizeof(double))
        return dfle_error_set(err, DFLE_ENOMEM, "lhs: %zu x %zu design is too large", opts->n,
                              np);

    g = calloc(1, sizeof *g);
    if (g == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "lhs: out of memory");
    g->n = opts->n;
    g->D = np;
    if (copy_params(g, params) != DFLE_OK) {
        dfle_lhs_free(g);
        return dfle_error_set(err, DFLE_ENOMEM, "lhs: out of memory");
    }
    g->unit = malloc(g->n * np * sizeof *g->unit);
    g->x = malloc(g->n * np * sizeof *g->x);
    g->choice = malloc(g->n * np * sizeof *g->choice);
    if (g->unit == NULL || g->x == NULL || g->choice == NULL) {
        dfle_lhs_free(g);
        return dfle_error_set(err, DFLE_ENOMEM, "lhs: out of memory for %zu x %zu samples",
                              opts->n, np);
    }
    if ((st = fill_design(g, opts, err)) != DFLE_OK) {
        dfle_lhs_free(g);
        return st;
    }
    *out = g;
    return DFLE_OK;
}

size_t dfle_lhs_n(const dfle_lhs *design)
{
    return design->n;
}

size_t dfle_lhs_dim(const dfle_lhs *design)
{
    return design->D;
}

const char *dfle_lhs_name(const dfle_lhs *design, size_t d)
{
    return d < design->D ? design->names[d] : NULL;
}

dfle_lhs_kind dfle_lhs_param_kind(const dfle_lhs *design, size_t d)
{
    return d < design->D ? design->kind[d] : DFLE_LHS_UNIFORM;
}

const double *dfle_lhs_row(const dfle_lhs *design, size_t i)
{
    return i < design->n ? design->x + i * design->D : NULL;
}

const double *dfle_lhs_unit_row(const dfle_lhs *design, size_t i)
{
    return i < design->n ? design->unit + i * design->D : NULL;
}

size_t dfle_lhs_choice(const dfle_lhs *design, size_t i, size_t d)
{
    if (i >= design->n || d >= design->D)
        return 0;
    return design->choice[i * design->D + d];
}
