/*
 * analytical.h - the approximate analytical steady state of Sect. 2.4.
 *
 * With fluvial erosion neglected, the empirical router, the power law
 * (Eq. 6) and Theta = 1 (tau >> tau_y), steady state gives Eq. (19):
 *
 *   S = (U / (k_df l1 l2 l3 l4))^(1/(alpha - beta/3)) A^N
 *   N = (beta/3 (b - gamma c2) + gamma (c2 - 1)) / (alpha - beta/3)   (20)
 *   l1 = M0^(c2 (beta/3 - 1) + 1)                                      (21)
 *   l2 = 10^(-6 gamma (c2 (beta/3 - 1) + 1))                           (22)
 *   l3 = c1^(beta/3 - 1)                                               (23)
 *   l4 = (3 mu / (rho_b g k_w))^(beta/3)                               (24)
 */
#ifndef DFLE_ANALYTICAL_H
#define DFLE_ANALYTICAL_H

#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_analytical_params {
    double U;                       /* uplift [m/yr]                  */
    double k_df, alpha, beta;       /* power law, Eq. (6)             */
    double M0, gamma, mu, c1, c2;   /* empirical router               */
    double rho_b, g;                /* [kg/m^3], [m/s^2]              */
    double k_w, b;                  /* width w = k_w A^b              */
} dfle_analytical_params;

/* Check that Eq. (19) is defined: positive scales, alpha != beta/3. */
int dfle_analytical_check(const dfle_analytical_params *p, dfle_error *err);

double dfle_analytical_N(const dfle_analytical_params *p);          /* Eq. (20) */
double dfle_analytical_slope(const dfle_analytical_params *p, double A); /* Eq. (19), A in m^2 */

#ifdef __cplusplus
}
#endif
#endif
