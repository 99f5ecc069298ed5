/*
 * test_analysis.c - slope-area binning and the Eq. (2) fit.
 *
 * Binning is checked against hand-computed counts, means and numpy-style
 * quartiles; the fit against synthetic Eq. (2) data whose parameters are
 * known, with and without deterministic noise, and through the whole
 * bin-then-fit path on a dense synthetic profile like the paper's Fig. 1.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/analysis.h"
#include "dfle_test.h"

/* A tiny LCG (Knuth's MMIX constants) so noisy data are identical on
 * every platform and run. */
static uint64_t lcg_state;

static double lcg_uniform(void)
{
    lcg_state = lcg_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(lcg_state >> 11) / 9007199254740992.0; /* [0, 1) */
}

/* n areas evenly spaced in ln A over [A_lo, A_hi], slopes from Eq. (2)
 * times (1 + noise * u), u uniform in [-1, 1). */
static void make_eq2_data(size_t n, double A_lo, double A_hi, double S_df,
                          double A_df, double a2, double noise, double *A,
                          double *S)
{
    for (size_t i = 0; i < n; i++) {
        A[i] = A_lo * pow(A_hi / A_lo, (double)i / (double)(n - 1));
        S[i] = dfle_eq2_eval(S_df, A_df, a2, A[i]) *
               (1.0 + noise * (2.0 * lcg_uniform() - 1.0));
    }
}

/* ---------------------------------------------------------------- */
/* Binning                                                          */
/* ---------------------------------------------------------------- */

static void test_bins_known_statistics(void **state)
{
    (void)state;
    /* Two bins over [1, 100]: edges 1, 10, 100.  Input deliberately
     * unsorted. */
    const double A[] = { 50, 2, 100, 1, 5, 20, 3 };
    const double S[] = { 0.1, 2, 0.3, 1, 10, 0.5, 3 };
    dfle_bins b;
    dfle_error err = { 0, "" };
    assert_ok(dfle_bins_compute(7, A, S, 2, &b, &err), &err);
    assert_int_equal(b.nbins, 2);
    assert_int_equal(b.n, 2);
    assert_int_equal(b.n_empty, 0);

    assert_int_equal(b.count[0], 4); /* slopes 1, 2, 3, 10 */
    assert_close(b.A_lo[0], 1.0, 1e-15, 0);
    assert_close(b.A_hi[0], 10.0, 1e-14, 0);
    assert_close(b.A[0], pow(1.0 * 2 * 3 * 5, 0.25), 1e-14, 0);
    assert_close(b.S_mean[0], 4.0, 1e-15, 0);
    assert_close(b.S_median[0], 2.5, 1e-15, 0);
    assert_close(b.S_q25[0], 1.75, 1e-15, 0);
    assert_close(b.S_q75[0], 4.75, 1e-15, 0);

    assert_int_equal(b.count[1], 3); /* slopes 0.1, 0.3, 0.5 */
    assert_close(b.A_lo[1], 10.0, 1e-14, 0);
    assert_close(b.A_hi[1], 100.0, 1e-15, 0);
    assert_close(b.A[1], cbrt(20.0 * 50 * 100), 1e-14, 0);
    assert_close(b.S_mean[1], 0.3, 1e-14, 0);
    assert_close(b.S_median[1], 0.3, 1e-15, 0);
    assert_close(b.S_q25[1], 0.2, 1e-14, 0);
    assert_close(b.S_q75[1], 0.4, 1e-14, 0);
    dfle_bins_release(&b);
}

static void test_bins_single_point_and_even_count(void **state)
{
    (void)state;
    /* Bin 0 has one point (all statistics equal it), bin 1 two points
     * (median and quartiles interpolate between them). */
    const double A[] = { 1, 60, 90 };
    const double S[] = { 0.7, 0.2, 0.6 };
    dfle_bins b;
    dfle_error err = { 0, "" };
    assert_ok(dfle_bins_compute(3, A, S, 2, &b, &err), &err);
    assert_int_equal(b.n, 2);
    assert_close(b.S_median[0], 0.7, 0, 0);
    assert_close(b.S_q25[0], 0.7, 0, 0);
    assert_close(b.S_q75[0], 0.7, 0, 0);
    assert_close(b.S_median[1], 0.4, 1e-15, 0);
    assert_close(b.S_q25[1], 0.3, 1e-15, 0);
    assert_close(b.S_q75[1], 0.5, 1e-15, 0);
    assert_close(b.A[1], sqrt(60.0 * 90.0), 1e-14, 0);
    dfle_bins_release(&b);
}

static void test_bins_empty_dropped(void **state)
{
    (void)state;
    /* Four bins over [1, 1e4] (a decade each); only the first and the
     * last receive points. */
    const double A[] = { 1, 1.5, 2, 5e3, 1e4 };
    const double S[] = { 1, 2, 3, 0.1, 0.2 };
    dfle_bins b;
    dfle_error err = { 0, "" };
    assert_ok(dfle_bins_compute(5, A, S, 4, &b, &err), &err);
    assert_int_equal(b.nbins, 4);
    assert_int_equal(b.n, 2);
    assert_int_equal(b.n_empty, 2);
    assert_int_equal(b.count[0], 3);
    assert_int_equal(b.count[1], 2);
    assert_close(b.A_lo[1], 1e3, 1e-13, 0);
    assert_close(b.A_hi[1], 1e4, 1e-15, 0);
    assert_close(b.S_mean[0], 2.0, 1e-15, 0);
    assert_close(b.S_mean[1], 0.15, 1e-15, 0);
    dfle_bins_release(&b);
}

