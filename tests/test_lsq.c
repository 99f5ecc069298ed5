/*
 * test_lsq.c - the least-squares point estimate (Nelder-Mead with a
 * finite-difference covariance) and the log-slope likelihood.
 *
 * A straight line has a closed-form least-squares answer and covariance
 * s^2 (X^T X)^-1, which the simplex and the difference Jacobian must
 * reproduce; then a region without values (a failed forward run), a
 * bound that holds the answer, a fatal callback status, a parameter the
 * data cannot see.  The likelihood: log-log interpolation is exact on a
 * power law, areas outside the channel and non-positive slopes are
 * refused, the Gaussian log-likelihood has its textbook value.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>

#include "dfle/likelihood.h"
#include "dfle/lsq.h"
#include "dfle_test.h"

#define NPTS 20

typedef struct line_data {
    double t[NPTS], y[NPTS];
    double fail_above; /* c1 above this has no value (DFLE_EFIT) */
    int fatal;         /* return DFLE_ECALLBACK                  */
    int calls;
} line_data;

static void make_line(line_data *d)
{
    memset(d, 0, sizeof *d);
    for (int i = 0; i < NPTS; i++) {
        d->t[i] = i;
        /* deterministic "noise" */
        d->y[i] = 1.5 + 2.0 * i + 0.3 * sin(1.7 * i + 0.4);
    }
    d->fail_above = INFINITY;
}

static int line_res(void *ud, const double *u, double *r, dfle_error *err)
{
    line_data *d = ud;
    d->calls++;
    if (d->fatal)
        return dfle_error_set(err, DFLE_ECALLBACK, "callback broke");
    if (u[1] > d->fail_above)
        return DFLE_EFIT;
    for (int i = 0; i < NPTS; i++)
        r[i] = d->y[i] - (u[0] + u[1] * d->t[i]);
    return DFLE_OK;
}

/* Ordinary least squares in closed form: answer, s^2 and covariance. */
static void ols(const line_data *d, double *c, double *cov)
{
    double n = NPTS, st = 0, stt = 0, sy = 0, sty = 0, det, rss = 0;
    for (int i = 0; i < NPTS; i++) {
        st += d->t[i];
        stt += d->t[i] * d->t[i];
        sy += d->y[i];
        sty += d->t[i] * d->y[i];
    }
    det = n * stt - st * st;
    c[0] = (stt * sy - st * sty) / det;
    c[1] = (n * sty - st * sy) / det;
    for (int i = 0; i < NPTS; i++) {
        double e = d->y[i] - c[0] - c[1] * d->t[i];
        rss += e * e;
    }
    rss /= NPTS - 2;
    cov[0] = rss * stt / det;
    cov[1] = cov[2] = -rss * st / det;
    cov[3] = rss * n / det;
}

static void opts_line(dfle_lsq_opts *o, const double *u0, const double *step)
{
    memset(o, 0, sizeof *o);
    o->n = 2;
    o->m = NPTS;
    o->u0 = u0;
    o->step = step;
    o->tol = 1e-9;
}

static void test_line_matches_closed_form(void **state)
{
    line_data d;
    double u0[2] = {0, 0}, step[2] = {1, 1}, u[2], cov[4], c[2], cref[4];
    dfle_lsq_opts o;
    dfle_lsq_info info;
    dfle_error err;
    (void)state;
    make_line(&d);
    ols(&d, c, cref);
    opts_line(&o, u0, step);
    assert_ok(dfle_lsq_fit(&o, line_res, &d, u, cov, &info, &err), &err);
    assert_true(info.converged);
    assert_true(info.cov_ok);
    assert_int_equal(info.failed, 0);
    assert_close(u[0], c[0], 1e-6, 1e-7);
    assert_close(u[1], c[1], 1e-6, 1e-8);
    for (int k = 0; k < 4; k++)
        assert_close(cov[k], cref[k], 1e-5, 0);
    /* A known sigma replaces s^2. */
    o.sigma = 2.0;
    assert_ok(dfle_lsq_fit(&o, line_res, &d, u, cov, &info, &err), &err);
    assert_close(info.s2, 4.0, 1e-15, 0);
    assert_close(cov[3], cref[3] * 4.0 / (info.rss / (NPTS - 2)), 1e-5, 0);
}

