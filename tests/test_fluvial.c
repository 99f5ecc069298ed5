/* test_fluvial.c - Appendix A: the check values of doc/model.md, stream power. */
#include <math.h>
#include <string.h>

#include "dfle_test.h"
#include "dfle/fluvial.h"

static void table_g1_gives_the_check_values(void **state)
{
    dfle_stochastic_threshold_opts o;
    dfle_fluvial *fl;
    dfle_error err;
    (void)state;
    dfle_stochastic_threshold_opts_default(&o);
    assert_ok(dfle_fluvial_new_stochastic_threshold(&o, &fl, &err), &err);
    /* doc/model.md, Check values: m_s = 1.4, n_s = 2.3333, K = 2.4539e-10 (4 digits). */
    assert_close(dfle_fluvial_m(fl), 1.4, 1e-12, 0);
    assert_close(dfle_fluvial_n(fl), 7.0 / 3.0, 1e-12, 0);
    assert_close(dfle_fluvial_K(fl), 2.4539e-10, 5e-5, 0);
    /* Eq. (26) with U = 5e-4 m/yr: 0.1270 at 1 km^2, 8.015 at 1000 m^2. */
    assert_close(dfle_fluvial_steady_slope(fl, 5e-4, 1e6), 0.1270, 5e-4, 0);
    assert_close(dfle_fluvial_steady_slope(fl, 5e-4, 1e3), 8.015, 1e-4, 0);
    /* The steady slope balances uplift exactly. */
    double S = dfle_fluvial_steady_slope(fl, 5e-4, 3.7e5);
    assert_close(dfle_fluvial_rate(fl, 3.7e5, S), 5e-4, 1e-12, 0);
    dfle_fluvial_free(fl);
}

static void k_scales_linearly_with_k_e(void **state)
{
    dfle_stochastic_threshold_opts o;
    dfle_fluvial *a, *b;
    (void)state;
    dfle_stochastic_threshold_opts_default(&o);
    assert_int_equal(dfle_fluvial_new_stochastic_threshold(&o, &a, NULL), DFLE_OK);
    o.k_e *= 3;
    assert_int_equal(dfle_fluvial_new_stochastic_threshold(&o, &b, NULL), DFLE_OK);
    assert_close(dfle_fluvial_K(b), 3 * dfle_fluvial_K(a), 1e-12, 0);
    dfle_fluvial_free(a);
    dfle_fluvial_free(b);
}

static void overrides_replace_derived_values(void **state)
{
    dfle_stochastic_threshold_opts o;
    dfle_fluvial *fl;
    (void)state;
    dfle_stochastic_threshold_opts_default(&o);
    o.K_override = 1e-9;
    o.m_override = 0.5;
    o.n_override = 1.0;
    assert_int_equal(dfle_fluvial_new_stochastic_threshold(&o, &fl, NULL), DFLE_OK);
    assert_close(dfle_fluvial_K(fl), 1e-9, 0, 0);
    assert_close(dfle_fluvial_m(fl), 0.5, 0, 0);
    assert_close(dfle_fluvial_n(fl), 1.0, 0, 0);
    dfle_fluvial_free(fl);
}

static void stream_power_rate_and_reverse_slopes(void **state)
{
    dfle_fluvial *fl;
    dfle_error err;
    (void)state;
    assert_ok(dfle_fluvial_new_stream_power(2e-6, 0.5, 1.0, &fl, &err), &err);
    assert_close(dfle_fluvial_rate(fl, 1e6, 0.1), 2e-6 * 1e3 * 0.1, 1e-12, 0);
    assert_close(dfle_fluvial_rate(fl, 1e6, 0.0), 0.0, 0, 0);
    assert_close(dfle_fluvial_rate(fl, 1e6, -0.3), 0.0, 0, 0);
    assert_close(dfle_fluvial_steady_slope(fl, 1e-4, 1e6), 1e-4 / 2e-6 / 1e3, 1e-12, 0);
    dfle_fluvial_free(fl);
    assert_ok(dfle_fluvial_new_stream_power(0.0, 0.5, 1.0, &fl, &err), &err);
    assert_true(isinf(dfle_fluvial_steady_slope(fl, 1e-4, 1e6)));
    dfle_fluvial_free(fl);
}

