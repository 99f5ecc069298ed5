/*
 * law_inertial.c - the inertial-stress incision law after Stock and
 * Dietrich (2006); equations and source in dfle/law_inertial.h.
 *
 * Split like the power law: the flow-only bracket t_p rho_s (D v/h)^2 is
 * the flow factor, evaluated after each routing; k S^alpha is applied at
 * every landscape step.
 */
#include "dfle/law_inertial.h"

#include <math.h>
#include <stdlib.h>

typedef struct inertial_law {
    dfle_inertial_law_opts opts;
} inertial_law;

void dfle_inertial_law_opts_default(dfle_inertial_law_opts *o)
{
    o->k = 1e-6;
    o->D = 0.09;
    o->rho_s = 2600.0;
    o->alpha = 1.0;
}

/* rho_s (D v / h)^2 [Pa]: the inertial stress scale. */
static double inertial_stress(const dfle_inertial_law_opts *o, double h, double v)
{
    double shear = h > 0 ? v / h : 0.0;
    double d = o->D * shear;
    return o->rho_s * d * d;
}

static int inertial_flow_factor(void *state, const dfle_law_ctx *ctx, double *F,
                                dfle_error *err)
{
    const inertial_law *il = state;
    const dfle_flow *fl = ctx->flow;
    (void)err;
    if (fl->time_resolved) {
        for (size_t i = 0; i < ctx->n; i++)
            F[i] = fl->integral[i];
        return DFLE_OK;
    }
    for (size_t i = 0; i < ctx->n; i++)
        F[i] = fl->Theta[i] > 0 ? fl->t_p[i] * inertial_stress(&il->opts, fl->h[i], fl->v[i])
                                : 0.0;
    return DFLE_OK;
}

static int inertial_rate(void *state, const dfle_law_ctx *ctx, const double *F, double *E,
                         dfle_error *err)
{
    const inertial_law *il = state;
    (void)err;
    for (size_t i = 0; i < ctx->n; i++) {
        double s = ctx->S[i];
        /* As in the power law: F = 0 means no erosion, never inf * 0. */
        E[i] = s > 0 && F[i] != 0 ? il->opts.k * pow(s, il->opts.alpha) * F[i] : 0.0;
    }
    return DFLE_OK;
}

/* d E_df / d ln S.  E = k S^alpha F with F = t_p rho_s (D v / h)^2
 * (while Theta > 0): d ln E = alpha + d ln t_p + 2 d ln v - 2 d ln h.
 * F drops to 0 where the flow stops, a jump the solvers bracket.  A flow
 * held fixed (d NULL), or a time-resolved one's Eq. (11) sum, leaves
 * alpha E. */
static int inertial_rate_dlnS(void *state, const dfle_law_ctx *ctx, const double *F,
                              const double *E, const dfle_flow_dlnS *d, double *dE,
                              dfle_error *err)
{
    const double alpha = ((const inertial_law *)state)->opts.alpha;
    const int bulk = d != NULL && !ctx->flow->time_resolved;
    (void)F, (void)err;
    for (size_t i = 0; i < ctx->n; i++) {
        double g = alpha;
        if (bulk)
            g += d[i].t_p + 2.0 * (d[i].v - d[i].h);
        dE[i] = E[i] == 0 ? 0.0 : g * E[i];
    }
    return DFLE_OK;
}

static int inertial_integrand(void *state, double h, double v, double lambda, double *g,
                              dfle_error *err)
{
    (void)lambda, (void)err;
    *g = inertial_stress(&((const inertial_law *)state)->opts, h, v);
    return DFLE_OK;
}

static size_t inertial_params(const void *state, dfle_param *out, size_t cap)
{
    const dfle_inertial_law_opts *o = &((const inertial_law *)state)->opts;
    const dfle_param p[] = {
        {"k", o->k, "", 0}, {"D", o->D, "m", 0}, {"rho_s", o->rho_s, "kg/m^3", 0},
        {"alpha", o->alpha, "", 0},
    };
    return dfle_param_copy(p, sizeof p / sizeof p[0], out, cap);
}

static void inertial_destroy(void *state) { free(state); }

static const dfle_law_ops inertial_ops = {
    .version = DFLE_LAW_OPS_VERSION,
    .name = "inertial",
    .flow_factor = inertial_flow_factor,
    .rate = inertial_rate,
    .integrand = inertial_integrand,
    .params = inertial_params,
    .destroy = inertial_destroy,
    .rate_dlnS = inertial_rate_dlnS,
};

int dfle_law_new_inertial(const dfle_inertial_law_opts *o, dfle_law **out, dfle_error *err)
{
    inertial_law *il;

    *out = NULL;
    if (!(isfinite(o->k) && o->k > 0))
        return dfle_error_set(err, DFLE_EINVAL, "law.inertial: k must be > 0 (got %g)", o->k);
    if (!(isfinite(o->D) && o->D > 0))
        return dfle_error_set(err, DFLE_EINVAL, "law.inertial: D must be > 0 m (got %g)", o->D);
    if (!(isfinite(o->rho_s) && o->rho_s > 0))
        return dfle_error_set(err, DFLE_EINVAL, "law.inertial: rho_s must be > 0 kg/m^3 (got %g)",
                              o->rho_s);
    if (!(isfinite(o->alpha) && o->alpha >= 0))
        return dfle_error_set(err, DFLE_EINVAL, "law.inertial: alpha must be >= 0 (got %g)",
                              o->alpha);
    il = malloc(sizeof *il);
    if (il == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "law.inertial: out of memory");
    il->opts = *o;
    return dfle_law_new(&inertial_ops, il, out, err);
}

const dfle_inertial_law_opts *dfle_law_inertial_opts(const dfle_law *law)
{
    if (law == NULL || dfle_law_get_ops(law) != &inertial_ops)
        return NULL;
    return &((const inertial_law *)dfle_law_state(law))->opts;
}