static void test_failures_and_bounds(void **state)
{
    line_data d;
    double u0[2] = {0, 1.9}, step[2] = {1, 0.5}, u[2], cov[4], c[2], cref[4];
    double lo[2] = {-INFINITY, -INFINITY}, hi[2] = {INFINITY, INFINITY};
    dfle_lsq_opts o;
    dfle_lsq_info info;
    dfle_error err;
    (void)state;
    make_line(&d);
    ols(&d, c, cref);
    /* No value above c1 = 2.2: the search still finds c1 = 2.0. */
    d.fail_above = 2.2;
    opts_line(&o, u0, step);
    assert_ok(dfle_lsq_fit(&o, line_res, &d, u, cov, &info, &err), &err);
    assert_true(info.failed > 0);
    assert_close(u[1], c[1], 1e-6, 1e-8);
    /* A bound below the answer holds it there. */
    d.fail_above = INFINITY;
    hi[1] = 1.5;
    o.lo = lo;
    o.hi = hi;
    u0[1] = 1.0;
    assert_ok(dfle_lsq_fit(&o, line_res, &d, u, cov, &info, &err), &err);
    assert_true(u[1] <= 1.5);
    assert_close(u[1], 1.5, 0, 1e-4);
    /* A start without a value, and a fatal status. */
    hi[1] = INFINITY;
    d.fail_above = 0.5;
    assert_int_equal(dfle_lsq_fit(&o, line_res, &d, u, cov, &info, &err), DFLE_EFIT);
    d.fail_above = INFINITY;
    d.fatal = 1;
    assert_int_equal(dfle_lsq_fit(&o, line_res, &d, u, cov, &info, &err), DFLE_ECALLBACK);
    assert_msg_contains(err.msg, "callback broke");
    /* Too few residuals. */
    o.m = 2;
    d.fatal = 0;
    assert_int_equal(dfle_lsq_fit(&o, line_res, &d, u, cov, &info, &err), DFLE_EINVAL);
}

/* y depends on u0 + u1 only: J^T J is singular, no covariance. */
static int sum_res(void *ud, const double *u, double *r, dfle_error *err)
{
    (void)ud, (void)err;
    for (int i = 0; i < 5; i++)
        r[i] = (double)i - (u[0] + u[1]) * (double)i;
    return DFLE_OK;
}

static void test_unidentified(void **state)
{
    double u0[2] = {0.2, 0.3}, step[2] = {0.1, 0.1}, u[2], cov[4];
    dfle_lsq_opts o;
    dfle_lsq_info info;
    dfle_error err;
    (void)state;
    memset(&o, 0, sizeof o);
    o.n = 2;
    o.m = 5;
    o.u0 = u0;
    o.step = step;
    assert_ok(dfle_lsq_fit(&o, sum_res, NULL, u, cov, &info, &err), &err);
    assert_close(u[0] + u[1], 1.0, 1e-5, 0);
    assert_false(info.cov_ok);
    assert_msg_contains(info.why, "singular");
    assert_true(isnan(cov[0]));
}

static void test_slope_at_power_law(void **state)
{
    double A[50], S[50], Aq[4] = {1e3, 3.7e4, 2.2e6, 1e7}, Sq[4], r[4], y[4];
    dfle_error err;
    (void)state;
    for (int i = 0; i < 50; i++) {
        A[i] = 1e3 * pow(1e4, i / 49.0);
        S[i] = 2.0 * pow(A[i], -0.5);
    }
    assert_ok(dfle_slope_at(50, A, S, 4, Aq, Sq, &err), &err);
    for (int q = 0; q < 4; q++)
        assert_close(Sq[q], 2.0 * pow(Aq[q], -0.5), 1e-12, 0);
    for (int q = 0; q < 4; q++)
        y[q] = log(2.0 * pow(Aq[q], -0.5)) + 0.1 * q;
    assert_ok(dfle_log_slope_residuals(50, A, S, 4, Aq, y, r, &err), &err);
    for (int q = 0; q < 4; q++)
        assert_close(r[q], 0.1 * q, 0, 1e-12);
    Aq[0] = 999;
    assert_int_equal(dfle_slope_at(50, A, S, 4, Aq, Sq, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "outside the model channel's areas");
    Aq[0] = 2e3;
    S[3] = 0;
    assert_int_equal(dfle_slope_at(50, A, S, 4, Aq, Sq, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "positive finite slopes");
    assert_int_equal(dfle_slope_at(1, A, S, 1, Aq, Sq, &err), DFLE_EINVAL);
}

static void test_gauss_loglike(void **state)
{
    double r[3] = {0.1, -0.2, 0.3};
    double want = -0.5 * (0.01 + 0.04 + 0.09) / 0.04 - 3 * log(0.2) - 1.5 * log(2 * 3.141592653589793);
    (void)state;
    assert_close(dfle_gauss_loglike(3, r, 0.2), want, 1e-14, 0);
    assert_true(dfle_gauss_loglike(3, r, 0) == -INFINITY);
    r[1] = NAN;
    assert_true(dfle_gauss_loglike(3, r, 0.2) == -INFINITY);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_line_matches_closed_form),
        cmocka_unit_test(test_failures_and_bounds),
        cmocka_unit_test(test_unidentified),
        cmocka_unit_test(test_slope_at_power_law),
        cmocka_unit_test(test_gauss_loglike),
    };
    gsl_set_error_handler_off(); /* as a host must (doc/c-api.md) */
    return cmocka_run_group_tests(tests, NULL, NULL);
}