static void bad_parameters_are_named(void **state)
{
    dfle_stochastic_threshold_opts o;
    dfle_fluvial *fl;
    dfle_error err;
    (void)state;
    assert_int_equal(dfle_fluvial_new_stream_power(-1, 0.5, 1, &fl, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "K must be >= 0");
    assert_int_equal(dfle_fluvial_new_stream_power(1, NAN, 1, &fl, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "m must be");
    assert_int_equal(dfle_fluvial_new_stream_power(1, 0.5, 0, &fl, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "n must be > 0");

    dfle_stochastic_threshold_opts_default(&o);
    o.k_e = 0;
    assert_int_equal(dfle_fluvial_new_stochastic_threshold(&o, &fl, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "k_e must be > 0");
    dfle_stochastic_threshold_opts_default(&o);
    o.omega_s = 1;
    assert_int_equal(dfle_fluvial_new_stochastic_threshold(&o, &fl, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "omega_s");
    dfle_stochastic_threshold_opts_default(&o);
    o.k = 0.01; /* k + 1 < a alpha_f (1 - omega_s) = 0.675 is fine; use a larger a */
    o.a = 3.0;  /* 3 * 0.6 * 0.75 = 1.35 > 1.01 */
    assert_int_equal(dfle_fluvial_new_stochastic_threshold(&o, &fl, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "k + 1 must exceed");
    dfle_stochastic_threshold_opts_default(&o);
    o.rho_s = 900;
    assert_int_equal(dfle_fluvial_new_stochastic_threshold(&o, &fl, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "rho_s");
}

static double param_value(const dfle_param *p, size_t n, const char *name)
{
    for (size_t i = 0; i < n; i++)
        if (strcmp(p[i].name, name) == 0)
            return p[i].value;
    fail_msg("no parameter %s", name);
    return NAN;
}

/* Table G1 and the derived K, m_s, n_s; stream power's K, m, n. */
static void params_rebuild_the_same_law(void **state)
{
    dfle_stochastic_threshold_opts o;
    dfle_fluvial *fl = NULL, *sp = NULL;
    dfle_param p[32];
    dfle_error err;
    size_t n;
    (void)state;
    dfle_stochastic_threshold_opts_default(&o);
    o.k_e = 7e-14;
    o.n_override = 2.0;
    assert_ok(dfle_fluvial_new_stochastic_threshold(&o, &fl, &err), &err);
    n = dfle_fluvial_params(fl, p, 32);
    assert_int_equal(n, 19);
    assert_close(param_value(p, n, "k_e"), 7e-14, 0, 0);
    assert_close(param_value(p, n, "rho_s"), 2600, 0, 0);
    assert_close(param_value(p, n, "K"), dfle_fluvial_K(fl), 0, 0);
    assert_close(param_value(p, n, "m_s"), dfle_fluvial_m(fl), 0, 0);
    assert_close(param_value(p, n, "n_s"), 2.0, 0, 0);
    assert_ok(dfle_fluvial_new_stream_power(1e-6, 0.5, 1, &sp, &err), &err);
    n = dfle_fluvial_params(sp, p, 32);
    assert_int_equal(n, 3);
    assert_close(param_value(p, n, "K"), 1e-6, 0, 0);
    assert_close(param_value(p, n, "m"), 0.5, 0, 0);
    assert_close(param_value(p, n, "n"), 1, 0, 0);
    dfle_fluvial_free(fl);
    dfle_fluvial_free(sp);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(table_g1_gives_the_check_values),
        cmocka_unit_test(k_scales_linearly_with_k_e),
        cmocka_unit_test(overrides_replace_derived_values),
        cmocka_unit_test(stream_power_rate_and_reverse_slopes),
        cmocka_unit_test(bad_parameters_are_named),
        cmocka_unit_test(params_rebuild_the_same_law),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
