/*
 * law_inertial.h - an inertial-stress debris-flow incision law after
 * Stock and Dietrich (2006):
 *
 *   E_df = k S^alpha * [t_p rho_s (D v / h)^2]          [m/yr]
 *
 * Stock and Dietrich (2006, GSA Bulletin 118, 1125-1148) argued that
 * debris flows lower bedrock by the impacts of coarse particles at the
 * flow front, so erosion scales with the inertial (Bagnold) normal stress
 * of grain collisions, sigma_i ~ rho_s D^2 (du/dz)^2, summed over the
 * flow's passage, and with the bed slope.  Here the shear rate du/dz is
 * approximated by the depth-averaged v / h, D is the representative grain
 * size and the passage time t_p is the duration of loading.  The bracket
 * is flow-only (the cached flow factor); S^alpha is applied every step.
 * With a time-resolved router the bracket becomes the Eq. (11) sum of
 * rho_s (D v / h)^2 Phi dt.  No erosion where Theta <= 0 (the flow
 * stops there).  k absorbs the debris-flow frequency, like k_df.
 */
#ifndef DFLE_LAW_INERTIAL_H
#define DFLE_LAW_INERTIAL_H

#include "dfle/law.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_inertial_law_opts {
    double k;     /* erodibility [m yr^-1 Pa^-1 s^-1 in effect], > 0 (1e-6) */
    double D;     /* grain size [m], > 0                             (0.09) */
    double rho_s; /* grain density [kg/m^3], > 0                     (2600) */
    double alpha; /* slope exponent [-], >= 0                        (1)    */
} dfle_inertial_law_opts;

void dfle_inertial_law_opts_default(dfle_inertial_law_opts *o);

int dfle_law_new_inertial(const dfle_inertial_law_opts *opts, dfle_law **out,
                          dfle_error *err);

/* The parameters of an inertial law, or NULL for another kind of law. */
const dfle_inertial_law_opts *dfle_law_inertial_opts(const dfle_law *law);

#ifdef __cplusplus
}
#endif
#endif
