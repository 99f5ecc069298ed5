/* test_flow1d.c - the two-phase flow solver against exact solutions and
 * invariants: Ritter's dam break, a pile at rest, a lake at rest, volume
 * conservation and positivity over the paper's parameter ranges. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dfle_test.h"
#include "dfle/flow1d.h"

/* Frictionless, inviscid: the shallow-water equations. */
static dfle_flow1d_params frictionless(void)
{
    dfle_flow1d_params p;
    dfle_flow1d_params_default(&p);
    p.mu_s = p.mu_2 = 0.0;
    p.eta = 0.0;
    p.lambda0 = 0.0;
    p.outlet_wall = 1;
    return p;
}

static dfle_flow1d *make(size_t n, double dx, double w, double S, const dfle_flow1d_params *p)
{
    double *wv = malloc(n * sizeof *wv), *Sv = malloc(n * sizeof *Sv);
    dfle_flow1d *f;
    dfle_error err;
    for (size_t k = 0; k < n; k++) {
        wv[k] = w;
        Sv[k] = S;
    }
    assert_ok(dfle_flow1d_new(n, dx, wv, Sv, p, &f, &err), &err);
    free(wv);
    free(Sv);
    return f;
}

/* Run to time T [s] with the solver's own stable steps. */
static double run_to(dfle_flow1d *f, double T, double *out_total)
{
    double t = 0.0, out = 0.0;
    while (t < T) {
        double dt = fmin(dfle_flow1d_stable_dt(f), T - t), o;
        assert_int_equal(dfle_flow1d_step(f, dt, t, &o, NULL), DFLE_OK);
        out += o;
        t += dt;
    }
    if (out_total != NULL)
        *out_total = out;
    return t;
}

/* Ritter (1892): dam of depth h0 at x0 over a dry, flat, frictionless bed. */
static double ritter_h(double x, double t, double x0, double h0, double g)
{
    double c0 = sqrt(g * h0), xi = (x - x0) / t;
    if (xi <= -c0)
        return h0;
    if (xi >= 2 * c0)
        return 0.0;
    return (2 * c0 - xi) * (2 * c0 - xi) / (9 * g);
}

static double dam_break_error(double dx)
{
    const double L = 1000, x0 = 500, h0 = 1, T = 30;
    dfle_flow1d_params p = frictionless();
    size_t n = (size_t)(L / dx + 0.5);
    dfle_flow1d *f = make(n, dx, 1.0, 0.0, &p);
    double *h = dfle_flow1d_h(f), err = 0;
    for (size_t k = 0; k < n; k++)
        h[k] = (k + 0.5) * dx < x0 ? h0 : 0.0;
    run_to(f, T, NULL);
    for (size_t k = 0; k < n; k++)
        err += fabs(h[k] - ritter_h((k + 0.5) * dx, T, x0, h0, p.g)) * dx;
    dfle_flow1d_free(f);
    return err / L; /* mean absolute error [m] */
}

static void dam_break_converges_to_ritter(void **state)
{
    const double dx[] = {8, 4, 2, 1};
    double e[4];
    (void)state;
    for (int i = 0; i < 4; i++)
        e[i] = dam_break_error(dx[i]);
    for (int i = 1; i < 4; i++) {
        double order = log(e[i - 1] / e[i]) / log(2.0);
        print_message("dam break dx = %g m: mean |h - h_Ritter| = %.3e m, observed order %.2f\n",
                      dx[i], e[i], order);
        /* First-order Godunov with a dry front: order between 0.5 and 1. */
        assert_true(order > 0.5);
    }
    assert_true(e[3] < 3e-3);
}

static void pile_below_friction_angle_stays_still(void **state)
{
    dfle_flow1d_params p;
    dfle_flow1d *f;
    double *h, *q, out;
    (void)state;
    dfle_flow1d_params_default(&p);
    p.lambda0 = 0.0; /* no pore pressure: full Coulomb friction mu_s = 0.384 */
    /* tan(theta) = 0.2 plus the edge pressure h/(2 dx) = 0.05 < mu_s. */
    f = make(60, 5.0, 1.0, 0.2, &p);
    h = dfle_flow1d_h(f);
    q = dfle_flow1d_q(f);
    for (size_t k = 10; k < 30; k++)
        h[k] = 0.5;
    run_to(f, 200.0, &out);
    for (size_t k = 0; k < 60; k++) {
        assert_close(h[k], k >= 10 && k < 30 ? 0.5 : 0.0, 0, 0);
        assert_close(q[k], 0.0, 0, 0);
    }
    assert_close(out, 0.0, 0, 0);
    dfle_flow1d_free(f);
}

