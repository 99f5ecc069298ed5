/*
 * test_sampling.c - the MT19937 stream, bounded integers and Latin
 * hypercube designs.
 *
 * Reproducibility is checked three ways: the generator against the
 * values the C++ standard fixes for mt19937 (so the word stream is the
 * reference one on every platform), the design against an independent
 * re-derivation of the documented algorithm straight from GSL, and a few
 * pinned values.  The strata property (one sample per stratum in every
 * dimension) is checked for several n, kinds and seeds.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_rng.h>

#include "dfle/sampling.h"
#include "dfle_test.h"

/* The restatement below must round like the library: no FMA. */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

/* ---------------------------------------------------------------- */
/* Generator                                                        */
/* ---------------------------------------------------------------- */

static void test_rng_matches_reference_mt19937(void **state)
{
    dfle_rng *r;
    dfle_error err;
    uint32_t w = 0;
    (void)state;
    /* C++11 [rand.predef]: the 10000th output of mt19937 seeded with its
     * default 5489 is 4123659995; its first is 3499211612. */
    assert_ok(dfle_rng_new(5489, &r, &err), &err);
    assert_int_equal(dfle_rng_u32(r), 3499211612u);
    for (int i = 1; i < 10000; i++)
        w = dfle_rng_u32(r);
    assert_int_equal(w, 4123659995u);
    dfle_rng_free(r);
}

static void test_rng_uniform_is_word_over_2_32(void **state)
{
    dfle_rng *a, *b;
    dfle_error err;
    (void)state;
    assert_ok(dfle_rng_new(42, &a, &err), &err);
    assert_ok(dfle_rng_new(42, &b, &err), &err);
    for (int i = 0; i < 1000; i++) {
        double u = dfle_rng_uniform(a);
        uint32_t w = dfle_rng_u32(b);
        assert_true(u == (double)w / 4294967296.0);
        assert_true(u >= 0.0 && u < 1.0);
    }
    dfle_rng_free(a);
    dfle_rng_free(b);
}

/* dfle_rng_below by the documented rule, from raw GSL words. */
static uint64_t below_reference(gsl_rng *g, uint64_t m)
{
    uint64_t span = UINT64_C(1) << 32, limit = span - span % m, w;
    do
        w = gsl_rng_get(g);
    while (w >= limit);
    return w % m;
}

static void test_rng_below_rejection(void **state)
{
    const uint64_t ms[] = {1, 2, 3, 7, 1000, 3000000000u, UINT64_C(4294967296)};
    (void)state;
    for (size_t k = 0; k < sizeof ms / sizeof ms[0]; k++) {
        dfle_rng *r;
        dfle_error err;
        gsl_rng *g = gsl_rng_alloc(gsl_rng_mt19937);
        assert_non_null(g);
        gsl_rng_set(g, 99);
        assert_ok(dfle_rng_new(99, &r, &err), &err);
        for (int i = 0; i < 2000; i++) {
            uint64_t v = dfle_rng_below(r, ms[k]);
            uint64_t ref = ms[k] == 1 ? 0 : below_reference(g, ms[k]);
            assert_true(v < ms[k]);
            assert_true(v == ref);
        }
        dfle_rng_free(r);
        gsl_rng_free(g);
    }
}

static void test_rng_errors(void **state)
{
    dfle_rng *r = NULL;
    dfle_error err;
    (void)state;
    assert_int_equal(dfle_rng_new(1, NULL, &err), DFLE_EINVAL);
    if (sizeof(unsigned long) > 4) { /* seeds above 2^32 - 1 would alias */
        unsigned long too_big = (unsigned long)DFLE_SEED_MAX + 1;
        r = (dfle_rng *)&r;
        assert_int_equal(dfle_rng_new(too_big, &r, &err), DFLE_EINVAL);
        assert_null(r);
        assert_msg_contains(err.msg, "seed");
    }
    assert_ok(dfle_rng_new(DFLE_SEED_MAX, &r, &err), &err);
    dfle_rng_free(r);
    dfle_rng_free(NULL);
}

