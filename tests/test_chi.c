/*
 * test_chi.c - chi, k_sn and concavity (chi.h) against analytical cases.
 *
 * A steady channel of the stream-power law U = K A^m S^n has slope
 * S = k_s A^-theta, k_s = (U/K)^(1/n), theta = m/n.  Discretised as dfle's
 * models and landscapes are (each cell's slope to its receiver, with the
 * cell's own area) its elevations are z_i = z_r + L_i k_s A_i^-theta,
 * summed from base level; on such a channel, or a network of them, with
 * theta_ref = theta and A0 = 1 m^2, chi-z must be one line of slope k_s
 * and k_sn = k_s at every cell, exactly, and both concavity methods must
 * find theta.  Along a continuous channel with Hack's law A = c s^h (s
 * the distance from the divide) the elevation is an integral in closed
 * form, which the link sums of chi approach at first order in the cell
 * size.
 */
#include <string.h>

#include "dfle/chi.h"
#include "dfle_test.h"

/* U = 1e-3 m/yr, K = 1e-5 (n = 1), m = 0.45: k_s = 100, theta = 0.45. */
#define KS 100.0
#define THETA 0.45

enum { MAXN = 40000 };
static size_t rcv[MAXN];
static double len[MAXN], area[MAXN], elev[MAXN];

/* The integral of (c s^h)^-theta ds from s to L (c, h > 0, h theta != 1). */
static double hack_integral(double c, double h, double theta, double s, double L)
{
    double p = 1 - h * theta;
    return pow(c, -theta) * (pow(L, p) - pow(s, p)) / p;
}

/* A chain with Hack's law from s = s0 to s = L (the outlet, base level at
 * z_b) every ds m, cells head first from index `at`; returns the next
 * free index.  continuous: elevations of the continuous channel (the
 * integral); else the discrete steady state z_i = z_r + ds ks A_i^-theta. */
static size_t chain_of(size_t at, double c, double h, double s0, double L, double ds, double z_b,
                       double ks, double theta, int continuous)
{
    size_t m = (size_t)llround((L - s0) / ds) + 1;
    for (size_t k = 0; k < m; k++) {
        double s = s0 + (double)k * ds;
        size_t i = at + k;
        area[i] = c * pow(s, h);
        rcv[i] = k + 1 < m ? i + 1 : i;
        len[i] = ds;
    }
    elev[at + m - 1] = z_b;
    for (size_t k = m - 1; k-- > 0;) {
        size_t i = at + k;
        elev[i] = continuous ? z_b + ks * hack_integral(c, h, theta, s0 + (double)k * ds, L)
                             : elev[i + 1] + ds * ks * pow(area[i], -theta);
    }
    return at + m;
}

static size_t chain(size_t at, double c, double h, double s0, double L, double ds, double z_b,
                    double ks, double theta)
{
    return chain_of(at, c, h, s0, L, ds, z_b, ks, theta, 0);
}

static dfle_tree tree_of(size_t n)
{
    return (dfle_tree){n, rcv, len, area, elev};
}

static void test_steady_profile_is_one_line(void **state)
{
    (void)state;
    /* 10 km, 5 m cells, Hack c = 6.7, h = 1.67, from 100 m below the divide */
    size_t n = chain(0, 6.7, 1.67, 100, 10000, 5, 500, KS, THETA);
    dfle_tree t = tree_of(n);
    dfle_chi_opts o;
    dfle_chi c;
    dfle_error err = {0};
    double chi_head = 0;

    dfle_chi_opts_default(&o);
    o.theta_ref = THETA;
    assert_ok(dfle_chi_compute(&t, &o, &c, &err), &err);
    assert_int_equal(c.n_base, 1);
    assert_int_equal(c.n_fit, n - 1);
    assert_close(c.M_chi, KS, 1e-12, 0);
    assert_close(c.k_sn_fit, KS, 1e-12, 0);
    assert_true(c.r2 > 1 - 1e-12);
    assert_close(c.chi[n - 1], 0, 0, 0);
    assert_close(c.d[0], 10000 - 100, 1e-12, 0);
    for (size_t i = 0; i + 1 < n; i++)
        chi_head += 5 * pow(area[i], -THETA);
    assert_close(c.chi[0], chi_head, 1e-12, 0);
    for (size_t i = 0; i + 1 < n; i += 97) /* over one link: S A^theta */
        assert_close(c.k_sn[i], KS, 1e-12, 0);
    assert_true(isnan(c.k_sn[n - 1])); /* base level: no link */
    dfle_chi_release(&c);

    /* A0 = 1e6 m^2: the line's slope is k_s A0^-theta, k_sn still k_s */
    o.A0 = 1e6;
    o.window = 250;
    assert_ok(dfle_chi_compute(&t, &o, &c, &err), &err);
    assert_close(c.M_chi, KS * pow(1e6, -THETA), 1e-12, 0);
    assert_close(c.k_sn_fit, KS, 1e-12, 0);
    for (size_t i = 0; i < n; i += 89)
        assert_close(c.k_sn[i], KS, 1e-12, 0);
    assert_close(c.k_sn[n - 1], KS, 1e-12, 0); /* the window's upper half */
    dfle_chi_release(&c);

    /* another theta_ref bends the line: k_sn varies, R^2 drops */
    o.A0 = 1;
    o.theta_ref = 0.2;
    assert_ok(dfle_chi_compute(&t, &o, &c, &err), &err);
    assert_true(c.r2 < 0.999);
    assert_true(c.k_sn[0] > 2 * c.k_sn[n - 2]);
    dfle_chi_release(&c);
}

