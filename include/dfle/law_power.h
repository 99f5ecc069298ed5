/*
 * law_power.h - the power family of debris-flow incision laws, Eq. (6):
 *
 *   E_df = k_df t_p S^alpha h^beta Theta          [m/yr]
 *
 * with t_p [s], h [m] and Theta from the router.  Following doc/model.md (Units) the
 * result is read as m/yr: k_df absorbs the debris-flow frequency.
 */
#ifndef DFLE_LAW_POWER_H
#define DFLE_LAW_POWER_H

#include "dfle/law.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_power_law_opts {
    double k_df;  /* erodibility [m^(1-beta) s^-1 yr^-1 in effect], > 0 (1e-4) */
    double alpha; /* slope exponent [-], >= 0   (6) */
    double beta;  /* depth exponent [-], >= 0   (1) */
} dfle_power_law_opts;

void dfle_power_law_opts_default(dfle_power_law_opts *o);

int dfle_law_new_power(const dfle_power_law_opts *opts, dfle_law **out,
                       dfle_error *err);

/* The parameters of a power law, or NULL for another kind of law. */
const dfle_power_law_opts *dfle_law_power_opts(const dfle_law *law);

#ifdef __cplusplus
}
#endif
#endif
