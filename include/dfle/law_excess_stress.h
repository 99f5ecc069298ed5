/*
 * law_excess_stress.h - an excess-shear-stress threshold incision law:
 *
 *   E_df = k max(tau - tau_c, 0)^p                 [m/yr]
 *
 * the form of the classic detachment-limited bedrock and cohesive-bed
 * erosion laws (e.g. Howard and Kerby 1983; Whipple and Tucker 1999,
 * JGR 104, 17661), applied to the basal shear stress tau [Pa] of the
 * routed debris flow.  tau_c [Pa] is the bed's erosion threshold.  As
 * for k_df in Eq. (6), k absorbs the debris-flow frequency and duration.
 *
 * tau already depends on the slope through the router (tau = rho_b g R_h
 * sin(atan S) for the empirical one), so the whole law is flow-dependent:
 * the cached factor is max(tau - tau_c, 0)^p and the rate multiplies it
 * by k.  It needs a bulk router that reports tau (the empirical one or a
 * Lua router); the process-based router's Eq. (11) integrand sees h, v
 * and lambda only, so this law has no integrand and that router refuses it.
 */
#ifndef DFLE_LAW_EXCESS_STRESS_H
#define DFLE_LAW_EXCESS_STRESS_H

#include "dfle/law.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_excess_stress_law_opts {
    double k;     /* erodibility [m yr^-1 Pa^-p], > 0          (1e-9) */
    double tau_c; /* erosion threshold [Pa], >= 0             (500)  */
    double p;     /* excess-stress exponent [-], > 0          (1.5)  */
} dfle_excess_stress_law_opts;

void dfle_excess_stress_law_opts_default(dfle_excess_stress_law_opts *o);

int dfle_law_new_excess_stress(const dfle_excess_stress_law_opts *opts, dfle_law **out,
                               dfle_error *err);

/* The parameters of an excess-stress law, or NULL for another kind. */
const dfle_excess_stress_law_opts *dfle_law_excess_stress_opts(const dfle_law *law);

#ifdef __cplusplus
}
#endif
#endif
