/*
 * test_mcmc.c - the ensemble sampler, its random streams, priors and
 * diagnostics.
 *
 * The sampler must reproduce known densities to within Monte-Carlo
 * error: a strongly correlated Gaussian, a banana-shaped density whose
 * moments are known in closed form, and a log-normal sampled in ln x (the
 * Jacobian of a log-scaled dimension).  The allowed error of each moment
 * is four times its Monte-Carlo standard error, sd sqrt(tau / (K N)),
 * with tau the integrated autocorrelation time of that very quantity
 * estimated from the chain; a sampler that is wrong by more than noise
 * fails.  Then determinism (a chain restarted mid-way continues exactly),
 * the autocorrelation time of AR(1) series whose tau is known, quantiles,
 * streams and priors.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/mcmc.h"
#include "dfle/mcmc_diag.h"
#include "dfle/prior.h"
#include "dfle/stream.h"
#include "dfle_test.h"

/* ---------------------------------------------------------------- */
/* Densities                                                        */
/* ---------------------------------------------------------------- */

/* N(mu, Sigma) with mu = (1, -2), sd = (1, 2), correlation 0.95. */
static const double G_MU[2] = {1.0, -2.0}, G_SD[2] = {1.0, 2.0}, G_RHO = 0.95;

static int gauss_lp(void *ud, size_t n, const double *x, double *lp, dfle_error *err)
{
    (void)ud, (void)err;
    for (size_t i = 0; i < n; i++) {
        double a = (x[2 * i] - G_MU[0]) / G_SD[0], b = (x[2 * i + 1] - G_MU[1]) / G_SD[1];
        lp[i] = -0.5 * (a * a - 2 * G_RHO * a * b + b * b) / (1 - G_RHO * G_RHO);
    }
    return DFLE_OK;
}

/* Banana: x1 ~ N(0, 1), x2 | x1 ~ N(x1^2 - 1, 1).  Then E x1 = 0,
 * E x1^2 = 1, E x2 = 0, E x2^2 = 1 + Var(x1^2) = 3, E x1^2 x2 = 2. */
static int banana_lp(void *ud, size_t n, const double *x, double *lp, dfle_error *err)
{
    (void)ud, (void)err;
    for (size_t i = 0; i < n; i++) {
        double a = x[2 * i], b = x[2 * i + 1] - (a * a - 1.0);
        lp[i] = -0.5 * (a * a + b * b);
    }
    return DFLE_OK;
}

/* Log-normal density of x itself: ln x ~ N(0, 0.5^2). */
static int lognormal_lp(void *ud, size_t n, const double *x, double *lp, dfle_error *err)
{
    (void)ud, (void)err;
    for (size_t i = 0; i < n; i++) {
        double v = x[i], z = log(v) / 0.5;
        lp[i] = v > 0 ? -0.5 * z * z - log(v) : -INFINITY;
    }
    return DFLE_OK;
}

/* ---------------------------------------------------------------- */
/* Helpers                                                          */
/* ---------------------------------------------------------------- */

typedef struct run {
    size_t K, N, d, burn;
    double *chain; /* N x K x d */
    size_t *acc;
} run;

static void start_ball(size_t K, size_t d, const double *c, double r, uint64_t seed, double *x)
{
    for (size_t k = 0; k < K; k++) {
        dfle_stream s;
        dfle_stream_init(&s, seed, 0, k, 1);
        for (size_t j = 0; j < d; j++)
            x[k * d + j] = c[j] + r * dfle_stream_normal(&s);
    }
}

static run sample(dfle_mcmc_logp_fn f, size_t d, size_t K, size_t N, size_t burn,
                  const int *logs, const double *x0)
{
    dfle_mcmc_opts o;
    dfle_mcmc *s;
    dfle_error err;
    run r = {K, N, d, burn, NULL, NULL};
    double *lp = malloc(K * sizeof *lp);

    dfle_mcmc_opts_default(&o);
    o.ndim = d;
    o.nwalkers = K;
    o.seed = 7;
    o.log_scale = logs;
    assert_ok(dfle_mcmc_new(&o, &s, &err), &err);
    assert_ok(f(NULL, K, x0, lp, &err), &err);
    assert_ok(dfle_mcmc_set_state(s, 0, x0, lp, &err), &err);
    r.chain = malloc(N * K * d * sizeof *r.chain);
    r.acc = calloc(K, sizeof *r.acc);
    assert_ok(dfle_mcmc_run(s, N, f, NULL, r.chain, NULL, r.acc, &err), &err);
    assert_int_equal(dfle_mcmc_step(s), N);
    dfle_mcmc_free(s);
    free(lp);
    return r;
}