/* The continuous channel: chi-z's slope tends to k_s as the cells shrink,
 * the error halving with the cell size (first order). */
static void test_continuous_profile_converges(void **state)
{
    (void)state;
    double e[3];
    const double ds[3] = {4, 2, 1};
    for (int k = 0; k < 3; k++) {
        size_t n = chain_of(0, 6.7, 1.67, 100, 10000, ds[k], 0, KS, THETA, 1);
        dfle_tree t = tree_of(n);
        dfle_chi_opts o;
        dfle_chi c;
        dfle_error err = {0};
        dfle_chi_opts_default(&o);
        o.theta_ref = THETA;
        assert_ok(dfle_chi_compute(&t, &o, &c, &err), &err);
        e[k] = c.M_chi / KS - 1;
        assert_true(c.r2 > 1 - 1e-5);
        dfle_chi_release(&c);
    }
    assert_true(fabs(e[2]) < 2e-3);
    assert_close(e[0] / e[1], 2, 0.05, 0);
    assert_close(e[1] / e[2], 2, 0.05, 0);
}

/* n = 2: m = 1, U/K = 100, so k_s = 10 and theta = 0.5. */
static void test_nonlinear_stream_power(void **state)
{
    (void)state;
    double ks = sqrt(1e-3 / 1e-5), theta = 1.0 / 2.0;
    size_t n = chain(0, 3.0, 1.8, 50, 8000, 2, 0, ks, theta);
    dfle_tree t = tree_of(n);
    dfle_chi_opts o;
    dfle_chi c;
    dfle_concavity cc;
    dfle_concavity_opts co;
    dfle_error err = {0};
    dfle_chi_opts_default(&o);
    o.theta_ref = theta;
    assert_ok(dfle_chi_compute(&t, &o, &c, &err), &err);
    assert_close(c.k_sn_fit, ks, 1e-5, 0);
    dfle_chi_release(&c);
    dfle_concavity_opts_default(&co);
    assert_ok(dfle_concavity_chi(&t, &co, &cc, &err), &err);
    assert_close(cc.theta, theta, 0, 1e-3);
    assert_close(cc.k_s, ks, 1e-2, 0);
    assert_false(cc.at_bound);
    dfle_concavity_release(&cc);
}

/* Two tributaries of different size join a trunk whose area grows
 * linearly downstream: all three steady at k_s, theta, so one chi-z line. */
static size_t branching(double ks, double theta)
{
    const double L1 = 4000, L2 = 2500, ds = 1, Lt = 3000, q = 200; /* q: m^2 per m */
    const double c1 = 6.7, c2 = 3.1, h = 1.67;
    double A_conf = c1 * pow(L1, h) + c2 * pow(L2, h);
    size_t mt = (size_t)llround(Lt / ds), a, b;
    /* the trunk, from just below the confluence to the outlet */
    for (size_t k = 0; k < mt; k++) {
        area[k] = A_conf + q * ds * (double)(k + 1);
        rcv[k] = k + 1 < mt ? k + 1 : k;
        len[k] = ds;
    }
    elev[mt - 1] = 0;
    for (size_t k = mt - 1; k-- > 0;)
        elev[k] = elev[k + 1] + ds * ks * pow(area[k], -theta);
    /* each tributary's last cell drains one ds to the trunk's first */
    a = chain(mt, c1, h, 50, L1, ds, elev[0] + ds * ks * pow(c1 * pow(L1, h), -theta), ks,
              theta);
    b = chain(a, c2, h, 80, L2, ds, elev[0] + ds * ks * pow(c2 * pow(L2, h), -theta), ks,
              theta);
    rcv[a - 1] = 0;
    rcv[b - 1] = 0;
    return b;
}