/* ---------------------------------------------------------------- */
/* Designs                                                          */
/* ---------------------------------------------------------------- */

static const double alpha_values[] = {2, 4, 6};

static void four_params(dfle_lhs_param p[4])
{
    memset(p, 0, 4 * sizeof *p);
    p[0].name = "k_df";
    p[0].kind = DFLE_LHS_LOG_UNIFORM;
    p[0].lo = 5e-5;
    p[0].hi = 1e-3;
    p[1].name = "gamma";
    p[1].kind = DFLE_LHS_UNIFORM;
    p[1].lo = 0;
    p[1].hi = 1;
    p[2].name = "alpha";
    p[2].kind = DFLE_LHS_DISCRETE;
    p[2].values = alpha_values;
    p[2].nvalues = 3;
    p[3].name = "U";
    p[3].kind = DFLE_LHS_UNIFORM;
    p[3].lo = -2.5;
    p[3].hi = 7.25;
}

static dfle_lhs *make_design(size_t n, unsigned long seed, int centered)
{
    dfle_lhs_param p[4];
    dfle_lhs_opts o;
    dfle_lhs *g = NULL;
    dfle_error err;
    four_params(p);
    dfle_lhs_opts_default(&o);
    o.n = n;
    o.seed = seed;
    o.centered = centered;
    assert_ok(dfle_lhs_new(&o, 4, p, &g, &err), &err);
    assert_non_null(g);
    return g;
}

/* Each dimension has exactly one sample in each of the n strata
 * [k/n, (k+1)/n), and the values lie in their ranges. */
static void check_strata(const dfle_lhs *g)
{
    size_t n = dfle_lhs_n(g), D = dfle_lhs_dim(g);
    unsigned char *seen = calloc(n, 1);
    assert_non_null(seen);
    for (size_t d = 0; d < D; d++) {
        memset(seen, 0, n);
        for (size_t i = 0; i < n; i++) {
            double u = dfle_lhs_unit_row(g, i)[d];
            double k = floor(u * (double)n);
            assert_true(u >= 0.0 && u < 1.0);
            assert_true(k >= 0 && k < (double)n);
            assert_int_equal(seen[(size_t)k], 0);
            seen[(size_t)k] = 1;
        }
        for (size_t k = 0; k < n; k++)
            assert_int_equal(seen[k], 1);
    }
    free(seen);
}

static void test_lhs_one_sample_per_stratum(void **state)
{
    const size_t ns[] = {1, 2, 7, 100, 1000, 4000};
    (void)state;
    for (size_t k = 0; k < sizeof ns / sizeof ns[0]; k++) {
        for (unsigned long seed = 0; seed < 3; seed++) {
            for (int centered = 0; centered <= 1; centered++) {
                dfle_lhs *g = make_design(ns[k], seed, centered);
                check_strata(g);
                dfle_lhs_free(g);
            }
        }
    }
}

static void test_lhs_values_in_ranges(void **state)
{
    dfle_lhs *g = make_design(2000, 7, 0);
    (void)state;
    for (size_t i = 0; i < 2000; i++) {
        const double *x = dfle_lhs_row(g, i);
        assert_true(x[0] >= 5e-5 && x[0] <= 1e-3);
        assert_true(x[1] >= 0.0 && x[1] <= 1.0);
        assert_true(x[2] == 2 || x[2] == 4 || x[2] == 6);
        assert_true(x[2] == alpha_values[dfle_lhs_choice(g, i, 2)]);
        assert_true(x[3] >= -2.5 && x[3] <= 7.25);
    }
    dfle_lhs_free(g);
}