static void test_bins_largest_area_in_last_bin(void **state)
{
    (void)state;
    /* Two points, ten bins: the largest area sits exactly on the top
     * edge and must still be counted, in bin 10 of 10. */
    const double A[] = { 1e10, 1.0 };
    const double S[] = { 0.01, 0.9 };
    dfle_bins b;
    dfle_error err = { 0, "" };
    assert_ok(dfle_bins_compute(2, A, S, 10, &b, &err), &err);
    assert_int_equal(b.n, 2);
    assert_int_equal(b.n_empty, 8);
    assert_int_equal(b.count[1], 1);
    assert_close(b.A[1], 1e10, 1e-15, 0);
    assert_close(b.A_hi[1], 1e10, 0, 0);
    assert_close(b.A_lo[1], 1e9, 1e-13, 0);
    assert_close(b.S_mean[1], 0.01, 0, 0);
    dfle_bins_release(&b);

    /* Many points and many bins: every usable point is counted once and
     * the bins tile [min A, max A]. */
    enum { N = 1000 };
    double *An = malloc(N * sizeof *An), *Sn = malloc(N * sizeof *Sn);
    assert_non_null(An);
    assert_non_null(Sn);
    lcg_state = 7;
    for (size_t i = 0; i < N; i++) {
        An[i] = 1e3 * pow(1e4, lcg_uniform());
        Sn[i] = lcg_uniform();
    }
    An[17] = 1e7 * (1.0 - 1e-16); /* the maximum, very close to a power of 10 */
    assert_ok(dfle_bins_compute(N, An, Sn, 37, &b, &err), &err);
    size_t total = 0;
    for (size_t k = 0; k < b.n; k++) {
        total += b.count[k];
        assert_true(b.A[k] >= b.A_lo[k] && b.A[k] <= b.A_hi[k]);
        if (k > 0)
            assert_true(b.A_lo[k] >= b.A_hi[k - 1]);
    }
    assert_int_equal(total, N);
    assert_int_equal(b.n + b.n_empty, 37);
    assert_close(b.A_hi[b.n - 1], An[17], 0, 0);
    dfle_bins_release(&b);
    free(An);
    free(Sn);
}

static void test_bins_points_on_edges(void **state)
{
    (void)state;
    /* Bins are half-open, [A_lo, A_hi): an area equal to a reported edge
     * must land in the bin above it, whatever rounding log() does. */
    enum { NB = 21, ND = 2000 }; /* log() rounding errs both ways here */
    double A[ND], S[ND], edge_A[NB + 1], edge_S[NB + 1];
    dfle_bins b, on_edges;
    dfle_error err = { 0, "" };
    for (size_t i = 0; i < ND; i++) {
        A[i] = 3.7 * pow(9.1e6 / 3.7, (double)i / (ND - 1));
        S[i] = 0.5;
    }
    A[ND - 1] = 9.1e6;
    assert_ok(dfle_bins_compute(ND, A, S, NB, &b, &err), &err);
    assert_int_equal(b.n, NB);
    for (size_t k = 0; k < NB; k++) {
        edge_A[k] = b.A_lo[k];
        edge_S[k] = (double)k;
    }
    edge_A[NB] = b.A_hi[NB - 1];
    edge_S[NB] = (double)NB;
    /* Same extremes, so the same grid. */
    assert_ok(dfle_bins_compute(NB + 1, edge_A, edge_S, NB, &on_edges, &err), &err);
    assert_int_equal(on_edges.n, NB);
    for (size_t k = 0; k < NB; k++) {
        assert_close(on_edges.A_lo[k], b.A_lo[k], 0, 0);
        assert_int_equal(on_edges.count[k], k + 1 < NB ? 1 : 2);
        assert_close(on_edges.S_mean[k], k + 1 < NB ? (double)k : NB - 0.5, 0, 0);
    }
    dfle_bins_release(&on_edges);

    /* And the largest double below an edge belongs to the bin below. */
    for (size_t k = 1; k < NB; k++) {
        edge_A[k] = nextafter(b.A_lo[k], 0.0);
        edge_S[k] = (double)(k - 1);
    }
    edge_S[NB] = (double)(NB - 1);
    assert_ok(dfle_bins_compute(NB + 1, edge_A, edge_S, NB, &on_edges, &err), &err);
    assert_int_equal(on_edges.n, NB);
    for (size_t k = 0; k < NB; k++) {
        assert_int_equal(on_edges.count[k], k == 0 ? 2 : 1);
        assert_close(on_edges.S_mean[k], (double)k, 0, 0);
    }
    dfle_bins_release(&b);
    dfle_bins_release(&on_edges);
}

