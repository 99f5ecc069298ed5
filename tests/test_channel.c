/* test_channel.c - the channel grid: Hack-law geometry, lengths, errors. */
#include <math.h>
#include <string.h>

#include "dfle_test.h"
#include "dfle/channel.h"

static void default_grid_reaches_8_km2_near_2010_m(void **state)
{
    dfle_channel_opts o;
    dfle_channel *ch;
    dfle_error err;
    (void)state;
    dfle_channel_opts_default(&o);
    assert_ok(dfle_channel_new(&o, &ch, &err), &err);
    size_t n = dfle_channel_size(ch);
    const double *x = dfle_channel_x(ch), *A = dfle_channel_A(ch), *w = dfle_channel_w(ch);
    /* x_out = ((8e6 - 1000)/25)^(3/5) = 2009.4 m: 402 intervals of 5 m. */
    assert_int_equal(n, 403);
    assert_close(x[0], 0.0, 0, 0);
    assert_close(x[n - 1], 2010.0, 1e-12, 0);
    assert_close(A[0], 1000.0, 1e-12, 0);
    assert_true(A[n - 1] >= 8e6);
    assert_true(A[n - 2] < 8e6);
    for (size_t i = 0; i < n; i += 37) {
        assert_close(A[i], 1000.0 + 25.0 * pow(5.0 * (double)i, 5.0 / 3.0), 1e-12, 0);
        assert_close(w[i], 0.05 * pow(A[i], 0.3), 1e-12, 0);
    }
    dfle_channel_free(ch);
}

static void length_option_sets_the_domain(void **state)
{
    dfle_channel_opts o;
    dfle_channel *ch;
    dfle_error err;
    (void)state;
    dfle_channel_opts_default(&o);
    o.length = 100;
    o.dx = 5;
    assert_ok(dfle_channel_new(&o, &ch, &err), &err);
    assert_int_equal(dfle_channel_size(ch), 21);
    assert_close(dfle_channel_x(ch)[20], 100.0, 1e-12, 0);
    dfle_channel_free(ch);
}

static void expect_error(dfle_channel_opts *o, const char *needle)
{
    dfle_channel *ch = (dfle_channel *)0x1;
    dfle_error err;
    assert_int_equal(dfle_channel_new(o, &ch, &err), DFLE_EINVAL);
    assert_null(ch);
    assert_msg_contains(err.msg, needle);
}

static void bad_parameters_are_named(void **state)
{
    dfle_channel_opts o;
    (void)state;
    dfle_channel_opts_default(&o);
    o.dx = 0;
    expect_error(&o, "dx must be > 0");
    dfle_channel_opts_default(&o);
    o.dx = NAN;
    expect_error(&o, "dx");
    dfle_channel_opts_default(&o);
    o.A_max = 500;
    expect_error(&o, "A_max must be > A0");
    dfle_channel_opts_default(&o);
    o.k_w = -1;
    expect_error(&o, "k_w");
    dfle_channel_opts_default(&o);
    o.length = 4;
    o.dx = 5;
    expect_error(&o, "fewer than 3 nodes");
    dfle_channel_opts_default(&o);
    o.dx = 1e-9;
    expect_error(&o, "nodes");
    dfle_channel_opts_default(&o);
    o.b = 80; /* (8e6)^80 overflows: caught at construction, not as NaN later */
    expect_error(&o, "not finite and positive");
}

static void arrays_are_validated_and_copied(void **state)
{
    double A[4] = {100, 200, 300, 400}, w[4] = {1, 1, 1, 1};
    dfle_channel *ch;
    dfle_error err;
    (void)state;
    assert_ok(dfle_channel_new_from_arrays(4, 10.0, A, w, &ch, &err), &err);
    A[0] = -5; /* the channel keeps its own copy */
    assert_close(dfle_channel_A(ch)[0], 100.0, 0, 0);
    assert_close(dfle_channel_x(ch)[3], 30.0, 1e-12, 0);
    dfle_channel_free(ch);

    A[0] = 100;
    A[2] = 150;
    assert_int_equal(dfle_channel_new_from_arrays(4, 10.0, A, w, &ch, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "must not decrease");
    A[2] = 300;
    w[1] = 0;
    assert_int_equal(dfle_channel_new_from_arrays(4, 10.0, A, w, &ch, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "w at node 2");
}

static void ids_are_unique(void **state)
{
    dfle_channel_opts o;
    dfle_channel *a, *b;
    (void)state;
    dfle_channel_opts_default(&o);
    assert_int_equal(dfle_channel_new(&o, &a, NULL), DFLE_OK);
    assert_int_equal(dfle_channel_new(&o, &b, NULL), DFLE_OK);
    assert_true(dfle_channel_id(a) != 0);
    assert_true(dfle_channel_id(a) != dfle_channel_id(b));
    dfle_channel_free(a);
    dfle_channel_free(b);
    dfle_channel_free(NULL);
}

/* A Hack channel lists the options as given (A_max as asked), and they
 * rebuild the same channel; a channel from arrays lists dx only. */
static void params_list_the_options_given(void **state)
{
    dfle_channel_opts o;
    dfle_channel *ch = NULL, *again = NULL, *arr = NULL;
    dfle_param p[16];
    dfle_error err;
    const double A[3] = {1e3, 2e3, 3e3}, w[3] = {1, 1, 1};
    (void)state;
    dfle_channel_opts_default(&o);
    o.dx = 10;
    o.A_max = 3e6;
    o.b = 0.4;
    assert_ok(dfle_channel_new(&o, &ch, &err), &err);
    assert_int_equal(dfle_channel_params(ch, NULL, 0), 8);
    assert_int_equal(dfle_channel_params(ch, p, 2), 8); /* writes 2, says 8 */
    assert_int_equal(dfle_channel_params(ch, p, 16), 8);
    assert_string_equal(p[0].name, "dx");
    assert_close(p[0].value, 10, 0, 0);
    assert_string_equal(p[0].unit, "m");
    assert_string_equal(p[6].name, "A_max");
    assert_close(p[6].value, 3e6, 0, 0);
    assert_true(dfle_channel_A(ch)[dfle_channel_size(ch) - 1] > 3e6);
    assert_string_equal(dfle_channel_kind(ch), "hack");
    dfle_channel_opts_default(&o);
    o.dx = p[0].value, o.A0 = p[1].value, o.hack_coef = p[2].value, o.hack_exp = p[3].value;
    o.k_w = p[4].value, o.b = p[5].value, o.A_max = p[6].value, o.length = p[7].value;
    assert_ok(dfle_channel_new(&o, &again, &err), &err);
    assert_int_equal(dfle_channel_size(again), dfle_channel_size(ch));
    assert_close(dfle_channel_w(again)[5], dfle_channel_w(ch)[5], 0, 0);
    assert_ok(dfle_channel_new_from_arrays(3, 7, A, w, &arr, &err), &err);
    assert_string_equal(dfle_channel_kind(arr), "arrays");
    assert_int_equal(dfle_channel_params(arr, p, 16), 1);
    assert_close(p[0].value, 7, 0, 0);
    dfle_channel_free(ch);
    dfle_channel_free(again);
    dfle_channel_free(arr);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(default_grid_reaches_8_km2_near_2010_m),
        cmocka_unit_test(length_option_sets_the_domain),
        cmocka_unit_test(bad_parameters_are_named),
        cmocka_unit_test(arrays_are_validated_and_copied),
        cmocka_unit_test(ids_are_unique),
        cmocka_unit_test(params_list_the_options_given),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