/* The documented algorithm, restated from raw GSL calls. */
static void test_lhs_rederived_from_gsl(void **state)
{
    const size_t n = 257, D = 4;
    dfle_lhs *g = make_design(n, 12345, 0);
    gsl_rng *r = gsl_rng_alloc(gsl_rng_mt19937);
    size_t *perm = malloc(n * sizeof *perm);
    (void)state;
    assert_non_null(r);
    assert_non_null(perm);
    gsl_rng_set(r, 12345);
    for (size_t d = 0; d < D; d++) {
        for (size_t i = 0; i < n; i++)
            perm[i] = i;
        for (size_t i = n - 1; i >= 1; i--) {
            size_t j = (size_t)below_reference(r, i + 1), t = perm[i];
            perm[i] = perm[j];
            perm[j] = t;
        }
        for (size_t i = 0; i < n; i++) {
            double v = (double)gsl_rng_get(r) / 4294967296.0;
            double u = ((double)perm[i] + v) / (double)n;
            double x = dfle_lhs_row(g, i)[d];
            assert_true(dfle_lhs_unit_row(g, i)[d] == u);
            if (d == 0) {
                double step = u * (log(1e-3) - log(5e-5));
                assert_true(x == exp(log(5e-5) + step));
            } else if (d == 1) {
                assert_true(x == u);
            } else if (d == 2) {
                assert_true(x == alpha_values[(size_t)floor(u * 3.0)]);
            } else {
                double step = u * (7.25 - -2.5);
                assert_true(x == -2.5 + step);
            }
        }
    }
    free(perm);
    gsl_rng_free(r);
    dfle_lhs_free(g);
}

static void test_lhs_reproducible(void **state)
{
    dfle_lhs *a = make_design(500, 1, 0), *b = make_design(500, 1, 0);
    dfle_lhs *c = make_design(500, 2, 0);
    size_t same = 0;
    (void)state;
    for (size_t i = 0; i < 500; i++) {
        assert_memory_equal(dfle_lhs_row(a, i), dfle_lhs_row(b, i), 4 * sizeof(double));
        assert_memory_equal(dfle_lhs_unit_row(a, i), dfle_lhs_unit_row(b, i),
                            4 * sizeof(double));
        same += dfle_lhs_unit_row(a, i)[1] == dfle_lhs_unit_row(c, i)[1];
    }
    assert_true(same < 5);
    dfle_lhs_free(a);
    dfle_lhs_free(b);
    dfle_lhs_free(c);
}

/* Pinned values (computed by this implementation when it was written and
 * cross-checked by test_lhs_rederived_from_gsl): a change here means
 * every user's recorded design changes. */
static void test_lhs_pinned_values(void **state)
{
    dfle_lhs *g = make_design(5, 1, 0);
    dfle_lhs *c = make_design(4, 1, 1);
    (void)state;
    assert_true(dfle_lhs_unit_row(g, 0)[0] == 0x1.99a597fe66666p-3);
    assert_true(dfle_lhs_unit_row(g, 4)[1] == 0x1.2c99653d33333p-1);
    assert_true(dfle_lhs_unit_row(g, 2)[3] == 0x1.62048cbc66666p-1);
    assert_true(dfle_lhs_row(g, 0)[2] == 6.0);
    assert_true(dfle_lhs_row(g, 1)[2] == 2.0);
    assert_true(dfle_lhs_row(g, 1)[3] == -1.6862556315842085);
    /* Centred: exactly (k + 1/2) / n with k the stratum. */
    for (size_t i = 0; i < 4; i++)
        for (size_t d = 0; d < 4; d++) {
            double u = dfle_lhs_unit_row(c, i)[d];
            assert_true(u == (floor(u * 4.0) + 0.5) / 4.0);
        }
    dfle_lhs_free(g);
    dfle_lhs_free(c);
}

/* n a multiple of the number of values: each value exactly n/k times. */
static void test_lhs_discrete_balanced(void **state)
{
    (void)state;
    for (unsigned long seed = 1; seed <= 5; seed++) {
        dfle_lhs *g = make_design(30, seed, seed % 2);
        size_t count[3] = {0, 0, 0};
        for (size_t i = 0; i < 30; i++)
            count[dfle_lhs_choice(g, i, 2)]++;
        assert_int_equal(count[0], 10);
        assert_int_equal(count[1], 10);
        assert_int_equal(count[2], 10);
        dfle_lhs_free(g);
    }
}