static void test_network_is_collinear(void **state)
{
    (void)state;
    size_t n = branching(KS, THETA);
    dfle_tree t = tree_of(n);
    dfle_chi_opts o;
    dfle_chi c;
    dfle_concavity cc;
    dfle_concavity_opts co;
    dfle_error err = {0};

    dfle_chi_opts_default(&o);
    o.theta_ref = THETA;
    assert_ok(dfle_chi_compute(&t, &o, &c, &err), &err);
    assert_int_equal(c.n_base, 1);
    assert_close(c.k_sn_fit, KS, 1e-12, 0);
    assert_true(c.r2 > 1 - 1e-12);
    dfle_chi_release(&c);

    dfle_concavity_opts_default(&co);
    assert_ok(dfle_concavity_chi(&t, &co, &cc, &err), &err);
    assert_close(cc.theta, THETA, 0, 2e-4);
    assert_close(cc.k_s, KS, 2e-3, 0);
    assert_false(cc.at_bound);
    assert_int_equal(cc.ncurve, 30); /* 0.05, 0.10, ..., 1.50 */
    assert_close(cc.curve_theta[0], 0.05, 0, 1e-12);
    assert_close(cc.curve_theta[29], 1.5, 0, 1e-12);
    for (size_t k = 0; k < cc.ncurve; k++)
        assert_true(cc.curve_r2[k] <= cc.r2 + 1e-12);
    dfle_concavity_release(&cc);

    /* a range that excludes theta: its end, flagged */
    co.theta_lo = 0.1;
    co.theta_hi = 0.3;
    assert_ok(dfle_concavity_chi(&t, &co, &cc, &err), &err);
    assert_close(cc.theta, 0.3, 0, 2e-4);
    assert_true(cc.at_bound);
    dfle_concavity_release(&cc);
}

static void test_slope_area_concavity(void **state)
{
    (void)state;
    enum { N = 3000 };
    static double A[N], S[N];
    dfle_concavity cc;
    dfle_concavity_opts co;
    dfle_error err = {0};
    for (int i = 0; i < N; i++) {
        A[i] = 900 * pow(1e4, i / (N - 1.0));
        S[i] = i < 300 ? 0.8 : KS * pow(A[i], -THETA); /* a steep head, then Flint's law */
    }
    dfle_concavity_opts_default(&co);
    co.A_min = A[300];
    assert_ok(dfle_concavity_slope_area(N, A, S, &co, &cc, &err), &err);
    assert_int_equal(cc.method, DFLE_CONCAVITY_SLOPE_AREA);
    assert_close(cc.theta, THETA, 1e-9, 0);
    assert_close(cc.k_s, KS, 1e-8, 0);
    assert_close(cc.r2, 1, 0, 1e-12);
    assert_true(cc.n > 50);
    /* the head in the fit flattens the line */
    co.A_min = 0;
    assert_ok(dfle_concavity_slope_area(N, A, S, &co, &cc, &err), &err);
    assert_true(cc.theta < THETA - 0.02);
    /* too narrow a range */
    co.A_min = A[10], co.A_max = A[11];
    assert_int_equal(dfle_concavity_slope_area(N, A, S, &co, &cc, &err), DFLE_EFIT);
    assert_msg_contains(err.msg, "too few");
}

/* Two catchments of different base level and size, the same k_s: one
 * line through each base level. */
