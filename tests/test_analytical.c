/* test_analytical.c - Eqs. (19)-(24) against the check values of doc/model.md. */
#include <math.h>
#include <string.h>

#include "dfle_test.h"
#include "dfle/analytical.h"

static dfle_analytical_params notes_case(void)
{
    dfle_analytical_params p = {
        .U = 5e-4, .k_df = 1e-4, .alpha = 6, .beta = 1, .M0 = 3000, .gamma = 0.5,
        .mu = 500, .c1 = 0.135, .c2 = 0.78, .rho_b = 1800, .g = 9.81, .k_w = 0.05, .b = 0.3,
    };
    return p;
}

static void notes_check_values(void **state)
{
    dfle_analytical_params p = notes_case();
    (void)state;
    assert_ok(dfle_analytical_check(&p, NULL), &(dfle_error){0});
    assert_close(dfle_analytical_N(&p), -0.024706, 2e-5, 0);
    assert_close(dfle_analytical_slope(&p, 1e4), 0.73834, 1e-5, 0);
}

static void slope_is_a_power_law_in_area(void **state)
{
    dfle_analytical_params p = notes_case();
    (void)state;
    double N = dfle_analytical_N(&p);
    assert_close(dfle_analytical_slope(&p, 8e6) / dfle_analytical_slope(&p, 1e3),
                 pow(8e3, N), 1e-12, 0);
    /* gamma = 0: only widening thins the flow, so slope grows with area
     * (N = beta/3 b / (alpha - beta/3) > 0, Sect. 2.4). */
    p.gamma = 0;
    assert_close(dfle_analytical_N(&p), (1.0 / 3.0) * 0.3 / (6 - 1.0 / 3.0), 1e-12, 0);
}

static void doubling_uplift_scales_slope(void **state)
{
    dfle_analytical_params p = notes_case();
    (void)state;
    double S1 = dfle_analytical_slope(&p, 1e5);
    p.U *= 2;
    assert_close(dfle_analytical_slope(&p, 1e5) / S1, pow(2.0, 1.0 / (6 - 1.0 / 3.0)), 1e-12, 0);
}

static void undefined_cases_are_rejected(void **state)
{
    dfle_analytical_params p = notes_case();
    dfle_error err;
    (void)state;
    p.alpha = 1.0 / 3.0;
    assert_int_equal(dfle_analytical_check(&p, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "alpha = beta/3");
    p = notes_case();
    p.mu = 0;
    assert_int_equal(dfle_analytical_check(&p, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "mu must be > 0");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(notes_check_values),
        cmocka_unit_test(slope_is_a_power_law_in_area),
        cmocka_unit_test(doubling_uplift_scales_slope),
        cmocka_unit_test(undefined_cases_are_rejected),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
