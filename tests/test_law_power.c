/* test_law_power.c - Eq. (6) and the flow-factor / rate split. */
#include <math.h>
#include <string.h>

#include "dfle_test.h"
#include "dfle/law_power.h"

static void rate_is_eq6(void **state)
{
    dfle_power_law_opts o = {.k_df = 2e-4, .alpha = 4.5, .beta = 1.7};
    dfle_law *law;
    dfle_flow flow;
    double S[3] = {0.5, 0.8, -0.1}, A[3] = {1, 2, 3}, w[3] = {1, 1, 1}, F[3], E[3];
    dfle_error err;
    (void)state;
    assert_ok(dfle_law_new_power(&o, &law, &err), &err);
    assert_string_equal(dfle_law_name(law), "power");
    assert_int_equal(dfle_flow_init(&flow, 3, NULL), DFLE_OK);
    for (int i = 0; i < 3; i++) {
        flow.h[i] = 0.5 + i;
        flow.t_p[i] = 20 + i;
        flow.Theta[i] = 0.25 * (i + 1);
    }
    flow.runout_end = 3;
    dfle_law_ctx ctx = {.n = 3, .S = S, .A = A, .w = w, .flow = &flow};
    assert_ok(dfle_law_flow_factor(law, &ctx, F, &err), &err);
    assert_ok(dfle_law_rate(law, &ctx, F, E, &err), &err);
    for (int i = 0; i < 2; i++)
        assert_close(E[i], 2e-4 * flow.t_p[i] * pow(S[i], 4.5) * pow(flow.h[i], 1.7) *
                               flow.Theta[i], 1e-12, 0);
    assert_close(E[2], 0.0, 0, 0); /* reverse slope: no erosion */
    /* The factor is flow-only: changing S changes E through S^alpha alone. */
    S[0] = 1.0;
    assert_ok(dfle_law_rate(law, &ctx, F, E, &err), &err);
    assert_close(E[0], 2e-4 * F[0], 1e-12, 0);
    assert_non_null(dfle_law_power_opts(law));
    assert_close(dfle_law_power_opts(law)->alpha, 4.5, 0, 0);
    dfle_flow_release(&flow);
    dfle_law_free(law);
}

static void integer_exponents_match_pow(void **state)
{
    dfle_power_law_opts o = {.k_df = 1, .alpha = 2, .beta = 0};
    dfle_law *law;
    dfle_flow flow;
    double S[1] = {0.7}, F[1], E[1];
    (void)state;
    assert_int_equal(dfle_law_new_power(&o, &law, NULL), DFLE_OK);
    assert_int_equal(dfle_flow_init(&flow, 1, NULL), DFLE_OK);
    flow.h[0] = 3.0;
    flow.t_p[0] = 1.0;
    flow.Theta[0] = 1.0;
    dfle_law_ctx ctx = {.n = 1, .S = S, .A = S, .w = S, .flow = &flow};
    assert_int_equal(dfle_law_flow_factor(law, &ctx, F, NULL), DFLE_OK);
    assert_close(F[0], 1.0, 0, 0); /* h^0 = 1 */
    assert_int_equal(dfle_law_rate(law, &ctx, F, E, NULL), DFLE_OK);
    assert_close(E[0], 0.49, 1e-15, 0);
    dfle_flow_release(&flow);
    dfle_law_free(law);
    /* Larger whole exponents go through squaring: still pow() to round-off. */
    o.alpha = 7;
    o.beta = 3;
    assert_int_equal(dfle_law_new_power(&o, &law, NULL), DFLE_OK);
    assert_int_equal(dfle_flow_init(&flow, 1, NULL), DFLE_OK);
    flow.h[0] = 1.37;
    flow.t_p[0] = 1.0;
    flow.Theta[0] = 1.0;
    assert_int_equal(dfle_law_flow_factor(law, &ctx, F, NULL), DFLE_OK);
    assert_int_equal(dfle_law_rate(law, &ctx, F, E, NULL), DFLE_OK);
    assert_close(E[0], pow(0.7, 7) * pow(1.37, 3), 1e-14, 0);
    dfle_flow_release(&flow);
    dfle_law_free(law);
}

static int dummy_factor(void *s, const dfle_law_ctx *c, double *F, dfle_error *e)
{
    (void)s, (void)c, (void)F, (void)e;
    return 0;
}

static void bad_parameters_and_ops(void **state)
{
    dfle_power_law_opts o;
    dfle_law *law = NULL;
    dfle_error err;
    static const dfle_law_ops incomplete = {
        .version = DFLE_LAW_OPS_VERSION, .name = "x", .flow_factor = dummy_factor};
    (void)state;
    dfle_power_law_opts_default(&o);
    o.k_df = 0;
    assert_int_equal(dfle_law_new_power(&o, &law, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "k_df must be > 0");
    dfle_power_law_opts_default(&o);
    o.alpha = -1;
    assert_int_equal(dfle_law_new_power(&o, &law, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "alpha");
    dfle_power_law_opts_default(&o);
    o.beta = NAN;
    assert_int_equal(dfle_law_new_power(&o, &law, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "beta");
    assert_int_equal(dfle_law_new(&incomplete, NULL, &law, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "rate()");
    assert_null(law);
    /* a table that does not say which version of law.h it was written for */
    {
        dfle_law_ops unversioned = incomplete;
        unversioned.version = 0;
        assert_int_equal(dfle_law_new(&unversioned, NULL, &law, &err), DFLE_EINVAL);
        assert_msg_contains(err.msg, "law x: ops version 0, this library knows 1 to 1");
        unversioned.version = DFLE_LAW_OPS_VERSION + 1;
        assert_int_equal(dfle_law_new(&unversioned, NULL, &law, &err), DFLE_EINVAL);
        assert_null(law);
    }
    assert_null(dfle_law_power_opts(NULL));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(rate_is_eq6),
        cmocka_unit_test(integer_exponents_match_pow),
        cmocka_unit_test(bad_parameters_and_ops),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
