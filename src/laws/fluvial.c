/*
 * fluvial.c - fluvial incision E_f = K A^m_s S^n_s (Eq. 4, Appendix A).
 *
 * The stochastic-threshold law of Lague (2014) reduces, for fixed
 * climate and hydraulic geometry, to a stream-power law whose K, m_s and
 * n_s follow from the Table G1 parameters.  So both constructors produce
 * the same object; the derivation runs once, not per node.
 */
#include "dfle/fluvial.h"

#include "dfle/param.h"

#include <math.h>
#include <stdlib.h>

struct dfle_fluvial {
    const char *name;
    double K; /* [m^(1 - 2 m) / yr] */
    double m; /* area exponent m_s  */
    double n; /* slope exponent n_s */
    int derived; /* stochastic threshold: st holds the Table G1 values */
    dfle_stochastic_threshold_opts st;
};

void dfle_stochastic_threshold_opts_default(dfle_stochastic_threshold_opts *o)
{
    o->k_e = 5e-14;
    o->rho_w = 1000.0;
    o->rho_s = 2600.0;
    o->D_eff = 0.09;
    o->b = 0.3;
    o->k_w = 0.05;
    o->a = 1.5;
    o->c = 1.0;
    o->k = 0.5;
    o->omega_s = 0.25;
    o->alpha_f = 0.6;
    o->beta_f = 0.7;
    o->R_c = 0.28;
    o->n_manning = 0.05;
    o->g = 9.81;
    o->tau_c_coef = 0.045;
    o->K_override = -1.0;
    o->m_override = -1.0;
    o->n_override = -1.0;
}

static int fluvial_alloc(const char *name, double K, double m, double n,
                         dfle_fluvial **out, dfle_error *err)
{
    dfle_fluvial *fl = malloc(sizeof *fl);
    if (fl == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "fluvial: out of memory");
    fl->name = name;
    fl->derived = 0;
    fl->K = K;
    fl->m = m;
    fl->n = n;
    *out = fl;
    return DFLE_OK;
}

#define POSITIVE(field)                                                       \
    do {                                                                      \
        if (!(isfinite(o->field) && o->field > 0))                            \
            return dfle_error_set(err, DFLE_EINVAL,                           \
                                  "fluvial.stochastic_threshold: " #field     \
                                  " must be > 0 (got %g)", o->field);         \
    } while (0)

int dfle_fluvial_new_stochastic_threshold(
    const dfle_stochastic_threshold_opts *o, dfle_fluvial **out,
    dfle_error *err)
{
    double n_s, m_s, tau_c, k_t, k_wq, aaw, k_s, K;

    *out = NULL;
    POSITIVE(k_e); POSITIVE(rho_w); POSITIVE(D_eff); POSITIVE(k_w);
    POSITIVE(a); POSITIVE(c); POSITIVE(k); POSITIVE(alpha_f);
    POSITIVE(beta_f); POSITIVE(R_c); POSITIVE(n_manning); POSITIVE(g);
    POSITIVE(tau_c_coef);
    if (!(isfinite(o->b)))
        return dfle_error_set(err, DFLE_EINVAL, "fluvial.stochastic_threshold: b must be finite");
    if (!(isfinite(o->rho_s) && o->rho_s > o->rho_w))
        return dfle_error_set(err, DFLE_EINVAL,
                              "fluvial.stochastic_threshold: rho_s must exceed rho_w = %g (got %g)",
                              o->rho_w, o->rho_s);
    if (!(isfinite(o->omega_s) && o->omega_s >= 0 && o->omega_s < 1))
        return dfle_error_set(err, DFLE_EINVAL,
                              "fluvial.stochastic_threshold: omega_s must be in [0, 1) (got %g)",
                              o->omega_s);

    /* Lague (2014): exponents of the equivalent stream-power law. */
    n_s = o->beta_f / o->alpha_f * (o->k + 1.0) / (1.0 - o->omega_s);
    m_s = (o->c - o->b) * (o->k + 1.0) / (1.0 - o->omega_s);

    /* Eq. (A2); the bracket is only defined while k + 1 > a alpha_f (1 - omega_s),
     * i.e. while the discharge distribution's tail keeps the mean erosion finite. */
    aaw = o->a * o->alpha_f * (1.0 - o->omega_s);
    if (!(o->k + 1.0 - aaw > 0))
        return dfle_error_set(err, DFLE_EINVAL,
                              "fluvial.stochastic_threshold: k + 1 must exceed "
                              "a alpha_f (1 - omega_s) = %g (got k = %g)", aaw, o->k);
    tau_c = o->tau_c_coef * o->g * (o->rho_s - o->rho_w) * o->D_eff;
    k_t = o->g * o->rho_w * pow(o->n_manning, 0.6);
    k_s = aaw * pow(k_t, n_s / o->beta_f) * pow(o->k, o->k + 1.0) / tgamma(o->k + 1.0)
          / ((o->k + 1.0) * (o->k + 1.0 - aaw))
          * pow(tau_c, o->a - n_s / o->beta_f) * o->k_e;
    /* Eq. (A1) with the hydraulic-friction exponents alpha_f, beta_f (doc/model.md, Units). */
    k_wq = pow(o->R_c, o->b / o->c) / o->k_w;
    K = k_s * pow(k_wq, -o->alpha_f * n_s / o->beta_f) * pow(o->R_c, m_s / o->c);

    if (o->K_override >= 0)
        K = o->K_override;
    if (o->m_override >= 0)
        m_s = o->m_override;
    if (o->n_override > 0)
        n_s = o->n_override;
    if (!(isfinite(K) && isfinite(m_s) && isfinite(n_s) && n_s > 0))
        return dfle_error_set(err, DFLE_EINVAL,
                              "fluvial.stochastic_threshold: parameters give K = %g, "
                              "m_s = %g, n_s = %g", K, m_s, n_s);
    if (fluvial_alloc("stochastic_threshold", K, m_s, n_s, out, err) != DFLE_OK)
        return DFLE_ENOMEM;
    (*out)->derived = 1;
    (*out)->st = *o;
    return DFLE_OK;
}