static void pile_above_friction_angle_moves(void **state)
{
    dfle_flow1d_params p;
    dfle_flow1d *f;
    double *h, *q;
    (void)state;
    dfle_flow1d_params_default(&p);
    p.lambda0 = 0.0;
    f = make(60, 5.0, 1.0, 0.5, &p); /* tan(theta) = 0.5 > mu_s = 0.384: it must slide */
    h = dfle_flow1d_h(f);
    q = dfle_flow1d_q(f);
    for (size_t k = 10; k < 30; k++)
        h[k] = 0.5;
    run_to(f, 5.0, NULL);
    double qmax = 0;
    for (size_t k = 0; k < 60; k++)
        qmax = fmax(qmax, q[k]);
    assert_true(qmax > 0.1);
    dfle_flow1d_free(f);
}

static void lake_at_rest_in_a_widening_channel(void **state)
{
    dfle_flow1d_params p = frictionless();
    double w[50], S[50];
    dfle_flow1d *f;
    dfle_error err;
    (void)state;
    for (int k = 0; k < 50; k++) {
        w[k] = 1.0 + 0.3 * sin(0.4 * k) + 0.02 * k; /* any positive width */
        S[k] = 0.0;
    }
    assert_ok(dfle_flow1d_new(50, 2.0, w, S, &p, &f, &err), &err);
    for (int k = 0; k < 50; k++)
        dfle_flow1d_h(f)[k] = 1.5;
    run_to(f, 100.0, NULL);
    for (int k = 0; k < 50; k++) {
        assert_close(dfle_flow1d_h(f)[k], 1.5, 1e-13, 0);
        assert_close(dfle_flow1d_q(f)[k], 0.0, 0, 1e-12);
    }
    dfle_flow1d_free(f);
}

/* A release on a steep slope with the paper's physics, out of an open
 * outlet: volume in = out + left to round-off, depth never negative,
 * nothing non-finite, across the Table G2/G4 parameter ranges. */
static void conservation_and_positivity_over_parameter_ranges(void **state)
{
    const double mu2[] = {0.532, 0.62, 0.869}, D[] = {1e-6, 1e-5}, eta[] = {30, 90};
    (void)state;
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 2; b++)
            for (int c = 0; c < 2; c++) {
                dfle_flow1d_params p;
                double w[80], S[80], in, left, out = 0, t = 0;
                dfle_flow1d *f;
                dfle_flow1d_params_default(&p);
                p.mu_2 = mu2[a];
                p.D = D[b];
                p.eta = eta[c];
                for (int k = 0; k < 80; k++) {
                    w[k] = 0.4 + 0.01 * k;
                    S[k] = 0.9 - 0.01 * k; /* steep to gentle, then reverse */
                }
                assert_int_equal(dfle_flow1d_new(80, 5.0, w, S, &p, &f, NULL), DFLE_OK);
                for (int k = 0; k < 10; k++)
                    dfle_flow1d_h(f)[k] = 4.0;
                in = dfle_flow1d_volume(f, 0, 80);
                while (t < 400) {
                    double dt = fmin(dfle_flow1d_stable_dt(f), 400 - t), o;
                    if (isinf(dt))
                        break;
                    assert_int_equal(dfle_flow1d_step(f, dt, t, &o, NULL), DFLE_OK);
                    out += o;
                    t += dt;
                    for (int k = 0; k < 80; k++) {
                        assert_true(dfle_flow1d_depth(f)[k] >= 0.0);
                        assert_true(isfinite(dfle_flow1d_discharge(f)[k]));
                    }
                }
                left = dfle_flow1d_volume(f, 0, 80);
                assert_close(out + left, in, 1e-12, 0);
                dfle_flow1d_free(f);
            }
}

/* The wet window.  Two solvers on one grid, one working on the wet
 * window and one on every cell (full_domain), stepped side by side with
 * their own stable steps: time step, outflow, every depth, discharge and
 * face volume must agree to the bit at every step (the window skips only
 * cells whose results are exactly zero).  On the window's solver,
 * outside the window the state and the faces must be exactly zero.
 * Returns the mean window length over the steps [cells]. */
typedef struct twin {
    dfle_flow1d *f[2]; /* [0] wet window, [1] full domain */
    double *h[2];
    size_t n;
} twin;