static void run_free(run *r)
{
    free(r->chain);
    free(r->acc);
}

/* E g(x) over the chain after burn-in must be within 4 Monte-Carlo
 * standard errors of `expect`. */
static void check_moment(const run *r, double (*g)(const double *x), double expect,
                         const char *what)
{
    size_t N = r->N - r->burn, K = r->K;
    double *series = malloc(N * K * sizeof *series), tau, mean = 0, ss = 0, se;
    dfle_error err;
    for (size_t t = 0; t < N; t++)
        for (size_t k = 0; k < K; k++) {
            double v = g(r->chain + ((r->burn + t) * K + k) * r->d);
            series[t * K + k] = v;
            mean += v;
        }
    mean /= (double)(N * K);
    for (size_t i = 0; i < N * K; i++)
        ss += (series[i] - mean) * (series[i] - mean);
    assert_ok(dfle_mcmc_autocorr(series, N, K, 1, 0, &tau, NULL, &err), &err);
    se = sqrt(ss / (double)(N * K - 1)) * sqrt(tau / (double)(N * K));
    print_message("%-14s %9.4f (expected %7.4f, MC error %.4f, tau %.1f)\n", what, mean,
                  expect, se, tau);
    assert_true(tau >= 1 && tau < (double)N / 20);
    if (!(fabs(mean - expect) <= 4 * se))
        fail_msg("%s: %.5f differs from %.5f by more than 4 MC errors (%.5f)", what, mean,
                 expect, 4 * se);
    free(series);
}

static double acceptance(const run *r)
{
    size_t a = 0;
    for (size_t k = 0; k < r->K; k++)
        a += r->acc[k];
    return (double)a / (double)(r->K * r->N);
}

static double g_x1(const double *x) { return x[0]; }
static double g_x2(const double *x) { return x[1]; }
static double g_var1(const double *x) { return (x[0] - G_MU[0]) * (x[0] - G_MU[0]); }
static double g_var2(const double *x) { return (x[1] - G_MU[1]) * (x[1] - G_MU[1]); }
static double g_cov(const double *x) { return (x[0] - G_MU[0]) * (x[1] - G_MU[1]); }
static double g_sq1(const double *x) { return x[0] * x[0]; }
static double g_sq2(const double *x) { return x[1] * x[1]; }
static double g_x1sq_x2(const double *x) { return x[0] * x[0] * x[1]; }
static double g_ln(const double *x) { return log(x[0]); }
static double g_ln2(const double *x) { return log(x[0]) * log(x[0]); }

/* ---------------------------------------------------------------- */
/* The sampler on known densities                                   */
/* ---------------------------------------------------------------- */

static void test_correlated_gaussian(void **state)
{
    double x0[32 * 2], c[2] = {0, 0};
    run r;
    (void)state;
    start_ball(32, 2, c, 0.5, 1, x0); /* away from the mode: burn-in matters */
    r = sample(gauss_lp, 2, 32, 3000, 500, NULL, x0);
    check_moment(&r, g_x1, G_MU[0], "E x1");
    check_moment(&r, g_x2, G_MU[1], "E x2");
    check_moment(&r, g_var1, G_SD[0] * G_SD[0], "Var x1");
    check_moment(&r, g_var2, G_SD[1] * G_SD[1], "Var x2");
    check_moment(&r, g_cov, G_RHO * G_SD[0] * G_SD[1], "Cov x1 x2");
    /* The stretch move's typical acceptance on a 2-D Gaussian. */
    assert_true(acceptance(&r) > 0.4 && acceptance(&r) < 0.9);
    run_free(&r);
}

