/*
 * test_plausible.c - warnings for values that run but are almost surely
 * a unit mistake (dfle/plausible.h).
 */
#include <string.h>

#include "dfle_test.h"

#include "dfle/plausible.h"

static char msg[400];

/* U = 0.5 meant as mm/yr: named, with the value to write. */
static void test_uplift_in_mm(void **state)
{
    (void)state;
    assert_int_equal(dfle_plausible_check("U", 0.5, msg, sizeof msg), 1);
    assert_msg_contains(msg, "U = 0.5 m/yr is far above rock-uplift rates");
    assert_msg_contains(msg, "if you meant 0.5 mm/yr, write U = 0.0005");
    /* The paper's range and no uplift at all are fine. */
    assert_int_equal(dfle_plausible_check("U", 1e-4, msg, sizeof msg), 0);
    assert_int_equal(dfle_plausible_check("U", 1e-3, msg, sizeof msg), 0);
    assert_int_equal(dfle_plausible_check("U", 0, msg, sizeof msg), 0);
    /* Far below: the range, but no conversion that would land in it. */
    assert_int_equal(dfle_plausible_check("U", 1e-9, msg, sizeof msg), 1);
    assert_msg_contains(msg, "far below rock-uplift rates");
    assert_null(strstr(msg, "if you meant"));
}

/* Each unit the table knows to be confused converts into its range. */
static void test_unit_mistakes(void **state)
{
    (void)state;
    assert_int_equal(dfle_plausible_check("A_max", 8, msg, sizeof msg), 1);
    assert_msg_contains(msg, "if you meant 8 km^2, write A_max = 8e+06");
    assert_int_equal(dfle_plausible_check("A_max", 8e6, msg, sizeof msg), 0);
    assert_int_equal(dfle_plausible_check("tau_y", 0.3, msg, sizeof msg), 1);
    assert_msg_contains(msg, "if you meant 0.3 kPa, write tau_y = 300");
    assert_int_equal(dfle_plausible_check("rho_b", 1.8, msg, sizeof msg), 1);
    assert_msg_contains(msg, "if you meant 1.8 g/cm^3, write rho_b = 1800");
    assert_int_equal(dfle_plausible_check("length", 2, msg, sizeof msg), 1);
    assert_msg_contains(msg, "write length = 2000");
    assert_int_equal(dfle_plausible_check("D_eff", 90, msg, sizeof msg), 1);
    assert_msg_contains(msg, "if you meant 90 mm, write D_eff = 0.09");
    /* No unit fits: the range alone. */
    assert_int_equal(dfle_plausible_check("M0", 1e9, msg, sizeof msg), 1);
    assert_msg_contains(msg, "M0 = 1e+09 m^3 is far above debris-flow volumes");
    assert_msg_contains(msg, "(M0 is in m^3)");
    /* Table G5's ranges are all plausible. */
    assert_int_equal(dfle_plausible_check("M0", 1000, msg, sizeof msg), 0);
    assert_int_equal(dfle_plausible_check("M0", 5000, msg, sizeof msg), 0);
    assert_int_equal(dfle_plausible_check("mu", 100, msg, sizeof msg), 0);
    assert_int_equal(dfle_plausible_check("tau_y", 600, msg, sizeof msg), 0);
}

/* Names the table does not know, and values the constructors refuse
 * (negative, non-finite), are not its business. */
static void test_not_judged(void **state)
{
    (void)state;
    assert_int_equal(dfle_plausible_check("alpha", 1e9, msg, sizeof msg), 0);
    assert_int_equal(dfle_plausible_check("U", -1, msg, sizeof msg), 0);
    assert_int_equal(dfle_plausible_check("U", INFINITY, msg, sizeof msg), 0);
    assert_int_equal(dfle_plausible_check("U", NAN, msg, sizeof msg), 0);
}

/* k_df: Tables G2-G5 (3e-5 to 1e-3) are plausible, 100 is not, and no
 * unit converts it into the range. */
static void test_debris_flow_erodibility(void **state)
{
    (void)state;
    assert_int_equal(dfle_plausible_check("k_df", 1e-4, msg, sizeof msg), 0);
    assert_int_equal(dfle_plausible_check("k_df", 3e-5, msg, sizeof msg), 0);
    assert_int_equal(dfle_plausible_check("k_df", 1e-3, msg, sizeof msg), 0);
    assert_int_equal(dfle_plausible_check("k_df", 100, msg, sizeof msg), 1);
    assert_msg_contains(msg, "k_df = 100");
    assert_msg_contains(msg, "far above debris-flow erodibilities");
    assert_null(strstr(msg, "if you meant"));
    assert_int_equal(dfle_plausible_check("k_df", 1e-9, msg, sizeof msg), 1);
    assert_msg_contains(msg, "far below");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_uplift_in_mm),
        cmocka_unit_test(test_unit_mistakes),
        cmocka_unit_test(test_not_judged),
        cmocka_unit_test(test_debris_flow_erodibility),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
