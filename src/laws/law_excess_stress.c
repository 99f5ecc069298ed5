/*
 * law_excess_stress.c - the excess-shear-stress threshold law
 * E_df = k max(tau - tau_c, 0)^p; equations and sources in
 * dfle/law_excess_stress.h.
 *
 * tau comes from the router, so the whole law is the flow factor; the
 * rate only scales it by k (and honours S <= 0: no erosion).
 */
#include "dfle/law_excess_stress.h"

#include <math.h>
#include <stdlib.h>

typedef struct excess_law {
    dfle_excess_stress_law_opts opts;
} excess_law;

void dfle_excess_stress_law_opts_default(dfle_excess_stress_law_opts *o)
{
    o->k = 1e-9;
    o->tau_c = 500.0;
    o->p = 1.5;
}

static int excess_flow_factor(void *state, const dfle_law_ctx *ctx, double *F, dfle_error *err)
{
    const excess_law *el = state;
    const dfle_flow *fl = ctx->flow;
    if (fl->time_resolved)
        return dfle_error_set(err, DFLE_EINVAL,
                              "law.excess_stress: needs a bulk router that reports tau "
                              "(not a time-resolved one)");
    for (size_t i = 0; i < ctx->n; i++) {
        double excess = fl->tau[i] - el->opts.tau_c;
        /* Theta <= 0: the flow stops here and erodes nothing. */
        F[i] = excess > 0 && fl->Theta[i] > 0 ? pow(excess, el->opts.p) : 0.0;
    }
    return DFLE_OK;
}

static int excess_rate(void *state, const dfle_law_ctx *ctx, const double *F, double *E,
                       dfle_error *err)
{
    const excess_law *el = state;
    (void)err;
    for (size_t i = 0; i < ctx->n; i++)
        E[i] = ctx->S[i] > 0 ? el->opts.k * F[i] : 0.0;
    return DFLE_OK;
}

/* d E_df / d ln S.  E = k (tau - tau_c)^p moves only through tau:
 * d ln E = p tau d ln tau / (tau - tau_c), finite wherever E > 0 (for
 * p < 1 it grows without bound as tau -> tau_c, where E -> 0).  A flow
 * held fixed (d NULL) leaves E where it is: 0. */
static int excess_rate_dlnS(void *state, const dfle_law_ctx *ctx, const double *F,
                            const double *E, const dfle_flow_dlnS *d, double *dE, dfle_error *err)
{
    const excess_law *el = state;
    const dfle_flow *fl = ctx->flow;
    (void)F, (void)err;
    for (size_t i = 0; i < ctx->n; i++)
        dE[i] = E[i] == 0 || d == NULL
                    ? 0.0
                    : E[i] * el->opts.p * fl->tau[i] * d[i].tau / (fl->tau[i] - el->opts.tau_c);
    return DFLE_OK;
}

static size_t excess_params(const void *state, dfle_param *out, size_t cap)
{
    const dfle_excess_stress_law_opts *o = &((const excess_law *)state)->opts;
    const dfle_param p[] = {
        {"k", o->k, "", 0}, {"tau_c", o->tau_c, "Pa", 0}, {"p", o->p, "", 0},
    };
    return dfle_param_copy(p, sizeof p / sizeof p[0], out, cap);
}

static void excess_destroy(void *state) { free(state); }

static const dfle_law_ops excess_ops = {
    .version = DFLE_LAW_OPS_VERSION,
    .name = "excess_stress",
    .flow_factor = excess_flow_factor,
    .rate = excess_rate,
    .integrand = NULL, /* tau is not a function of (h, v, lambda) alone */
    .params = excess_params,
    .destroy = excess_destroy,
    .rate_dlnS = excess_rate_dlnS,
};

int dfle_law_new_excess_stress(const dfle_excess_stress_law_opts *o, dfle_law **out,
                               dfle_error *err)
{
    excess_law *el;

    *out = NULL;
    if (!(isfinite(o->k) && o->k > 0))
        return dfle_error_set(err, DFLE_EINVAL, "law.excess_stress: k must be > 0 (got %g)", o->k);
    if (!(isfinite(o->tau_c) && o->tau_c >= 0))
        return dfle_error_set(err, DFLE_EINVAL, "law.excess_stress: tau_c must be >= 0 Pa (got %g)",
                              o->tau_c);
    if (!(isfinite(o->p) && o->p > 0))
        return dfle_error_set(err, DFLE_EINVAL, "law.excess_stress: p must be > 0 (got %g)", o->p);
    el = malloc(sizeof *el);
    if (el == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "law.excess_stress: out of memory");
    el->opts = *o;
    return dfle_law_new(&excess_ops, el, out, err);
}

const dfle_excess_stress_law_opts *dfle_law_excess_stress_opts(const dfle_law *law)
{
    if (law == NULL || dfle_law_get_ops(law) != &excess_ops)
        return NULL;
    return &((const excess_law *)dfle_law_state(law))->opts;
}