static void test_banana(void **state)
{
    double x0[32 * 2], c[2] = {0, 0};
    run r;
    (void)state;
    start_ball(32, 2, c, 0.1, 2, x0);
    r = sample(banana_lp, 2, 32, 6000, 1000, NULL, x0);
    check_moment(&r, g_x1, 0.0, "E x1");
    check_moment(&r, g_sq1, 1.0, "E x1^2");
    check_moment(&r, g_x2, 0.0, "E x2");
    check_moment(&r, g_sq2, 3.0, "E x2^2");
    check_moment(&r, g_x1sq_x2, 2.0, "E x1^2 x2");
    run_free(&r);
}

static void test_log_scaled_dimension(void **state)
{
    /* Moving in ln x needs the Jacobian in the acceptance ratio: without
     * it the chain samples x e^... and E ln x is off by sd^2. */
    double x0[8], c[1] = {0};
    int logs[1] = {1};
    run r;
    (void)state;
    start_ball(8, 1, c, 0.3, 3, x0);
    for (int k = 0; k < 8; k++)
        x0[k] = exp(x0[k]);
    r = sample(lognormal_lp, 1, 8, 8000, 1000, logs, x0);
    check_moment(&r, g_ln, 0.0, "E ln x");
    check_moment(&r, g_ln2, 0.25, "E (ln x)^2");
    check_moment(&r, g_x1, exp(0.125), "E x");
    for (size_t i = 0; i < r.N * r.K; i++)
        assert_true(r.chain[i] > 0);
    run_free(&r);
}

/* A chain restarted from the ensemble at step 60 continues exactly as the
 * uninterrupted chain: every walker update has its own stream. */
static void test_restart_is_exact(void **state)
{
    const size_t K = 16, d = 2;
    double x0[16 * 2], lp0[16], c[2] = {0, 0}, *full, *part;
    dfle_mcmc_opts o;
    dfle_mcmc *a, *b;
    dfle_error err;
    (void)state;
    start_ball(K, d, c, 1.0, 4, x0);
    gauss_lp(NULL, K, x0, lp0, &err);
    dfle_mcmc_opts_default(&o);
    o.ndim = d;
    o.nwalkers = K;
    o.seed = 99;
    full = malloc(100 * K * d * sizeof *full);
    part = malloc(100 * K * d * sizeof *part);
    assert_ok(dfle_mcmc_new(&o, &a, &err), &err);
    assert_ok(dfle_mcmc_set_state(a, 0, x0, lp0, &err), &err);
    assert_ok(dfle_mcmc_run(a, 100, gauss_lp, NULL, full, NULL, NULL, &err), &err);

    assert_ok(dfle_mcmc_new(&o, &b, &err), &err);
    assert_ok(dfle_mcmc_set_state(b, 0, x0, lp0, &err), &err);
    assert_ok(dfle_mcmc_run(b, 60, gauss_lp, NULL, part, NULL, NULL, &err), &err);
    dfle_mcmc_free(b);
    {
        double lp60[16];
        gauss_lp(NULL, K, part + 59 * K * d, lp60, &err);
        assert_ok(dfle_mcmc_new(&o, &b, &err), &err);
        assert_ok(dfle_mcmc_set_state(b, 60, part + 59 * K * d, lp60, &err), &err);
        assert_ok(dfle_mcmc_run(b, 40, gauss_lp, NULL, part + 60 * K * d, NULL, NULL, &err), &err);
    }
    assert_memory_equal(full, part, 100 * K * d * sizeof *full);
    /* Another seed gives another chain. */
    o.seed = 100;
    dfle_mcmc_free(b);
    assert_ok(dfle_mcmc_new(&o, &b, &err), &err);
    assert_ok(dfle_mcmc_set_state(b, 0, x0, lp0, &err), &err);
    assert_ok(dfle_mcmc_run(b, 100, gauss_lp, NULL, part, NULL, NULL, &err), &err);
    assert_true(memcmp(full, part, 100 * K * d * sizeof *full) != 0);
    dfle_mcmc_free(a);
    dfle_mcmc_free(b);
    free(full);
    free(part);
}

