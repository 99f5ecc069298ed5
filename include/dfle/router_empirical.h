/*
 * router_empirical.h - the empirical debris-flow router (Sect. 2.3).
 *
 * Per node, from drainage area A [m^2], width w [m] and slope S:
 *   M   = M0 (1e-6 A)^gamma                    volume [m^3]         (Santi & Morandi 2013)
 *   Q   = c1 M^c2                              peak discharge [m^3/s] (Eq. 12, Rickenmann 1999)
 *   h   = (3 mu Q / (rho_b g S w))^(1/3)       depth [m]            (Eq. 14)
 *   v   = Q / (w h)                            velocity [m/s]       (Eq. 13)
 *   t_p = M / Q                                passage time [s]     (Eq. 16)
 *   tau = rho_b g R_h sin(theta), R_h = w h/(w + 2h), theta = atan S
 *   Theta = 1 - tau_y / tau                                         (Eq. 17)
 * The flow starts at the head and stops at the first node, going
 * downstream, where tau < tau_y (or S <= 0); it reaches no node beyond.
 */
#ifndef DFLE_ROUTER_EMPIRICAL_H
#define DFLE_ROUTER_EMPIRICAL_H

#include "dfle/router.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_empirical_opts {
    double M0;    /* volume-area coefficient [m^(3-2 gamma)], > 0  (3000) */
    double gamma; /* volume-area exponent [-], >= 0                (0.5)  */
    double mu;    /* dynamic viscosity [Pa s], > 0                 (500)  */
    double tau_y; /* yield strength [Pa], >= 0                     (300)  */
    double c1;    /* discharge coefficient [-], > 0                (0.135)*/
    double c2;    /* discharge exponent [-], > 0                   (0.78) */
    double rho_b; /* bulk density [kg/m^3], > 0                    (1800) */
    double g;     /* gravity [m/s^2], > 0                          (9.81) */
} dfle_empirical_opts;

/* Fig. 9 defaults of McGuire et al. (2023), listed above. */
void dfle_empirical_opts_default(dfle_empirical_opts *o);

int dfle_router_new_empirical(const dfle_empirical_opts *opts,
                              dfle_router **out, dfle_error *err);

/* The parameters of an empirical router, or NULL for another kind. */
const dfle_empirical_opts *dfle_router_empirical_opts(const dfle_router *rt);

#ifdef __cplusplus
}
#endif
#endif
