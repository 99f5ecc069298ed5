/*
 * sensitivity.c - PAWN indices on given data, bit-compatible with SALib's
 * pawn.analyze, and their bootstrap confidence intervals: the entry
 * point (dfle_pawn), its checks of the arguments and data, the result.
 *
 * Users compare dfle's rankings with SALib's, so every step follows the
 * arithmetic numpy and scipy perform (dfle/sensitivity.h lists it): the
 * linear quantile with its two interpolation branches, half-open slices,
 * the KS statistic as scipy's exact fraction h / lcm, numpy's pairwise
 * summation for the mean and the variance.  Each rounding step is a
 * separate statement so that no compiler contracts a product and a sum
 * into an FMA (numpy does not).
 *
 * The work is in the files sensitivity_internal.h lists: numpy's
 * arithmetic (sensitivity_numpy.c), the sorted orders and scratch of a
 * table (sensitivity_work.c), one analysis with row multiplicities
 * (sensitivity_slices.c) and the bootstrap's replicates on threads
 * (sensitivity_bootstrap.c).
 */
#include "analysis/sensitivity_internal.h"

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
    opts->threads = 1;
    opts->per_slice = 0;
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
    if (dfle_pawn_work_init(&w, N, D, S, x, y) != DFLE_OK) {
        dfle_pawn_release(out);
        return dfle_error_set(err, DFLE_ENOMEM, "pawn: out of memory for %zu rows", N);
    }
    w.per_slice = opts->per_slice;
    if (dfle_pawn_scratch_init(&sc, N, S) != DFLE_OK) {
        dfle_pawn_work_free(&w);
        dfle_pawn_release(out);
        return dfle_error_set(err, DFLE_ENOMEM, "pawn: out of memory for %zu rows", N);
    }
    dfle_pawn_scratch_set_mult(&sc, &w, NULL);
    dfle_pawn_analyse(&w, &sc, NULL, out->index, out->edges, out->ks, out->count, out->ks_h,
                      out->ks_lcm);
    dfle_pawn_scratch_free(&sc);
    if (opts->bootstrap > 0) {
        out->bootstrap = opts->bootstrap;
        if ((st = dfle_pawn_bootstrap(&w, opts, out, err)) != DFLE_OK) {
            dfle_pawn_work_free(&w);
            dfle_pawn_release(out);
            return st;
        }
    }
    dfle_pawn_work_free(&w);
    return DFLE_OK;
}