/* Proposals that have no density (-inf, NaN) are never accepted. */
static int half_plane_lp(void *ud, size_t n, const double *x, double *lp, dfle_error *err)
{
    (void)ud, (void)err;
    for (size_t i = 0; i < n; i++)
        lp[i] = x[2 * i] < 0 ? -INFINITY : x[2 * i + 1] > 3 ? NAN : -0.5 * (x[2 * i] * x[2 * i] + x[2 * i + 1] * x[2 * i + 1]);
    return DFLE_OK;
}

static void test_zero_density_rejected(void **state)
{
    double x0[8 * 2], c[2] = {1, 0};
    run r;
    (void)state;
    start_ball(8, 2, c, 0.1, 5, x0);
    r = sample(half_plane_lp, 2, 8, 500, 0, NULL, x0);
    for (size_t i = 0; i < r.N * r.K; i++) {
        assert_true(r.chain[2 * i] >= 0);
        assert_true(r.chain[2 * i + 1] <= 3);
    }
    run_free(&r);
}

static void test_errors(void **state)
{
    dfle_mcmc_opts o;
    dfle_mcmc *s;
    dfle_error err;
    double x[8] = {0}, lp[4] = {0, 0, -INFINITY, 0}, y[4];
    (void)state;
    dfle_mcmc_opts_default(&o);
    o.ndim = 2;
    o.nwalkers = 5;
    assert_int_equal(dfle_mcmc_new(&o, &s, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "even");
    o.nwalkers = 2;
    assert_int_equal(dfle_mcmc_new(&o, &s, &err), DFLE_EINVAL);
    o.ndim = 3;
    o.nwalkers = 4;
    assert_int_equal(dfle_mcmc_new(&o, &s, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "twice");
    o.ndim = 2;
    o.a = 1.0;
    assert_int_equal(dfle_mcmc_new(&o, &s, &err), DFLE_EINVAL);
    o.a = 2.0;
    assert_ok(dfle_mcmc_new(&o, &s, &err), &err);
    assert_int_equal(dfle_mcmc_propose(s, 0, y, &err), DFLE_ESTATE);
    assert_int_equal(dfle_mcmc_set_state(s, 0, x, lp, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "walker 3");
    lp[2] = 0;
    assert_ok(dfle_mcmc_set_state(s, 0, x, lp, &err), &err);
    assert_int_equal(dfle_mcmc_propose(s, 1, y, &err), DFLE_ESTATE);
    assert_int_equal(dfle_mcmc_accept(s, 0, y, lp, NULL, &err), DFLE_ESTATE);
    dfle_mcmc_free(s);
}

/* ---------------------------------------------------------------- */
/* Diagnostics                                                      */
/* ---------------------------------------------------------------- */

/* AR(1) x_t = phi x_{t-1} + e_t has tau = (1 + phi) / (1 - phi). */
static void test_autocorr_ar1(void **state)
{
    const size_t N = 20000, K = 8;
    const double phis[3] = {0.0, 0.5, 0.8};
    double *chain = malloc(N * K * 3 * sizeof *chain), tau[3];
    int windowed;
    dfle_error err;
    (void)state;
    for (size_t k = 0; k < K; k++) {
        double x[3] = {0, 0, 0};
        dfle_stream s;
        dfle_stream_init(&s, 11, k, 0, 0);
        for (size_t t = 0; t < N; t++)
            for (int j = 0; j < 3; j++) {
                x[j] = phis[j] * x[j] + dfle_stream_normal(&s);
                chain[(t * K + k) * 3 + (size_t)j] = x[j];
            }
    }
    assert_ok(dfle_mcmc_autocorr(chain, N, K, 3, 0, tau, &windowed, &err), &err);
    assert_int_equal(windowed, 1);
    for (int j = 0; j < 3; j++) {
        double want = (1 + phis[j]) / (1 - phis[j]);
        print_message("AR(1) phi = %.1f: tau %.3f (exact %.3f)\n", phis[j], tau[j], want);
        assert_close(tau[j], want, 0.08, 0);
    }
    /* A walker that never moves is left out; all of them: NaN. */
    for (size_t i = 0; i < N * K * 3; i++)
        chain[i] = 1.0;
    assert_ok(dfle_mcmc_autocorr(chain, N, K, 3, 0, tau, NULL, &err), &err);
    assert_true(isnan(tau[0]));
    assert_int_equal(dfle_mcmc_autocorr(chain, 1, K, 3, 0, tau, NULL, &err), DFLE_EINVAL);
    free(chain);
}

static void test_summary_quantiles(void **state)
{
    double x[202];
    dfle_summary s;
    dfle_error err;
    (void)state;
    for (int i = 0; i <= 100; i++) {
        x[2 * i] = 100 - i; /* stride 2, unsorted */
        x[2 * i + 1] = NAN;
    }
    assert_ok(dfle_summarize(x, 101, 2, &s, &err), &err);
    assert_int_equal(s.n, 101);
    assert_close(s.mean, 50, 1e-12, 0);
    assert_close(s.median, 50, 1e-12, 0);
    assert_close(s.lo95, 2.5, 1e-12, 0);
    assert_close(s.hi95, 97.5, 1e-12, 0);
    assert_close(s.lo68, 15.865525393145707, 1e-12, 0);
    assert_close(s.hi68, 84.13447460685429, 1e-12, 0);
    assert_close(s.sd, sqrt(858.5), 1e-12, 0);
    /* NaNs are left out. */
    assert_ok(dfle_summarize(x + 1, 101, 2, &s, &err), &err);
    assert_int_equal(s.n, 0);
    assert_true(isnan(s.median));
}

/* ---------------------------------------------------------------- */
/* Streams and priors                                               */
/* ---------------------------------------------------------------- */

static void test_streams(void **state)
{
    dfle_stream a, b;
    double sum = 0, sum2 = 0;
    size_t counts[3] = {0, 0, 0};
    const size_t n = 200000;
    (void)state;
    dfle_stream_init(&a, 1, 2, 3, 4);
    dfle_stream_init(&b, 1, 2, 3, 4);
    for (int i = 0; i < 100; i++)
        assert_true(dfle_stream_u64(&a) == dfle_stream_u64(&b));
    /* Swapped key words give unrelated streams. */
    dfle_stream_init(&a, 1, 2, 3, 4);
    dfle_stream_init(&b, 1, 3, 2, 4);
    assert_true(dfle_stream_u64(&a) != dfle_stream_u64(&b));
    /* Pinned: the chains users keep depend on these words. */
    dfle_stream_init(&a, 0, 0, 0, 0);
    assert_true(dfle_stream_u64(&a) == 0xfa2502a89c74497fULL);
    dfle_stream_init(&a, 5, 1, 2, 3);
    for (size_t i = 0; i < n; i++) {
        double u = dfle_stream_uniform(&a);
        assert_true(u > 0 && u < 1);
        sum += u;
        counts[dfle_stream_below(&a, 3)]++;
    }
    assert_close(sum / (double)n, 0.5, 0, 4 * sqrt(1.0 / 12 / (double)n));
    for (int k = 0; k < 3; k++)
        assert_close((double)counts[k] / (double)n, 1.0 / 3, 0, 4 * sqrt(2.0 / 9 / (double)n));
    assert_int_equal(dfle_stream_below(&a, 1), 0);
    sum = 0;
    for (size_t i = 0; i < n; i++) {
        double z = dfle_stream_normal(&a);
        sum += z;
        sum2 += z * z;
    }
    assert_close(sum / (double)n, 0.0, 0, 4 / sqrt((double)n));
    assert_close(sum2 / (double)n, 1.0, 0, 4 * sqrt(2.0 / (double)n));
}

static void test_priors(void **state)
{
    dfle_prior u = {DFLE_PRIOR_UNIFORM, 0, 2, 0, 0, 0};
    dfle_prior lu = {DFLE_PRIOR_LOG_UNIFORM, 1e-4, 1e-3, 0, 0, 0};
    dfle_prior nm = {DFLE_PRIOR_NORMAL, 0, INFINITY, 1, 0.5, 0};
    dfle_prior ln = {DFLE_PRIOR_LOG_NORMAL, 0, INFINITY, log(2.0), 0.3, 0};
    dfle_prior cu = {DFLE_PRIOR_CUSTOM, 1, 100, 0, 0, 1};
    dfle_error err;
    dfle_stream s;
    double integral = 0, mean_ln = 0, lo, hi;
    char buf[128];
    (void)state;
    assert_ok(dfle_prior_check(&u, "a", &err), &err);
    assert_ok(dfle_prior_check(&lu, "b", &err), &err);
    assert_ok(dfle_prior_check(&nm, "c", &err), &err);
    assert_ok(dfle_prior_check(&ln, "d", &err), &err);
    assert_ok(dfle_prior_check(&cu, "e", &err), &err);
    assert_close(dfle_prior_logpdf(&u, 1.0), -log(2.0), 1e-14, 0);
    assert_true(dfle_prior_logpdf(&u, 2.5) == -INFINITY);
    assert_true(dfle_prior_logpdf(&u, NAN) == -INFINITY);
    /* The log-uniform density integrates to one over its range. */
    for (int i = 0; i < 100000; i++) {
        double x = 1e-4 + (i + 0.5) * 9e-4 / 100000;
        integral += exp(dfle_prior_logpdf(&lu, x)) * 9e-4 / 100000;
    }
    assert_close(integral, 1.0, 1e-6, 0);
    assert_close(dfle_prior_logpdf(&nm, 1.5), -0.5 - log(0.5) - 0.9189385332046727, 1e-14, 0);
    assert_true(dfle_prior_logpdf(&nm, -0.1) == -INFINITY); /* truncated at 0 */
    assert_int_equal(dfle_prior_log_scale(&lu), 1);
    assert_int_equal(dfle_prior_log_scale(&u), 0);
    assert_int_equal(dfle_prior_log_scale(&ln), 1);
    assert_int_equal(dfle_prior_log_scale(&cu), 1);
    dfle_prior_bounds(&lu, &lo, &hi);
    assert_close(lo, log(1e-4), 1e-14, 0);
    assert_close(dfle_prior_center(&lu), 0.5 * (log(1e-4) + log(1e-3)), 1e-14, 0);
    /* Draws lie in the support; log-uniform draws are uniform in ln x. */
    for (int i = 0; i < 20000; i++) {
        double v;
        dfle_stream_init(&s, 3, 0, (uint64_t)i, 0);
        v = dfle_prior_draw(&lu, &s);
        assert_true(v >= 1e-4 && v <= 1e-3);
        mean_ln += log(v) / 20000;
        v = dfle_prior_draw(&nm, &s);
        assert_true(v >= 0);
        v = dfle_prior_draw(&cu, &s);
        assert_true(v >= 1 && v <= 100);
    }
    assert_close(mean_ln, dfle_prior_center(&lu), 0, 4 * (log(10.0) / sqrt(12.0)) / sqrt(20000));
    dfle_prior_describe(&lu, buf, sizeof buf);
    assert_string_equal(buf, "log-uniform[0.0001,0.001]");
    /* Bad priors name the parameter. */
    lu.lo = 0;
    assert_int_equal(dfle_prior_check(&lu, "k_df", &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "k_df: a log-uniform prior needs 0 < lo");
    nm.sd = 0;
    assert_int_equal(dfle_prior_check(&nm, "U", &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "sd > 0");
    u.hi = -1;
    assert_int_equal(dfle_prior_check(&u, "gamma", &err), DFLE_EINVAL);
    cu.hi = INFINITY;
    assert_int_equal(dfle_prior_check(&cu, "x", &err), DFLE_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_correlated_gaussian),
        cmocka_unit_test(test_banana),
        cmocka_unit_test(test_log_scaled_dimension),
        cmocka_unit_test(test_restart_is_exact),
        cmocka_unit_test(test_zero_density_rejected),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_autocorr_ar1),
        cmocka_unit_test(test_summary_quantiles),
        cmocka_unit_test(test_streams),
        cmocka_unit_test(test_priors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