static void test_bins_skip_unusable_pairs(void **state)
{
    (void)state;
    const double A[] = { 1, NAN, 10, -5, 0, 50, INFINITY, 1000 };
    const double S[] = { 1, 0.5, NAN, 0.5, 0.5, 0.25, 0.5, -0.1 };
    dfle_bins b;
    dfle_error err = { 0, "" };
    /* usable: (1, 1), (50, 0.25), (1000, -0.1); three bins over [1, 1e3]. */
    assert_ok(dfle_bins_compute(8, A, S, 3, &b, &err), &err);
    assert_int_equal(b.n, 3);
    assert_int_equal(b.n_empty, 0);
    assert_close(b.S_mean[0], 1.0, 0, 0);
    assert_close(b.S_mean[1], 0.25, 0, 0);
    assert_close(b.S_mean[2], -0.1, 0, 0);
    assert_close(b.A_lo[0], 1.0, 0, 0);
    assert_close(b.A_hi[2], 1000.0, 0, 0);
    dfle_bins_release(&b);
}

static void test_bins_errors(void **state)
{
    (void)state;
    const double A[] = { 5, 5, 5, NAN };
    const double S[] = { 0.1, 0.2, 0.3, 0.4 };
    const double A2[] = { 1, 2, -1, 4 };
    const double S2[] = { 0.1, NAN, 0.3, INFINITY };
    dfle_bins b;
    dfle_error err = { 0, "" };

    memset(&b, 0xff, sizeof b);
    assert_int_equal(dfle_bins_compute(4, A2, S, 0, &b, &err), DFLE_EINVAL);
    assert_int_equal(err.code, DFLE_EINVAL);
    assert_msg_contains(err.msg, "nbins is 0");
    assert_null(b.A);
    assert_int_equal(b.n, 0);

    memset(&b, 0xff, sizeof b);
    assert_int_equal(dfle_bins_compute(4, A, S, 10, &b, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "all 3 usable areas equal 5");
    assert_null(b.S_mean);
    assert_null(b.count);

    /* NaN/Inf/negative pairs are skipped, leaving one usable pair. */
    assert_int_equal(dfle_bins_compute(4, A2, S2, 10, &b, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "1 usable (A, S) pairs of 4");
    assert_msg_contains(err.msg, "need at least 2");

    /* A bin count no memory can hold fails cleanly. */
    memset(&b, 0xff, sizeof b);
    assert_int_equal(dfle_bins_compute(4, A2, S, SIZE_MAX, &b, &err), DFLE_ENOMEM);
    assert_msg_contains(err.msg, "out of memory");
    assert_null(b.A);

    assert_int_equal(dfle_bins_compute(0, NULL, NULL, 10, &b, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "0 usable");
    assert_int_equal(dfle_bins_compute(4, A2, NULL, 10, &b, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "slope array is NULL");
    assert_int_equal(dfle_bins_compute(4, A2, S, 10, NULL, &err), DFLE_EINVAL);
    /* err may be NULL */
    assert_int_equal(dfle_bins_compute(4, A2, S, 0, &b, NULL), DFLE_EINVAL);
}

static void test_bins_release_idempotent(void **state)
{
    (void)state;
    const double A[] = { 1, 10, 100 };
    const double S[] = { 0.3, 0.2, 0.1 };
    dfle_bins b;
    dfle_error err = { 0, "" };
    assert_ok(dfle_bins_compute(3, A, S, 5, &b, &err), &err);
    dfle_bins_release(&b);
    assert_null(b.A);
    assert_int_equal(b.n, 0);
    dfle_bins_release(&b);
    dfle_bins_release(NULL);
}

/* ---------------------------------------------------------------- */
/* Fit                                                              */
/* ---------------------------------------------------------------- */

static const double eq2_cases[][3] = {
    { 0.8, 3e4, 0.9 },
    { 1.2, 2e5, 1.5 },
    { 0.5, 5e3, 0.6 },
    { 1.0, 1e6, 0.7 }, /* ln S_df = 0: a parameter at exactly zero */
    { 0.9, 5e4, 0.65 },
};
#define N_CASES (sizeof eq2_cases / sizeof eq2_cases[0])

/* Exact Eq. (2) data: both fits, residuals in S and in log S, recover
 * the parameters, with R^2 = 1 in both spaces. */
static void test_fit_recovers_noise_free(void **state)
{
    (void)state;
    enum { N = 61 };
    double A[N], S[N];
    for (size_t c = 0; c < 2 * N_CASES; c++) {
        const double *p = eq2_cases[c % N_CASES];
        dfle_residuals res = c < N_CASES ? DFLE_RESIDUALS_LINEAR : DFLE_RESIDUALS_LOG;
        dfle_eq2_fit fit;
        dfle_error err = { 0, "" };
        make_eq2_data(N, 1e2, 1e8, p[0], p[1], p[2], 0.0, A, S);
        assert_ok(dfle_fit_eq2_residuals(N, A, S, res, &fit, &err), &err);
        assert_int_equal(fit.residuals, res);
        assert_close(fit.S_df, p[0], 1e-6, 0);
        assert_close(fit.A_df, p[1], 1e-6, 0);
        assert_close(fit.a2, p[2], 1e-6, 0);
        assert_close(fit.r2, 1.0, 0, 1e-12);
        assert_close(fit.r2_log, 1.0, 0, 1e-12);
        assert_close(fit.rmse, 0.0, 0, 1e-9 * p[0]);
        assert_close(fit.rmse_log, 0.0, 0, 1e-9);
        assert_int_equal(fit.n_points, N);
        /* The data-driven start should land close: a handful of steps. */
        assert_true(fit.iterations > 0 && fit.iterations <= 10);
    }
}

static void test_fit_recovers_steady_state_range(void **state)
{
    (void)state;
    /* The range the brief calls typical: A from 1e3 to 8e6 m^2, slopes
     * near 0.8 falling to a few percent. */
    enum { N = 40 };
    double A[N], S[N];
    dfle_eq2_fit fit;
    dfle_error err = { 0, "" };
    make_eq2_data(N, 1e3, 8e6, 0.9, 5e4, 0.65, 0.0, A, S);
    assert_true(S[0] > 0.5 && S[N - 1] < 0.05);
    assert_ok(dfle_fit_eq2(N, A, S, &fit, &err), &err);
    assert_close(fit.S_df, 0.9, 1e-6, 0);
    assert_close(fit.A_df, 5e4, 1e-6, 0);
    assert_close(fit.a2, 0.65, 1e-6, 0);
}

static void test_fit_transition_beyond_data(void **state)
{
    (void)state;
    /* A_df lies above every area, so the slope falls by only 0.2 % over
     * the data; a start in the middle of the data slides into the flat
     * a2 -> 0 valley instead.  Only a start from the data finds it. */
    enum { N = 50 };
    double A[N], S[N];
    dfle_eq2_fit fit;
    dfle_error err = { 0, "" };
    make_eq2_data(N, 1e3, 8e6, 0.3, 1e8, 2.5, 0.0, A, S);
    assert_ok(dfle_fit_eq2(N, A, S, &fit, &err), &err);
    assert_close(fit.S_df, 0.3, 1e-6, 0);
    assert_close(fit.A_df, 1e8, 1e-6, 0);
    assert_close(fit.a2, 2.5, 1e-6, 0);
}

static void test_fit_recovers_with_noise(void **state)
{
    (void)state;
    enum { N = 200 };
    double A[N], S[N];
    lcg_state = 12345;
    for (size_t c = 0; c < N_CASES; c++) {
        const double *p = eq2_cases[c];
        dfle_eq2_fit fit;
        dfle_error err = { 0, "" };
        make_eq2_data(N, 1e2, 1e8, p[0], p[1], p[2], 0.05, A, S);
        assert_ok(dfle_fit_eq2(N, A, S, &fit, &err), &err);
        assert_close(fit.S_df, p[0], 0.03, 0);
        assert_close(fit.A_df, p[1], 0.08, 0);
        assert_close(fit.a2, p[2], 0.03, 0);
        assert_true(fit.r2 > 0.98 && fit.r2 < 1.0);

        /* r2 and rmse must be those of the returned parameters. */
        double mean = 0, ss_res = 0, ss_tot = 0;
        for (size_t i = 0; i < N; i++)
            mean += S[i] / N;
        for (size_t i = 0; i < N; i++) {
            double r = dfle_eq2_eval(fit.S_df, fit.A_df, fit.a2, A[i]) - S[i];
            ss_res += r * r;
            ss_tot += (S[i] - mean) * (S[i] - mean);
        }
        assert_close(fit.r2, 1.0 - ss_res / ss_tot, 1e-10, 0);
        assert_close(fit.rmse, sqrt(ss_res / N), 1e-10, 0);
    }
}

static void test_fit_is_least_squares(void **state)
{
    (void)state;
    /* With noise, the returned parameters must be a minimum of the
     * squared misfit: nudging any parameter must not lower it. */
    enum { N = 50 };
    double A[N], S[N];
    dfle_eq2_fit fit;
    dfle_error err = { 0, "" };
    lcg_state = 99;
    make_eq2_data(N, 1e3, 1e7, 0.7, 8e4, 1.1, 0.1, A, S);
    assert_ok(dfle_fit_eq2(N, A, S, &fit, &err), &err);
    double best[3] = { fit.S_df, fit.A_df, fit.a2 };
    double sse0 = 0;
    for (size_t i = 0; i < N; i++) {
        double r = dfle_eq2_eval(best[0], best[1], best[2], A[i]) - S[i];
        sse0 += r * r;
    }
    for (int j = 0; j < 3; j++) {
        for (int sign = -1; sign <= 1; sign += 2) {
            double p[3] = { best[0], best[1], best[2] };
            p[j] *= 1.0 + sign * 1e-3;
            double sse = 0;
            for (size_t i = 0; i < N; i++) {
                double r = dfle_eq2_eval(p[0], p[1], p[2], A[i]) - S[i];
                sse += r * r;
            }
            assert_true(sse > sse0);
        }
    }
}

static void test_fit_slope_summaries(void **state)
{
    (void)state;
    /* Unsorted input: the channel head is the smallest area (A = 10),
     * not the first point; the largest slope is elsewhere. */
    const double A[] = { 1e4, 1e5, 10, 1e3, 1e6, 1e2 };
    const double S[] = { 0.4, 0.12, 0.6, 0.75, 0.03, 0.7 };
    dfle_eq2_fit fit;
    dfle_error err = { 0, "" };
    int st = dfle_fit_eq2(6, A, S, &fit, &err);
    assert_ok(st, &err);
    assert_close(fit.S_ch, 0.6, 0, 0);
    assert_close(fit.S_max, 0.75, 0, 0);
    assert_close(fit.S_max_minus_S_ch, 0.15, 1e-14, 0);
    assert_int_equal(fit.n_points, 6);
}

static void test_fit_degenerate_data(void **state)
{
    (void)state;
    enum { N = 30 };
    double A[N], S[N];
    dfle_eq2_fit fit;
    dfle_error err = { 0, "" };

    /* A pure power law is Eq. (2) only in the limit S_df -> Inf,
     * A_df -> 0, where the two are not separately determined. */
    for (size_t i = 0; i < N; i++) {
        A[i] = 1e3 * pow(1e4, i / (N - 1.0));
        S[i] = 20.0 * pow(A[i], -0.5);
    }
    memset(&fit, 0xff, sizeof fit);
    assert_int_equal(dfle_fit_eq2(N, A, S, &fit, &err), DFLE_EFIT);
    assert_msg_contains(err.msg, "pure power law");
    assert_int_equal(fit.n_points, 0);
    assert_close(fit.S_df, 0.0, 0, 0);

    /* Nearly constant slope: the transition lies beyond the data.
     * Failure must be reported, never a NaN or a wandering A_df. */
    lcg_state = 3;
    for (size_t i = 0; i < N; i++)
        S[i] = 0.3 * (1.0 + 1e-3 * (2.0 * lcg_uniform() - 1.0));
    int st = dfle_fit_eq2(N, A, S, &fit, &err);
    if (st == DFLE_OK) {
        assert_true(isfinite(fit.S_df) && isfinite(fit.a2) && isfinite(fit.r2));
        assert_true(fit.A_df >= 1e-1 && fit.A_df <= 1e11);
        assert_true(fit.rmse < 1e-3);
    } else {
        assert_int_equal(st, DFLE_EFIT);
        assert_msg_contains(err.msg, "slope-area fit:");
    }

    /* Curved data whose A_df sits just below the smallest area are still
     * a fit, not a power law. */
    make_eq2_data(N, 1e3, 1e7, 2.0, 300.0, 0.8, 0.0, A, S);
    assert_ok(dfle_fit_eq2(N, A, S, &fit, &err), &err);
    assert_close(fit.A_df, 300.0, 1e-6, 0);

    /* Exactly constant slope cannot be fitted at all. */
    for (size_t i = 0; i < N; i++)
        S[i] = 0.3;
    assert_int_equal(dfle_fit_eq2(N, A, S, &fit, &err), DFLE_EFIT);
    assert_msg_contains(err.msg, "all 30 slopes equal 0.3");
}

static void test_fit_errors(void **state)
{
    (void)state;
    const double A[] = { 1e3, 1e4, 1e5, 1e6, 1e7 };
    const double S[] = { 0.8, 0.5, 0.2, 0.05, 0.01 };
    const double S_zero[] = { 0.8, 0.5, 0.0, 0.05, 0.01 };
    const double S_neg[] = { 0.8, 0.5, 0.2, -0.05, 0.01 };
    const double A_bad[] = { 1e3, 1e4, NAN, 1e6, 1e7 };
    const double A_two[] = { 1e3, 1e3, 1e7, 1e7, 1e7 };
    dfle_eq2_fit fit;
    dfle_error err = { 0, "" };

    memset(&fit, 0xff, sizeof fit);
    assert_int_equal(dfle_fit_eq2(3, A, S, &fit, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "slope-area fit: 3 points, need at least 4");
    assert_int_equal(fit.n_points, 0);

    assert_int_equal(dfle_fit_eq2(5, A, S_zero, &fit, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "point 2 has slope 0");
    assert_int_equal(dfle_fit_eq2(5, A, S_neg, &fit, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "point 3 has slope -0.05");
    assert_msg_contains(err.msg, "positive");
    assert_int_equal(dfle_fit_eq2(5, A_bad, S, &fit, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "point 2 has area NaN");
    assert_int_equal(dfle_fit_eq2(5, A_two, S, &fit, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "fewer than 3 distinct areas");
    assert_int_equal(dfle_fit_eq2(5, A, NULL, &fit, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "slope array is NULL");
    assert_int_equal(dfle_fit_eq2(5, A, S, NULL, &err), DFLE_EINVAL);
    assert_int_equal(dfle_fit_eq2(2, A, S, &fit, NULL), DFLE_EINVAL);
}

/* ---------------------------------------------------------------- */
/* Bin then fit                                                     */
/* ---------------------------------------------------------------- */

/* A dense profile like a 5 m grid: x = 0..2010 m every 5 m, area growing
 * as 1000 + 25 x^(5/3) (1e3 to 8e6 m^2), slope from Eq. (2). */
enum { PROFILE_N = 403 };

static void make_profile(double S_df, double A_df, double a2, double *A,
                         double *S)
{
    for (size_t i = 0; i < PROFILE_N; i++) {
        double x = 5.0 * (double)i;
        A[i] = 1000.0 + 25.0 * pow(x, 5.0 / 3.0);
        S[i] = dfle_eq2_eval(S_df, A_df, a2, A[i]);
    }
}

static void test_slope_area_fit_dense_profile(void **state)
{
    (void)state;
    static double A[PROFILE_N], S[PROFILE_N];
    const double cases[][3] = { { 0.8, 3e4, 0.9 }, { 0.9, 5e4, 0.65 },
                                { 0.6, 2e5, 1.2 } };
    for (size_t c = 0; c < 3; c++) {
        const double *p = cases[c];
        dfle_bins b;
        dfle_eq2_fit fit;
        dfle_error err = { 0, "" };
        make_profile(p[0], p[1], p[2], A, S);
        assert_ok(dfle_slope_area_fit(PROFILE_N, A, S, 100, &b, &fit, &err), &err);
        assert_int_equal(b.nbins, 100);
        assert_int_equal(b.n + b.n_empty, 100);
        assert_true(b.n_empty > 0); /* the sparse channel-head end */
        assert_int_equal(fit.n_points, b.n);
        assert_close(b.A_lo[0], 1000.0, 0, 0);
        assert_close(b.A_hi[b.n - 1], A[PROFILE_N - 1], 0, 0);
        /* Bin means are not Eq. (2) at the bin's mean area, so the
         * recovery is to the bin-averaging error, not machine precision. */
        assert_close(fit.S_df, p[0], 0.01, 0);
        assert_close(fit.A_df, p[1], 0.02, 0);
        assert_close(fit.a2, p[2], 0.01, 0);
        assert_true(fit.r2 > 0.9999);
        assert_close(fit.S_ch, b.S_mean[0], 0, 0);
        assert_close(fit.S_max_minus_S_ch, 0.0, 0, 0); /* monotone profile */
        dfle_bins_release(&b);
    }
}

static void test_slope_area_fit_without_bins(void **state)
{
    (void)state;
    static double A[PROFILE_N], S[PROFILE_N];
    dfle_bins b;
    dfle_eq2_fit with, without;
    dfle_error err = { 0, "" };
    make_profile(0.8, 3e4, 0.9, A, S);
    assert_ok(dfle_slope_area_fit(PROFILE_N, A, S, 100, &b, &with, &err), &err);
    assert_ok(dfle_slope_area_fit(PROFILE_N, A, S, 100, NULL, &without, &err), &err);
    assert_close(without.S_df, with.S_df, 0, 0);
    assert_close(without.A_df, with.A_df, 0, 0);
    assert_close(without.a2, with.a2, 0, 0);
    dfle_bins_release(&b);
}

static void test_slope_area_fit_skips_nonpositive_bins(void **state)
{
    (void)state;
    /* 50 bins; points in bins 10 and 20 are given negative or zero slope
     * (flats and reverse slopes in a noisy DEM). */
    enum { N = 500 };
    double A[N], S[N];
    make_eq2_data(N, 1e3, 1e7, 0.8, 3e4, 0.9, 0.0, A, S);
    for (size_t i = 100; i < 110; i++)
        S[i] = -0.01;
    for (size_t i = 200; i < 210; i++)
        S[i] = 0.0;
    dfle_bins b;
    dfle_eq2_fit fit;
    dfle_error err = { 0, "" };
    assert_ok(dfle_slope_area_fit(N, A, S, 50, &b, &fit, &err), &err);
    assert_int_equal(b.n, 50);
    size_t nonpositive = 0;
    for (size_t k = 0; k < b.n; k++)
        nonpositive += b.S_mean[k] <= 0.0;
    assert_int_equal(nonpositive, 2);
    assert_int_equal(fit.n_points, 48);
    assert_close(fit.S_df, 0.8, 0.01, 0);
    assert_close(fit.a2, 0.9, 0.01, 0);
    dfle_bins_release(&b);
}

static void test_slope_area_fit_errors(void **state)
{
    (void)state;
    const double A[] = { 1, 10, 100, 1000, 1e4, 1e5 };
    const double S[] = { 0.5, 0.4, -0.3, -0.2, 0.1, 0.05 };
    dfle_bins b;
    dfle_eq2_fit fit;
    dfle_error err = { 0, "" };

    /* Three bins, all non-empty; the middle one has a negative mean. */
    memset(&b, 0xff, sizeof b);
    assert_int_equal(dfle_slope_area_fit(6, A, S, 3, &b, &fit, &err), DFLE_EFIT);
    assert_msg_contains(err.msg, "2 of 3 non-empty bins have a positive mean");
    assert_null(b.A); /* released on failure */
    assert_int_equal(b.n, 0);

    assert_int_equal(dfle_slope_area_fit(6, A, S, 0, &b, &fit, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "nbins is 0");
    assert_int_equal(dfle_slope_area_fit(6, A, S, 10, &b, NULL, &err), DFLE_EINVAL);
    assert_null(b.A);
}

static void test_eq2_eval(void **state)
{
    (void)state;
    assert_close(dfle_eq2_eval(0.8, 3e4, 0.9, 3e4), 0.4, 1e-15, 0);
    assert_close(dfle_eq2_eval(0.8, 3e4, 0.9, 0.0), 0.8, 0, 0);
    assert_close(dfle_eq2_eval(1.1, 1e4, 1.0, 1e5), 0.1, 1e-14, 0);
    assert_close(dfle_eq2_eval(1.0, 1e4, 2.0, 1e3), 1.0 / 1.01, 1e-15, 0);
    assert_close(dfle_eq2_eval(0.5, 5e3, 0.6, 5e3 * 32.0),
                 0.5 / (1.0 + pow(32.0, 0.6)), 1e-15, 0);
    /* far beyond A_df, Eq. (2) tends to S_df (A / A_df)^-a2 */
    assert_close(dfle_eq2_eval(0.7, 1e4, 1.5, 1e12), 0.7 * pow(1e8, -1.5), 1e-10, 0);
}

/* ---------------------------------------------------------------- */
/* Residuals in log S                                               */
/* ---------------------------------------------------------------- */

/* A standard normal deviate (Box-Muller on the LCG). */
static double lcg_normal(void)
{
    double u1 = 1.0 - lcg_uniform(), u2 = lcg_uniform();
    return sqrt(-2.0 * log(u1)) * cos(2.0 * 3.14159265358979323846 * u2);
}

/* Multiplicative log-normal noise, S = S_eq2 exp(sigma e), as DEM
 * slopes have: the log fit is unbiased; the linear fit on bin means
 * follows E[S] = S_eq2 exp(sigma^2 / 2), so its S_df comes out high by
 * that factor, and its misfit is dominated by the steep bins. */
static void test_log_fit_unbiased_with_lognormal_noise(void **state)
{
    (void)state;
    enum { N = 40000 };
    const double S_df = 0.8, A_df = 3e4, a2 = 0.9, sigma = 0.5;
    double *A = malloc(N * sizeof *A), *S = malloc(N * sizeof *S);
    dfle_eq2_fit lin, lg;
    dfle_error err = { 0, "" };
    assert_non_null(A);
    assert_non_null(S);
    lcg_state = 12345;
    for (size_t i = 0; i < N; i++) {
        A[i] = 1e3 * pow(1e4, lcg_uniform()); /* log-uniform over 1e3 .. 1e7 m^2 */
        S[i] = dfle_eq2_eval(S_df, A_df, a2, A[i]) * exp(sigma * lcg_normal());
    }
    assert_ok(dfle_slope_area_fit_residuals(N, A, S, 40, DFLE_RESIDUALS_LOG, NULL, &lg, &err),
              &err);
    assert_ok(dfle_slope_area_fit_residuals(N, A, S, 40, DFLE_RESIDUALS_LINEAR, NULL, &lin, &err),
              &err);
    assert_int_equal(lg.residuals, DFLE_RESIDUALS_LOG);
    assert_int_equal(lin.residuals, DFLE_RESIDUALS_LINEAR);
    /* The log fit: each within a few percent. */
    assert_close(lg.S_df, S_df, 0.03, 0);
    assert_close(lg.A_df, A_df, 0.10, 0);
    assert_close(lg.a2, a2, 0.03, 0);
    /* The linear fit: S_df high by about exp(sigma^2 / 2) = 1.133. */
    assert_close(lin.S_df / S_df, exp(sigma * sigma / 2), 0.04, 0);
    assert_true(fabs(log(lg.S_df / S_df)) < 0.25 * fabs(log(lin.S_df / S_df)));
    /* Each fit is the better one in its own space. */
    assert_true(lg.r2_log >= lin.r2_log);
    assert_true(lin.r2 >= lg.r2);
    assert_true(lg.r2_log > 0.99 && lin.r2 > 0.99);
    free(A);
    free(S);
}

/* R^2 by hand on three points, with S_df = 1, A_df = 1, a2 = 1, so
 * S_model = 1 / (1 + A) = 0.5, 0.25, 0.125 at A = 1, 3, 7, and data
 * S = 0.6, 0.2, 0.125:
 *   linear: residuals 0.1, -0.05, 0 -> SS_res = 0.0125; mean S = 0.925/3,
 *     SS_tot = (0.6 - m)^2 + (0.2 - m)^2 + (0.125 - m)^2 = 0.130416667;
 *   log10: residuals log10(1.2), log10(0.8), 0; SS_tot about the mean of
 *     log10 0.6, log10 0.2, log10 0.125. */
/* Far past A_df with a large a2, Eq. (2) underflows to S = 0; in log
 * space it is merely far off: log10 S = -log10(1 + A^400) = -400 log10 A
 * here (A_df = 1, S_df = 1), so the residuals are -399, -798, -1197
 * against y = -1, -2, -3 (mean -2, SS_tot = 2).  log10(0) made it -inf. */
static void test_r2_log_without_underflow(void **state)
{
    (void)state;
    const double A[3] = { 10, 100, 1000 }, S[3] = { 0.1, 0.01, 0.001 };
    double r2 = dfle_eq2_r2(1.0, 1.0, 400.0, 3, A, S, DFLE_RESIDUALS_LOG);
    assert_true(isfinite(r2));
    assert_close(r2, 1.0 - (399.0 * 399 + 798.0 * 798 + 1197.0 * 1197) / 2.0, 1e-12, 0);
}

static void test_r2_by_hand(void **state)
{
    (void)state;
    const double A[3] = { 1, 3, 7 }, S[3] = { 0.6, 0.2, 0.125 };
    double m = (log10(0.6) + log10(0.2) + log10(0.125)) / 3;
    double ss_tot_log = (log10(0.6) - m) * (log10(0.6) - m) + (log10(0.2) - m) * (log10(0.2) - m) +
                        (log10(0.125) - m) * (log10(0.125) - m);
    double ss_res_log = log10(1.2) * log10(1.2) + log10(0.8) * log10(0.8);
    assert_close(dfle_eq2_r2(1, 1, 1, 3, A, S, DFLE_RESIDUALS_LINEAR),
                 1.0 - 0.0125 / 0.13041666666666667, 1e-12, 0);
    assert_close(dfle_eq2_r2(1, 1, 1, 3, A, S, DFLE_RESIDUALS_LOG),
                 1.0 - ss_res_log / ss_tot_log, 1e-12, 0);
    /* the hand numbers themselves: 0.904153 and 0.935937 */
    assert_close(dfle_eq2_r2(1, 1, 1, 3, A, S, DFLE_RESIDUALS_LINEAR), 0.904153, 1e-6, 0);
    assert_close(dfle_eq2_r2(1, 1, 1, 3, A, S, DFLE_RESIDUALS_LOG), 0.935937, 1e-6, 0);
    /* undefined for fewer than two points or equal values */
    assert_true(isnan(dfle_eq2_r2(1, 1, 1, 1, A, S, DFLE_RESIDUALS_LINEAR)));
    assert_true(isnan(dfle_eq2_r2(1, 1, 1, 2, A, (const double[]){ 0.3, 0.3 },
                                  DFLE_RESIDUALS_LOG)));
}

/* Bins: the geometric mean is over the positive slopes; a bin with none
 * has 0, and is left out of a log fit but not of a linear one. */
static void test_bins_geometric_mean(void **state)
{
    (void)state;
    const double A[6] = { 1, 1.1, 1.2, 10, 10.5, 11 };
    const double S[6] = { 0.1, 0.4, 0.0, -0.1, 0.0, 0.2 };
    dfle_bins b;
    dfle_error err = { 0, "" };
    assert_ok(dfle_bins_compute(6, A, S, 2, &b, &err), &err);
    assert_int_equal(b.n, 2);
    assert_close(b.S_geomean[0], 0.2, 1e-12, 0); /* sqrt(0.1 * 0.4); the flat left out */
    assert_close(b.S_geomean[1], 0.2, 1e-12, 0);
    dfle_bins_release(&b);
    const double S2[6] = { 0.1, 0.4, 0.0, -0.1, 0.0, -0.2 };
    assert_ok(dfle_bins_compute(6, A, S2, 2, &b, &err), &err);
    assert_true(b.S_geomean[1] == 0.0);
    dfle_bins_release(&b);
}

/* A bad residuals value is refused, naming it. */
static void test_residuals_checked(void **state)
{
    (void)state;
    enum { N = 61 };
    double A[N], S[N];
    dfle_eq2_fit fit;
    dfle_error err = { 0, "" };
    make_eq2_data(N, 1e2, 1e8, 0.8, 3e4, 0.9, 0.0, A, S);
    assert_int_equal(dfle_slope_area_fit_residuals(N, A, S, 10, (dfle_residuals)7, NULL, &fit,
                                                   &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "residuals 7");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bins_known_statistics),
        cmocka_unit_test(test_bins_single_point_and_even_count),
        cmocka_unit_test(test_bins_empty_dropped),
        cmocka_unit_test(test_bins_largest_area_in_last_bin),
        cmocka_unit_test(test_bins_points_on_edges),
        cmocka_unit_test(test_bins_skip_unusable_pairs),
        cmocka_unit_test(test_bins_errors),
        cmocka_unit_test(test_bins_release_idempotent),
        cmocka_unit_test(test_fit_recovers_noise_free),
        cmocka_unit_test(test_fit_recovers_steady_state_range),
        cmocka_unit_test(test_fit_transition_beyond_data),
        cmocka_unit_test(test_fit_recovers_with_noise),
        cmocka_unit_test(test_fit_is_least_squares),
        cmocka_unit_test(test_fit_slope_summaries),
        cmocka_unit_test(test_fit_degenerate_data),
        cmocka_unit_test(test_fit_errors),
        cmocka_unit_test(test_slope_area_fit_dense_profile),
        cmocka_unit_test(test_slope_area_fit_without_bins),
        cmocka_unit_test(test_slope_area_fit_skips_nonpositive_bins),
        cmocka_unit_test(test_slope_area_fit_errors),
        cmocka_unit_test(test_eq2_eval),
        cmocka_unit_test(test_log_fit_unbiased_with_lognormal_noise),
        cmocka_unit_test(test_r2_by_hand),
        cmocka_unit_test(test_r2_log_without_underflow),
        cmocka_unit_test(test_bins_geometric_mean),
        cmocka_unit_test(test_residuals_checked),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