static void test_lhs_accessors(void **state)
{
    dfle_lhs *g = make_design(3, 1, 0);
    (void)state;
    assert_int_equal(dfle_lhs_n(g), 3);
    assert_int_equal(dfle_lhs_dim(g), 4);
    assert_string_equal(dfle_lhs_name(g, 0), "k_df");
    assert_string_equal(dfle_lhs_name(g, 3), "U");
    assert_null(dfle_lhs_name(g, 4));
    assert_int_equal(dfle_lhs_param_kind(g, 0), DFLE_LHS_LOG_UNIFORM);
    assert_int_equal(dfle_lhs_param_kind(g, 2), DFLE_LHS_DISCRETE);
    assert_null(dfle_lhs_row(g, 3));
    assert_null(dfle_lhs_unit_row(g, 3));
    assert_non_null(dfle_lhs_row(g, 2));
    assert_int_equal(dfle_lhs_choice(g, 3, 2), 0);
    dfle_lhs_free(g);
    dfle_lhs_free(NULL);
}

/* A failing build names the parameter at fault and leaves *out NULL. */
static void expect_param_error(dfle_lhs_param *p, size_t np, size_t n, const char *needle)
{
    dfle_lhs_opts o;
    dfle_lhs *g = (dfle_lhs *)&o;
    dfle_error err;
    dfle_lhs_opts_default(&o);
    o.n = n;
    assert_int_equal(dfle_lhs_new(&o, np, p, &g, &err), DFLE_EINVAL);
    assert_null(g);
    assert_msg_contains(err.msg, needle);
}

static void test_lhs_errors(void **state)
{
    dfle_lhs_param p[4];
    (void)state;
    four_params(p);
    p[1].lo = 1;
    p[1].hi = 1;
    expect_param_error(p, 4, 10, "'gamma'");
    expect_param_error(p, 4, 10, "lo < hi");
    four_params(p);
    p[0].lo = 0;
    expect_param_error(p, 4, 10, "'k_df'");
    expect_param_error(p, 4, 10, "lo > 0");
    four_params(p);
    p[3].hi = NAN;
    expect_param_error(p, 4, 10, "'U'");
    four_params(p);
    p[3].lo = -1e308;
    p[3].hi = 1e308;
    expect_param_error(p, 4, 10, "overflows");
    four_params(p);
    p[2].nvalues = 0;
    expect_param_error(p, 4, 10, "'alpha'");
    four_params(p);
    p[3].name = "gamma";
    expect_param_error(p, 4, 10, "'gamma' is given twice");
    four_params(p);
    p[1].name = "";
    expect_param_error(p, 4, 10, "name");
    four_params(p);
    expect_param_error(p, 4, 0, "n (number of samples)");
    expect_param_error(p, 0, 10, "at least one parameter");
    {
        dfle_lhs_opts o;
        dfle_lhs *g;
        dfle_error err;
        dfle_lhs_opts_default(&o);
        assert_int_equal(dfle_lhs_new(&o, 4, p, NULL, &err), DFLE_EINVAL);
        assert_int_equal(dfle_lhs_new(NULL, 4, p, &g, &err), DFLE_EINVAL);
        assert_null(g);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rng_matches_reference_mt19937),
        cmocka_unit_test(test_rng_uniform_is_word_over_2_32),
        cmocka_unit_test(test_rng_below_rejection),
        cmocka_unit_test(test_rng_errors),
        cmocka_unit_test(test_lhs_one_sample_per_stratum),
        cmocka_unit_test(test_lhs_values_in_ranges),
        cmocka_unit_test(test_lhs_rederived_from_gsl),
        cmocka_unit_test(test_lhs_reproducible),
        cmocka_unit_test(test_lhs_pinned_values),
        cmocka_unit_test(test_lhs_discrete_balanced),
        cmocka_unit_test(test_lhs_accessors),
        cmocka_unit_test(test_lhs_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
