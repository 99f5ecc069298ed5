/*
 * test_error.c - the error record (dfle/error.h): a NaN reads "NaN" in
 * every message, whatever its sign bit (printf says "-nan" for 0/0 on
 * x86, which the fuzzer found in messages), and names that merely
 * contain "nan" are left as they are.
 */
#include <math.h>
#include <string.h>

#include "dfle_test.h"

#include "dfle/error.h"

static void nan_reads_nan(void **state)
{
    dfle_error err;
    volatile double zero = 0.0;
    const double nan_neg = zero / zero, nan_pos = -(zero / zero);
    (void)state;
    assert_int_equal(dfle_error_set(&err, DFLE_EINVAL, "z at node 2 is not finite (%g)", nan_neg),
                     DFLE_EINVAL);
    assert_string_equal(err.msg, "z at node 2 is not finite (NaN)");
    dfle_error_set(&err, DFLE_EINVAL, "U(t) must be > 0 m/yr (got %g at t = %g yr)", nan_pos, 1.5);
    assert_string_equal(err.msg, "U(t) must be > 0 m/yr (got NaN at t = 1.5 yr)");
    dfle_error_set(&err, DFLE_EINVAL, "S = %g, z = %f; A=%e: %g", nan_neg, nan_pos, nan_neg,
                   nan_pos);
    assert_string_equal(err.msg, "S = NaN, z = NaN; A=NaN: NaN");
    dfle_error_set(&err, DFLE_EINVAL, "did not converge (bracket [%g, %g])", 0.0, nan_neg);
    assert_string_equal(err.msg, "did not converge (bracket [0, NaN])");
    dfle_error_set(&err, DFLE_EINVAL, "inf stays: %g %g", INFINITY, -INFINITY);
    assert_string_equal(err.msg, "inf stays: inf -inf");
}

static void names_with_nan_are_kept(void **state)
{
    dfle_error err;
    (void)state;
    dfle_error_set(&err, DFLE_EIO, "cannot read '%s': %s", "nan", "banana-nan");
    assert_string_equal(err.msg, "cannot read 'nan': banana-nan");
    dfle_error_set(&err, DFLE_EIO, "parameter 'x' (nanometres) got %s", "nan_x");
    assert_string_equal(err.msg, "parameter 'x' (nanometres) got nan_x");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(nan_reads_nan),
        cmocka_unit_test(names_with_nan_are_kept),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
