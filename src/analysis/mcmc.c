/*
 * mcmc.c - the affine-invariant ensemble sampler with the parallel
 * stretch move (see dfle/mcmc.h for the algorithm and its references;
 * written from the papers).
 *
 * Evaluation is the caller's: the sampler only proposes and accepts, so
 * that the expensive densities (a forward model each) can be spread over
 * threads by a layer that owns them, and the chain still depends on
 * nothing but the seed.
 */
#include "dfle/mcmc.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/stream.h"

struct dfle_mcmc {
    size_t d, K, half;
    uint64_t seed;
    double a;
    unsigned char *logs; /* d flags                                  */
    double *x, *lp;      /* K x d, K                                 */
    double *z, *lnu;     /* K/2: stretch factors, ln of the uniform  */
    size_t step;
    int have_state;
    int next_half;       /* 0 or 1: which half proposes next         */
    int proposed;        /* propose was called for next_half         */
};

void dfle_mcmc_opts_default(dfle_mcmc_opts *o)
{
    memset(o, 0, sizeof *o);
    o->a = 2.0;
    o->seed = 1;
}

void dfle_mcmc_free(dfle_mcmc *s)
{
    if (s == NULL)
        return;
    free(s->logs);
    free(s->x);
    free(s->lp);
    free(s->z);
    free(s->lnu);
    free(s);
}

int dfle_mcmc_new(const dfle_mcmc_opts *o, dfle_mcmc **out, dfle_error *err)
{
    dfle_mcmc *s;
    *out = NULL;
    if (o->ndim < 1 || o->ndim > 1000)
        return dfle_error_set(err, DFLE_EINVAL, "mcmc: ndim must be in 1..1000 (got %zu)",
                              o->ndim);
    /* K >= 2d: with fewer walkers than that the stretch moves span a
     * subspace and cannot reach all of parameter space. */
    if (o->nwalkers % 2 != 0 || o->nwalkers < 4 || o->nwalkers < 2 * o->ndim ||
        o->nwalkers > 1000000)
        return dfle_error_set(err, DFLE_EINVAL, "mcmc: walkers must be even, at least 4 and at "
                              "least twice the %zu parameters (got %zu)", o->ndim, o->nwalkers);
    if (!(o->a > 1 && isfinite(o->a)))
        return dfle_error_set(err, DFLE_EINVAL, "mcmc: the stretch scale a must be > 1 (got %g)",
                              o->a);
    s = calloc(1, sizeof *s);
    if (s == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "mcmc: out of memory");
    s->d = o->ndim;
    s->K = o->nwalkers;
    s->half = o->nwalkers / 2;
    s->seed = o->seed;
    s->a = o->a;
    s->logs = calloc(s->d, 1);
    s->x = calloc(s->K * s->d, sizeof *s->x);
    s->lp = calloc(s->K, sizeof *s->lp);
    s->z = calloc(s->half, sizeof *s->z);
    s->lnu = calloc(s->half, sizeof *s->lnu);
    if (s->logs == NULL || s->x == NULL || s->lp == NULL || s->z == NULL || s->lnu == NULL) {
        dfle_mcmc_free(s);
        return dfle_error_set(err, DFLE_ENOMEM, "mcmc: out of memory");
    }
    for (size_t j = 0; o->log_scale != NULL && j < s->d; j++)
        s->logs[j] = o->log_scale[j] != 0;
    *out = s;
    return DFLE_OK;
}

int dfle_mcmc_set_state(dfle_mcmc *s, size_t step, const double *x, const double *lp,
                        dfle_error *err)
{
    for (size_t k = 0; k < s->K; k++) {
        if (!(lp[k] > -INFINITY) || isnan(lp[k]))
            return dfle_error_set(err, DFLE_EINVAL, "mcmc: walker %zu starts where the density "
                                  "is zero (log density %g)", k + 1, lp[k]);
        for (size_t j = 0; j < s->d; j++) {
            double v = x[k * s->d + j];
            if (!isfinite(v) || (s->logs[j] && !(v > 0)))
                return dfle_error_set(err, DFLE_EINVAL, "mcmc: walker %zu has coordinate %zu = "
                                      "%g%s", k + 1, j + 1, v, s->logs[j] ? " (log-scaled: must "
                                      "be > 0)" : "");
        }
    }
    memcpy(s->x, x, s->K * s->d * sizeof *x);
    memcpy(s->lp, lp, s->K * sizeof *lp);
    s->step = step;
    s->have_state = 1;
    s->next_half = 0;
    s->proposed = 0;
    return DFLE_OK;
}