int dfle_fluvial_new_stream_power(double K, double m, double n,
                                  dfle_fluvial **out, dfle_error *err)
{
    *out = NULL;
    if (!(isfinite(K) && K >= 0))
        return dfle_error_set(err, DFLE_EINVAL, "fluvial.stream_power: K must be >= 0 (got %g)", K);
    if (!(isfinite(m) && m >= 0))
        return dfle_error_set(err, DFLE_EINVAL, "fluvial.stream_power: m must be >= 0 (got %g)", m);
    if (!(isfinite(n) && n > 0))
        return dfle_error_set(err, DFLE_EINVAL, "fluvial.stream_power: n must be > 0 (got %g)", n);
    return fluvial_alloc("stream_power", K, m, n, out, err);
}

void dfle_fluvial_free(dfle_fluvial *fl) { free(fl); }

double dfle_fluvial_K(const dfle_fluvial *fl) { return fl->K; }
double dfle_fluvial_m(const dfle_fluvial *fl) { return fl->m; }
double dfle_fluvial_n(const dfle_fluvial *fl) { return fl->n; }
const char *dfle_fluvial_name(const dfle_fluvial *fl) { return fl->name; }

double dfle_fluvial_rate(const dfle_fluvial *fl, double A, double S)
{
    if (!(S > 0))
        return 0.0;
    return fl->K * pow(A, fl->m) * pow(S, fl->n);
}

double dfle_fluvial_steady_slope(const dfle_fluvial *fl, double U, double A)
{
    if (!(fl->K > 0))
        return INFINITY;
    return pow(U / fl->K, 1.0 / fl->n) * pow(A, -fl->m / fl->n);
}

size_t dfle_fluvial_params(const dfle_fluvial *fl, dfle_param *out, size_t cap)
{
    const dfle_stochastic_threshold_opts *o = &fl->st;
    /* Table G1, then the law they give: K, m_s and n_s are what the model
     * runs, and as overrides they rebuild the same law. */
    const dfle_param st[] = {
        {"k_e", o->k_e, "m^2.5 s^2 kg^-1.5", 0},
        {"rho_w", o->rho_w, "kg/m^3", 0},
        {"rho_s", o->rho_s, "kg/m^3", 0},
        {"D_eff", o->D_eff, "m", 0},
        {"b", o->b, "", 0},
        {"k_w", o->k_w, "m^(1-2 b)", 0},
        {"a", o->a, "", 0},
        {"c", o->c, "", 0},
        {"k", o->k, "", 0},
        {"omega_s", o->omega_s, "", 0},
        {"alpha_f", o->alpha_f, "", 0},
        {"beta_f", o->beta_f, "", 0},
        {"R_c", o->R_c, "m", 0},
        {"n_manning", o->n_manning, "s m^-1/3", 0},
        {"g", o->g, "m/s^2", 0},
        {"tau_c_coef", o->tau_c_coef, "", 0},
        {"K", fl->K, "m^(1-2 m_s)/yr", 0},
        {"m_s", fl->m, "", 0},
        {"n_s", fl->n, "", 0},
    };
    const dfle_param sp[] = {
        {"K", fl->K, "m^(1-2 m)/yr", 0},
        {"m", fl->m, "", 0},
        {"n", fl->n, "", 0},
    };
    if (fl->derived)
        return dfle_param_copy(st, sizeof st / sizeof st[0], out, cap);
    return dfle_param_copy(sp, sizeof sp / sizeof sp[0], out, cap);
}