static void twin_new(twin *tw, size_t n, double dx, const double *w, const double *S,
                     dfle_flow1d_params p)
{
    dfle_error err;
    tw->n = n;
    for (int a = 0; a < 2; a++) {
        p.full_domain = a;
        assert_ok(dfle_flow1d_new(n, dx, w, S, &p, &tw->f[a], &err), &err);
        tw->h[a] = dfle_flow1d_h(tw->f[a]);
    }
}

static double twin_run(twin *tw, double T, double t_entry0, double *out_total)
{
    double t = 0.0, window = 0.0;
    size_t steps = 0;
    *out_total = 0.0;
    while (t < T) {
        double dt[2], out[2];
        size_t k0, k1;
        for (int a = 0; a < 2; a++)
            dt[a] = fmin(dfle_flow1d_stable_dt(tw->f[a]), T - t);
        assert_close(dt[0], dt[1], 0, 0);
        if (isinf(dt[0]))
            break;
        for (int a = 0; a < 2; a++)
            assert_int_equal(dfle_flow1d_step(tw->f[a], dt[a], t - t_entry0, &out[a], NULL),
                             DFLE_OK);
        assert_close(out[0], out[1], 0, 0);
        *out_total += out[0];
        t += dt[0];
        steps++;
        dfle_flow1d_window(tw->f[0], &k0, &k1);
        window += (double)(k1 - k0);
        for (size_t k = 0; k < tw->n; k++) {
            const double h = dfle_flow1d_depth(tw->f[0])[k], q = dfle_flow1d_discharge(tw->f[0])[k];
            assert_close(h, dfle_flow1d_depth(tw->f[1])[k], 0, 0);
            assert_close(q, dfle_flow1d_discharge(tw->f[1])[k], 0, 0);
            assert_true(h >= 0.0 && isfinite(q));
            if (k < k0 || k >= k1)
                assert_true(h == 0.0 && q == 0.0);
        }
        for (size_t k = 0; k <= tw->n; k++) {
            const double v = dfle_flow1d_face_volume(tw->f[0], k);
            assert_close(v, dfle_flow1d_face_volume(tw->f[1], k), 0, 0);
            if (k < k0 || k > k1)
                assert_true(v == 0.0);
        }
        assert_close(dfle_flow1d_volume(tw->f[0], 0, tw->n),
                     dfle_flow1d_volume(tw->f[1], 0, tw->n), 0, 0);
    }
    return steps > 0 ? window / (double)steps : 0.0;
}

static void twin_free(twin *tw)
{
    for (int a = 0; a < 2; a++)
        dfle_flow1d_free(tw->f[a]);
}

static void wet_window_changes_nothing(void **state)
{
    enum { N = 400 };
    double w[N], S[N], in, out, mean;
    dfle_flow1d_params p;
    twin tw;
    (void)state;

    /* A release on a steep channel with the paper's physics that comes to
     * rest partly out through the open outlet (as the router's flows). */
    dfle_flow1d_params_default(&p);
    for (int k = 0; k < N; k++) {
        w[k] = 0.4 + 0.01 * k;
        S[k] = 1.0 - 0.003 * k;
    }
    twin_new(&tw, N, 5.0, w, S, p);
    for (int k = 0; k < 10; k++)
        tw.h[0][k] = tw.h[1][k] = 4.0;
    in = dfle_flow1d_volume(tw.f[0], 0, N);
    mean = twin_run(&tw, 600.0, 0.0, &out);
    assert_close(out + dfle_flow1d_volume(tw.f[0], 0, N), in, 1e-12, 0);
    assert_true(mean < 0.5 * N); /* the window does follow the flow */
    /* The caller writes a second pile far down mid-run: the window opens
     * to the whole grid for one step, then follows both piles. */
    for (int k = 300; k < 310; k++)
        dfle_flow1d_h(tw.f[0])[k] = dfle_flow1d_h(tw.f[1])[k] = 2.0;
    in = dfle_flow1d_volume(tw.f[0], 0, N);
    twin_run(&tw, 300.0, -600.0, &out);
    assert_close(out + dfle_flow1d_volume(tw.f[0], 0, N), in, 1e-12, 0);
    twin_free(&tw);

    /* Out through the open outlet: the window reaches the last face. */
    dfle_flow1d_params_default(&p);
    for (int k = 0; k < N; k++) {
        w[k] = 1.0;
        S[k] = 0.9;
    }
    twin_new(&tw, 60, 5.0, w, S, p);
    for (int k = 0; k < 10; k++)
        tw.h[0][k] = tw.h[1][k] = 2.0;
    in = dfle_flow1d_volume(tw.f[0], 0, 60);
    twin_run(&tw, 300.0, 0.0, &out);
    assert_true(out > 0.5 * in);
    assert_close(out + dfle_flow1d_volume(tw.f[0], 0, 60), in, 1e-12, 0);
    twin_free(&tw);

    /* A frictionless dam in mid-channel spreading both ways to the walls
     * (both ends of the window reach the grid's ends), on varying widths. */
    p = frictionless();
    for (int k = 0; k < N; k++) {
        w[k] = 1.0 + 0.3 * sin(0.2 * k);
        S[k] = 0.0;
    }
    twin_new(&tw, N, 2.0, w, S, p);
    for (int k = 190; k < 210; k++)
        tw.h[0][k] = tw.h[1][k] = 1.0;
    in = dfle_flow1d_volume(tw.f[0], 0, N);
    twin_run(&tw, 200.0, 0.0, &out);
    assert_close(out, 0.0, 0, 0);
    assert_close(dfle_flow1d_volume(tw.f[0], 0, N), in, 1e-12, 0);
    twin_free(&tw);
}