const double *dfle_mcmc_x(const dfle_mcmc *s) { return s->x; }
const double *dfle_mcmc_lp(const dfle_mcmc *s) { return s->lp; }
size_t dfle_mcmc_step(const dfle_mcmc *s) { return s->step; }
size_t dfle_mcmc_ndim(const dfle_mcmc *s) { return s->d; }
size_t dfle_mcmc_nwalkers(const dfle_mcmc *s) { return s->K; }

int dfle_mcmc_propose(dfle_mcmc *s, int half, double *y, dfle_error *err)
{
    const size_t d = s->d, H = s->half;
    if (!s->have_state)
        return dfle_error_set(err, DFLE_ESTATE, "mcmc: no starting ensemble set");
    if (half != s->next_half)
        return dfle_error_set(err, DFLE_ESTATE, "mcmc: half %d proposed out of turn", half);
    for (size_t i = 0; i < H; i++) {
        size_t k = (size_t)half * H + i;
        /* The partner comes from the other half, as it stands now. */
        dfle_stream st;
        size_t j;
        double r, z;
        const double *xk = s->x + k * d, *xj;
        dfle_stream_init(&st, s->seed, s->step + 1, k, 0);
        j = (size_t)(1 - half) * H + (size_t)dfle_stream_below(&st, H);
        r = dfle_stream_uniform(&st);
        z = (s->a - 1.0) * r + 1.0;
        z = z * z / s->a;
        s->z[i] = z;
        s->lnu[i] = log(dfle_stream_uniform(&st));
        xj = s->x + j * d;
        for (size_t c = 0; c < d; c++) {
            if (s->logs[c]) {
                double lj = log(xj[c]);
                y[i * d + c] = exp(lj + z * (log(xk[c]) - lj));
            } else {
                y[i * d + c] = xj[c] + z * (xk[c] - xj[c]);
            }
        }
    }
    s->proposed = 1;
    return DFLE_OK;
}

int dfle_mcmc_accept(dfle_mcmc *s, int half, const double *y, const double *lp_y,
                     unsigned char *accepted, dfle_error *err)
{
    const size_t d = s->d, H = s->half;
    if (!s->proposed || half != s->next_half)
        return dfle_error_set(err, DFLE_ESTATE, "mcmc: accept for half %d without its proposals",
                              half);
    for (size_t i = 0; i < H; i++) {
        size_t k = (size_t)half * H + i;
        double *xk = s->x + k * d, lq;
        int ok = 0;
        if (lp_y[i] > -INFINITY && !isnan(lp_y[i])) {
            lq = (double)(d - 1) * log(s->z[i]) + lp_y[i] - s->lp[k];
            for (size_t c = 0; c < d; c++)
                if (s->logs[c])
                    lq += log(y[i * d + c]) - log(xk[c]);
            ok = s->lnu[i] < lq;
        }
        if (ok) {
            memcpy(xk, y + i * d, d * sizeof *xk);
            s->lp[k] = lp_y[i];
        }
        if (accepted != NULL)
            accepted[i] = (unsigned char)ok;
    }
    s->proposed = 0;
    if (half == 1) {
        s->step++;
        s->next_half = 0;
    } else {
        s->next_half = 1;
    }
    return DFLE_OK;
}

int dfle_mcmc_run(dfle_mcmc *s, size_t nsteps, dfle_mcmc_logp_fn f, void *ud, double *chain,
                  double *lpchain, size_t *naccept, dfle_error *err)
{
    const size_t d = s->d, H = s->half;
    double *y = malloc(H * d * sizeof *y), *lpy = malloc(H * sizeof *lpy);
    unsigned char *acc = malloc(H);
    int st = DFLE_OK;

    if (y == NULL || lpy == NULL || acc == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "mcmc: out of memory");
        goto done;
    }
    for (size_t t = 0; t < nsteps; t++) {
        for (int h = 0; h < 2; h++) {
            if ((st = dfle_mcmc_propose(s, h, y, err)) != DFLE_OK ||
                (st = f(ud, H, y, lpy, err)) != DFLE_OK ||
                (st = dfle_mcmc_accept(s, h, y, lpy, acc, err)) != DFLE_OK)
                goto done;
            for (size_t i = 0; naccept != NULL && i < H; i++)
                naccept[(size_t)h * H + i] += acc[i];
        }
        if (chain != NULL)
            memcpy(chain + t * s->K * d, s->x, s->K * d * sizeof *chain);
        if (lpchain != NULL)
            memcpy(lpchain + t * s->K, s->lp, s->K * sizeof *lpchain);
    }
done:
    free(y);
    free(lpy);
    free(acc);
    return st;
}
