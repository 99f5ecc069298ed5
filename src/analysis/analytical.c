/*
 * analytical.c - Eqs. (19)-(24): the steady-state slope of a reach shaped
 * by debris flows alone (empirical router, power law, Theta = 1).
 *
 * It is the project's main check on the numerics: a run with fluvial
 * erosion off and tau_y = 0 must reproduce it node by node.
 */
#include "dfle/analytical.h"

#include <math.h>
#include <stddef.h>

int dfle_analytical_check(const dfle_analytical_params *p, dfle_error *err)
{
    const struct { const char *name; double v; } positive[] = {
        {"U", p->U}, {"k_df", p->k_df}, {"M0", p->M0}, {"mu", p->mu},
        {"c1", p->c1}, {"c2", p->c2}, {"rho_b", p->rho_b}, {"g", p->g},
        {"k_w", p->k_w},
    };
    for (size_t i = 0; i < sizeof positive / sizeof positive[0]; i++)
        if (!(isfinite(positive[i].v) && positive[i].v > 0))
            return dfle_error_set(err, DFLE_EINVAL, "analytical_slope: %s must be > 0 (got %g)",
                                  positive[i].name, positive[i].v);
    if (!(isfinite(p->alpha) && isfinite(p->beta) && isfinite(p->gamma) && isfinite(p->b)))
        return dfle_error_set(err, DFLE_EINVAL,
                              "analytical_slope: alpha, beta, gamma and b must be finite");
    /* At alpha = beta/3 erosion no longer depends on slope (h ~ S^-1/3
     * cancels S^alpha): no slope balances uplift. */
    if (fabs(p->alpha - p->beta / 3.0) < 1e-12)
        return dfle_error_set(err, DFLE_EINVAL,
                              "analytical_slope: undefined for alpha = beta/3 (alpha = %g, beta = %g)",
                              p->alpha, p->beta);
    return DFLE_OK;
}

double dfle_analytical_N(const dfle_analytical_params *p)
{
    double b3 = p->beta / 3.0;
    return (b3 * (p->b - p->gamma * p->c2) + p->gamma * (p->c2 - 1.0)) / (p->alpha - b3);
}

double dfle_analytical_slope(const dfle_analytical_params *p, double A)
{
    double b3 = p->beta / 3.0;
    double e = p->c2 * (b3 - 1.0) + 1.0;
    double l1 = pow(p->M0, e);
    double l2 = pow(10.0, -6.0 * p->gamma * e);
    double l3 = pow(p->c1, b3 - 1.0);
    double l4 = pow(3.0 * p->mu / (p->rho_b * p->g * p->k_w), b3);
    return pow(p->U / (p->k_df * l1 * l2 * l3 * l4), 1.0 / (p->alpha - b3))
           * pow(A, dfle_analytical_N(p));
}