static void friction_law_and_pore_pressure(void **state)
{
    dfle_flow1d_params p;
    dfle_flow1d *f;
    (void)state;
    dfle_flow1d_params_default(&p);
    f = make(3, 1.0, 1.0, 0.0, &p);
    /* Eq. (10): phi = mu_s at rest and tends to mu_2 at large I. */
    assert_close(dfle_flow1d_phi(f, 0, 1.0, 0.0), 0.384, 1e-15, 0);
    assert_close(dfle_flow1d_phi(f, 0, 1.0, 1e9), 0.62, 1e-6, 0);
    /* At I = I0 the friction is halfway. */
    double P = 1800 * 9.81 * 1.0, v = 0.279 * sqrt(P / 2600) / 0.09 / 2.0;
    assert_close(dfle_flow1d_phi(f, 0, 1.0, v), 0.5 * (0.384 + 0.62), 1e-12, 0);
    /* Eq. (9): lambda0 before entry, lambda0 (1 - erfc(2h/sqrt(4Dt))) after. */
    assert_close(dfle_flow1d_lambda(f, 0.3, -1), 0.9, 0, 0);
    assert_close(dfle_flow1d_lambda(f, 0.3, 1e4), 0.9 * (1 - erfc(0.6 / sqrt(4 * 5e-6 * 1e4))),
                 1e-14, 0);
    /* In two parts, bit for bit the same; no phi beyond phi_max. */
    assert_close(dfle_flow1d_pore_length(f, -1), 0.0, 0, 0);
    assert_close(dfle_flow1d_lambda_at(f, 0.3, dfle_flow1d_pore_length(f, 1e4)),
                 dfle_flow1d_lambda(f, 0.3, 1e4), 0, 0);
    for (double speed = 1e-3; speed < 1e12; speed *= 7.0)
        assert_true(dfle_flow1d_phi(f, 0, 0.01, speed) <= dfle_flow1d_phi_max(f));
    assert_true(dfle_flow1d_phi_max(f) < 0.62 * (1 + 1e-9));
    dfle_flow1d_free(f);
}

static void bad_parameters_are_named(void **state)
{
    dfle_flow1d_params p;
    dfle_flow1d *f = NULL;
    dfle_error err;
    double w[2] = {1, 1}, S[2] = {0, 0};
    (void)state;
    dfle_flow1d_params_default(&p);
    p.lambda0 = 1.0;
    assert_int_equal(dfle_flow1d_new(2, 1, w, S, &p, &f, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "lambda0");
    dfle_flow1d_params_default(&p);
    p.mu_2 = 0.1;
    assert_int_equal(dfle_flow1d_new(2, 1, w, S, &p, &f, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "mu_2 must be >= mu_s");
    dfle_flow1d_params_default(&p);
    p.eta = NAN;
    assert_int_equal(dfle_flow1d_new(2, 1, w, S, &p, &f, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "eta");
    dfle_flow1d_params_default(&p);
    w[1] = 0;
    assert_int_equal(dfle_flow1d_new(2, 1, w, S, &p, &f, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "cell 2");
    assert_null(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(dam_break_converges_to_ritter),
        cmocka_unit_test(pile_below_friction_angle_stays_still),
        cmocka_unit_test(pile_above_friction_angle_moves),
        cmocka_unit_test(lake_at_rest_in_a_widening_channel),
        cmocka_unit_test(conservation_and_positivity_over_parameter_ranges),
        cmocka_unit_test(wet_window_changes_nothing),
        cmocka_unit_test(friction_law_and_pore_pressure),
        cmocka_unit_test(bad_parameters_are_named),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
