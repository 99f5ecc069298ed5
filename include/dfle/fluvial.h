/*
 * fluvial.h - fluvial incision E_f = K A^m_s S^n_s  [m/yr].
 *
 * Two ways to get (K, m_s, n_s):
 *  - the stochastic-threshold stream-power law of Lague (2014) as used in
 *    McGuire et al. (2023) Appendix A, derived from the Table G1
 *    parameters (any of K, m_s, n_s may still be overridden);
 *  - a plain stream-power law with K, m, n given directly.
 * Either way the law is the same object; only its construction differs.
 */
#ifndef DFLE_FLUVIAL_H
#define DFLE_FLUVIAL_H

#include <stddef.h>
#include "dfle/error.h"
#include "dfle/param.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_fluvial dfle_fluvial;

/* Table G1 of McGuire et al. (2023) plus the instantaneous erodibility. */
typedef struct dfle_stochastic_threshold_opts {
    double k_e;     /* instantaneous fluvial erodibility [m^2.5 s^2 kg^-1.5] */
    double rho_w;   /* water density [kg/m^3]                                */
    double rho_s;   /* sediment density [kg/m^3]                             */
    double D_eff;   /* effective grain size [m]                              */
    double b;       /* width-area exponent [-]                               */
    double k_w;     /* width-area coefficient [m^(1-2b)]                     */
    double a;       /* shear-stress exponent [-]                             */
    double c;       /* mean discharge-area exponent [-]                      */
    double k;       /* discharge variability coefficient [-]                 */
    double omega_s; /* at-a-station width exponent [-]                       */
    double alpha_f; /* discharge exponent of the friction law [-]            */
    double beta_f;  /* slope exponent of the friction law [-]                */
    double R_c;     /* mean annual runoff [m]                                */
    double n_manning; /* Manning coefficient [s m^-1/3]                      */
    double g;       /* gravity [m/s^2]                                       */
    double tau_c_coef; /* critical Shields stress in tau_c = coef g drho D [-] */
    /* Overrides replace the derived value when >= 0 (n: when > 0). */
    double K_override;  /* [m^(1-2m_s)/yr]; < 0 means derive              */
    double m_override;  /* < 0 means derive                                */
    double n_override;  /* < 0 means derive                                */
} dfle_stochastic_threshold_opts;

/* Table G1 values with k_e = 5e-14; no overrides. */
void dfle_stochastic_threshold_opts_default(dfle_stochastic_threshold_opts *o);

/* Appendix A.  The result has K = 2.4539e-10, m_s = 1.4, n_s = 2.3333
 * for the defaults. */
int dfle_fluvial_new_stochastic_threshold(
    const dfle_stochastic_threshold_opts *opts, dfle_fluvial **out,
    dfle_error *err);

/* Plain stream power: K >= 0 [m^(1-2m)/yr], m >= 0, n > 0. */
int dfle_fluvial_new_stream_power(double K, double m, double n,
                                  dfle_fluvial **out, dfle_error *err);

void dfle_fluvial_free(dfle_fluvial *fl);

double dfle_fluvial_K(const dfle_fluvial *fl); /* [m^(1-2m)/yr] */
double dfle_fluvial_m(const dfle_fluvial *fl); /* area exponent m_s  */
double dfle_fluvial_n(const dfle_fluvial *fl); /* slope exponent n_s */
const char *dfle_fluvial_name(const dfle_fluvial *fl);

/* The parameters (param.h), up to cap of them; returns how many there
 * are: for "stochastic_threshold" the Table G1 values followed by the
 * K, m_s and n_s they give (overrides included), for "stream_power"
 * K, m and n.  Either list rebuilds the same law. */
size_t dfle_fluvial_params(const dfle_fluvial *fl, dfle_param *out, size_t cap);

/* E_f [m/yr] at one node; zero where S <= 0 (no erosion up a reverse
 * slope: the pit fills by uplift). */
double dfle_fluvial_rate(const dfle_fluvial *fl, double A, double S);

/* Eq. (26): the fluvial steady-state slope (U/K)^(1/n) A^(-m/n) for
 * uplift U [m/yr].  Returns +Inf when K == 0. */
double dfle_fluvial_steady_slope(const dfle_fluvial *fl, double U, double A);

#ifdef __cplusplus
}
#endif
#endif