static void test_two_outlets(void **state)
{
    (void)state;
    size_t a = chain(0, 6.7, 1.67, 100, 6000, 2, 300, KS, THETA);
    size_t n = chain(a, 2.0, 1.7, 60, 3000, 2, 1200, KS, THETA);
    dfle_tree t = tree_of(n);
    dfle_chi c;
    dfle_chi_opts o;
    dfle_error err = {0};
    dfle_chi_opts_default(&o);
    o.theta_ref = THETA;
    assert_ok(dfle_chi_compute(&t, &o, &c, &err), &err);
    assert_int_equal(c.n_base, 2);
    assert_close(c.z_base[0], 300, 0, 0);
    assert_close(c.z_base[a], 1200, 0, 0);
    assert_close(c.k_sn_fit, KS, 1e-5, 0);
    assert_true(c.r2 > 1 - 1e-9);
    dfle_chi_release(&c);
}

/* A knickpoint between k_s = 200 above and 100 below: a window of W m
 * measures each exactly beyond W/2 of it, and cells below A_min get no
 * k_sn and stay out of the line. */
static void test_window_and_knickpoint(void **state)
{
    (void)state;
    size_t n = chain(0, 6.7, 1.67, 100, 6000, 1, 0, KS, THETA), knick = 3000;
    dfle_tree t = tree_of(n);
    dfle_chi c;
    dfle_chi_opts o;
    dfle_error err = {0};
    /* above the knick, twice the drop per unit chi */
    for (size_t i = 0; i < knick; i++)
        elev[i] = elev[knick] + 2 * (elev[i] - elev[knick]);
    dfle_chi_opts_default(&o);
    o.theta_ref = THETA;
    o.window = 400;
    o.A_min = area[100];
    assert_ok(dfle_chi_compute(&t, &o, &c, &err), &err);
    assert_close(c.k_sn[knick - 201], 2 * KS, 1e-5, 0);
    assert_close(c.k_sn[knick + 201], KS, 1e-5, 0);
    assert_true(c.k_sn[knick] > KS * 1.3 && c.k_sn[knick] < KS * 1.7);
    assert_true(isnan(c.k_sn[50]));
    assert_int_equal(c.n_fit, n - 1 - 100);
    dfle_chi_release(&c);
}

static void test_bad_trees(void **state)
{
    (void)state;
    size_t n = chain(0, 6.7, 1.67, 100, 200, 10, 0, KS, THETA);
    dfle_tree t = tree_of(n);
    dfle_chi c;
    dfle_chi_opts o;
    dfle_error err = {0};
    dfle_chi_opts_default(&o);

    rcv[n - 1] = 0; /* the outlet drains back to the head: a cycle */
    len[n - 1] = 10;
    assert_int_equal(dfle_chi_compute(&t, &o, &c, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "cycle");
    dfle_chi_release(&c);
    rcv[n - 1] = n - 1;
    rcv[2] = n + 5;
    assert_int_equal(dfle_chi_compute(&t, &o, &c, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "cell 2 drains to");
    rcv[2] = 3;
    area[4] = NAN;
    assert_int_equal(dfle_chi_compute(&t, &o, &c, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "cell 4 has drainage area");
    area[4] = 10;
    len[3] = 0;
    assert_int_equal(dfle_chi_compute(&t, &o, &c, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "over 0 m");
    len[3] = 10;
    o.theta_ref = -1;
    assert_int_equal(dfle_chi_compute(&t, &o, &c, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "theta_ref");
    dfle_chi_opts_default(&o);
    o.A_min = 1e12; /* no cell that large */
    assert_int_equal(dfle_chi_compute(&t, &o, &c, &err), DFLE_EFIT);
    assert_msg_contains(err.msg, "too few");
    dfle_chi_release(&c);
    dfle_chi_release(&c); /* idempotent */
    {
        dfle_concavity cc;
        dfle_concavity_opts co;
        dfle_concavity_opts_default(&co);
        co.theta_lo = 0.5, co.theta_hi = 0.4;
        assert_int_equal(dfle_concavity_chi(&t, &co, &cc, &err), DFLE_EINVAL);
        assert_msg_contains(err.msg, "range of theta");
        dfle_concavity_release(&cc);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_steady_profile_is_one_line),
        cmocka_unit_test(test_continuous_profile_converges),
        cmocka_unit_test(test_nonlinear_stream_power),
        cmocka_unit_test(test_network_is_collinear),
        cmocka_unit_test(test_slope_area_concavity),
        cmocka_unit_test(test_two_outlets),
        cmocka_unit_test(test_window_and_knickpoint),
        cmocka_unit_test(test_bad_trees),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
