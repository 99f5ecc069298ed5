/*
 * law_power.c - the power family of debris-flow incision laws, Eq. (6):
 *
 *   E_df = k_df S^alpha * [t_p h^beta Theta]          [m/yr]
 *
 * The bracket depends only on the routed flow, so it is the cached flow
 * factor; the slope power is applied every landscape step.  With the
 * process-based router the bracket becomes the Eq. (11) sum of
 * h^beta Phi dt over the flow's time steps, again a flow-only quantity.
 */
#include "dfle/law_power.h"

#include <math.h>
#include <stdlib.h>

typedef struct power_law {
    dfle_power_law_opts opts;
    int alpha_int, beta_int; /* the exponent if a whole number in [0, 16], else -1 */
} power_law;

void dfle_power_law_opts_default(dfle_power_law_opts *o)
{
    o->k_df = 1e-4;
    o->alpha = 6.0;
    o->beta = 1.0;
}

/* pow() is the cost of this law (a third of a whole run); the paper's
 * favourite exponents are small whole numbers, where a few products by
 * squaring are far cheaper and as accurate (within a few ulp). */
static int small_whole(double p)
{
    return p >= 0 && p <= 16 && p == floor(p) ? (int)p : -1;
}

static double power_of(double x, double p, int whole)
{
    double r = 1.0;
    if (whole < 0)
        return pow(x, p);
    for (; whole > 0; whole >>= 1, x *= x)
        if (whole & 1)
            r *= x;
    return r;
}

static int power_flow_factor(void *state, const dfle_law_ctx *ctx, double *F,
                             dfle_error *err)
{
    const power_law *pl = state;
    const dfle_flow *fl = ctx->flow;
    (void)err;
    if (fl->time_resolved) {
        /* Eq. (11): the router has summed h^beta Phi dt already. */
        for (size_t i = 0; i < ctx->n; i++)
            F[i] = fl->integral[i];
        return DFLE_OK;
    }
    for (size_t i = 0; i < ctx->n; i++)
        F[i] = fl->t_p[i] * power_of(fl->h[i], pl->opts.beta, pl->beta_int) * fl->Theta[i];
    return DFLE_OK;
}

static int power_rate(void *state, const dfle_law_ctx *ctx, const double *F,
                      double *E, dfle_error *err)
{
    const power_law *pl = state;
    const double k_df = pl->opts.k_df, alpha = pl->opts.alpha;
    (void)err;
    for (size_t i = 0; i < ctx->n; i++) {
        double s = ctx->S[i];
        /* F = 0 (no flow, or Theta = 0) means no erosion, whatever S^alpha
         * is: never form inf * 0 at absurd trial slopes. */
        E[i] = s > 0 && F[i] != 0 ? k_df * power_of(s, alpha, pl->alpha_int) * F[i] : 0.0;
    }
    return DFLE_OK;
}

/* d E_df / d ln S.  E = k_df S^alpha F with F = t_p h^beta Theta moving
 * with the flow: d ln E = alpha + d ln t_p + beta d ln h + dTheta/Theta.
 * Where E > 0, Theta > 0 too, and E dTheta/Theta = k_df S^alpha t_p h^beta
 * dTheta stays finite as Theta -> 0.  A flow held fixed (d NULL), or the
 * Eq. (11) sum of a time-resolved one, leaves alpha E. */
static int power_rate_dlnS(void *state, const dfle_law_ctx *ctx, const double *F,
                           const double *E, const dfle_flow_dlnS *d, double *dE, dfle_error *err)
{
    const power_law *pl = state;
    const dfle_flow *fl = ctx->flow;
    const double alpha = pl->opts.alpha, beta = pl->opts.beta;
    const int bulk = d != NULL && !fl->time_resolved;
    (void)F, (void)err;
    for (size_t i = 0; i < ctx->n; i++) {
        double g = alpha;
        if (E[i] == 0) {
            dE[i] = 0.0;
            continue;
        }
        if (bulk)
            g += d[i].t_p + beta * d[i].h + d[i].Theta / fl->Theta[i];
        dE[i] = g * E[i];
    }
    return DFLE_OK;
}

static int power_integrand(void *state, double h, double v, double lambda, double *g,
                           dfle_error *err)
{
    const power_law *pl = state;
    (void)v, (void)lambda, (void)err;
    *g = power_of(h, pl->opts.beta, pl->beta_int);
    return DFLE_OK;
}

static size_t power_params(const void *state, dfle_param *out, size_t cap)
{
    const dfle_power_law_opts *o = &((const power_law *)state)->opts;
    /* k_df absorbs the debris-flow frequency: E_df in m/yr from t_p in s. */
    const dfle_param p[] = {
        {"k_df", o->k_df, "", 0}, {"alpha", o->alpha, "", 0}, {"beta", o->beta, "", 0},
    };
    return dfle_param_copy(p, sizeof p / sizeof p[0], out, cap);
}

static void power_destroy(void *state) { free(state); }

static const dfle_law_ops power_ops = {
    .version = DFLE_LAW_OPS_VERSION,
    .name = "power",
    .flow_factor = power_flow_factor,
    .rate = power_rate,
    .integrand = power_integrand,
    .params = power_params,
    .destroy = power_destroy,
    .rate_dlnS = power_rate_dlnS,
};

int dfle_law_new_power(const dfle_power_law_opts *o, dfle_law **out,
                       dfle_error *err)
{
    power_law *pl;

    *out = NULL;
    if (!(isfinite(o->k_df) && o->k_df > 0))
        return dfle_error_set(err, DFLE_EINVAL, "law.power: k_df must be > 0 (got %g)", o->k_df);
    if (!(isfinite(o->alpha) && o->alpha >= 0))
        return dfle_error_set(err, DFLE_EINVAL, "law.power: alpha must be >= 0 (got %g)",
                              o->alpha);
    if (!(isfinite(o->beta) && o->beta >= 0))
        return dfle_error_set(err, DFLE_EINVAL, "law.power: beta must be >= 0 (got %g)", o->beta);
    pl = malloc(sizeof *pl);
    if (pl == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "law.power: out of memory");
    pl->opts = *o;
    pl->alpha_int = small_whole(o->alpha);
    pl->beta_int = small_whole(o->beta);
    return dfle_law_new(&power_ops, pl, out, err);
}

const dfle_power_law_opts *dfle_law_power_opts(const dfle_law *law)
{
    if (law == NULL || dfle_law_get_ops(law) != &power_ops)
        return NULL;
    return &((const power_law *)dfle_law_state(law))->opts;
}
