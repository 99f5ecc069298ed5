/* test_router_process.c - the process-based router: volume balance,
 * the Eq. (11) sum, re-routing rule, Appendix D, rest on gentle slopes,
 * and a whole steady state with the Fig. 6 defaults. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dfle_test.h"
#include "dfle/analysis.h"
#include "dfle/law_power.h"
#include "dfle/model.h"
#include "dfle/solver.h"
#include "dfle/router_process.h"

static dfle_channel *channel(double dx)
{
    dfle_channel_opts o;
    dfle_channel *ch;
    dfle_channel_opts_default(&o);
    o.dx = dx;
    assert_int_equal(dfle_channel_new(&o, &ch, NULL), DFLE_OK);
    return ch;
}

/* Slopes of the Eq. (26) fluvial steady state, head steepest (S = 8). */
static void fluvial_slopes(const dfle_channel *ch, double *S)
{
    dfle_stochastic_threshold_opts so;
    dfle_fluvial *fl;
    dfle_stochastic_threshold_opts_default(&so);
    assert_int_equal(dfle_fluvial_new_stochastic_threshold(&so, &fl, NULL), DFLE_OK);
    for (size_t i = 0; i < dfle_channel_size(ch); i++)
        S[i] = dfle_fluvial_steady_slope(fl, 5e-4, dfle_channel_A(ch)[i]);
    dfle_fluvial_free(fl);
}

static int one(void *s, double h, double v, double lambda, double *g, dfle_error *err)
{
    (void)s, (void)err, (void)h, (void)v, (void)lambda;
    *g = 1.0;
    return DFLE_OK;
}

static int depth(void *s, double h, double v, double lambda, double *g, dfle_error *err)
{
    (void)s, (void)err, (void)v, (void)lambda;
    *g = h;
    return DFLE_OK;
}

typedef struct routed {
    dfle_channel *ch;
    dfle_router *rt;
    dfle_flow flow;
    double *S;
} routed;

static void route(routed *r, const dfle_process_opts *o, double dx,
                  int (*g)(void *, double, double, double, double *, dfle_error *))
{
    dfle_error err;
    r->ch = channel(dx);
    r->S = malloc(dfle_channel_size(r->ch) * sizeof *r->S);
    fluvial_slopes(r->ch, r->S);
    assert_ok(dfle_router_new_process(o, &r->rt, &err), &err);
    assert_int_equal(dfle_flow_init(&r->flow, dfle_channel_size(r->ch), NULL), DFLE_OK);
    r->flow.integrand = g;
    assert_ok(dfle_router_route(r->rt, r->ch, r->S, &r->flow, &err), &err);
}

static void unroute(routed *r)
{
    dfle_flow_release(&r->flow);
    dfle_router_free(r->rt);
    dfle_channel_free(r->ch);
    free(r->S);
}

static void volume_in_equals_out_plus_left(void **state)
{
    dfle_process_opts o;
    routed r;
    (void)state;
    dfle_process_opts_default(&o);
    route(&r, &o, 10.0, one);
    const dfle_process_report *rep = dfle_router_process_report(r.rt);
    assert_true(rep->routed);
    assert_close(rep->volume_in, 200.0, 1e-12, 0);
    assert_close(rep->volume_out + rep->volume_left, rep->volume_in, 1e-12, 0);
    assert_true(rep->end == DFLE_PROCESS_REST || rep->end == DFLE_PROCESS_LEFT);
    assert_true(r.flow.time_resolved);
    assert_true(r.flow.runout_end > 10 && r.flow.runout_end < dfle_channel_size(r.ch));
    unroute(&r);
}

/* With g = 1 the Eq. (11) sum is the time with Phi = 1, the passage
 * time; with g = h it is bounded by peak depth times passage time. */
static void erosion_sum_is_the_time_integral(void **state)
{
    dfle_process_opts o;
    routed a, b;
    (void)state;
    dfle_process_opts_default(&o);
    route(&a, &o, 10.0, one);
    route(&b, &o, 10.0, depth);
    for (size_t i = 0; i < dfle_channel_size(a.ch); i++) {
        assert_close(a.flow.integral[i], a.flow.t_p[i], 1e-12, 0);
        assert_true(b.flow.integral[i] <= b.flow.h[i] * b.flow.t_p[i] * (1 + 1e-12));
        /* Reached nodes (Phi = 1 at some time) have an arrival time. */
        const dfle_process_report *rep = dfle_router_process_report(a.rt);
        assert_int_equal(isnan(rep->arrival[i]), !(a.flow.t_p[i] > 0));
        if (i > 0 && a.flow.t_p[i] > 0 && a.flow.t_p[i - 1] > 0)
            assert_true(rep->arrival[i] >= rep->arrival[i - 1]);
    }
    unroute(&a);
    unroute(&b);
}

static void appendix_d_scales_the_sum(void **state)
{
    dfle_process_opts o;
    routed a, b;
    (void)state;
    dfle_process_opts_default(&o);
    route(&a, &o, 10.0, one);
    o.frequency_scaling = 1;
    o.gamma = 0.5;
    route(&b, &o, 10.0, one);
    for (size_t i = 0; i < a.flow.runout_end; i++) {
        double A = dfle_channel_A(a.ch)[i];
        assert_close(b.flow.integral[i], a.flow.integral[i] * 1000 * sqrt(1e-6 * A) / 200.0,
                     1e-12, 0);
    }
    unroute(&a);
    unroute(&b);
}

static void rerouting_follows_the_slope_threshold(void **state)
{
    dfle_process_opts o;
    routed r;
    (void)state;
    dfle_process_opts_default(&o);
    route(&r, &o, 10.0, one);
    size_t n = dfle_channel_size(r.ch);
    double *S = malloc(n * sizeof *S);
    int again = -1;
    dfle_error err;
    memcpy(S, r.S, n * sizeof *S);
    assert_ok(dfle_router_needs_reroute(r.rt, n, r.S, S, &again, &err), &err);
    assert_false(again);
    S[50] += 0.049;
    assert_ok(dfle_router_needs_reroute(r.rt, n, r.S, S, &again, &err), &err);
    assert_false(again);
    S[50] += 0.002;
    assert_ok(dfle_router_needs_reroute(r.rt, n, r.S, S, &again, &err), &err);
    assert_true(again);
    free(S);
    assert_false(dfle_router_is_local(r.rt));
    unroute(&r);
}

static void pile_on_a_gentle_channel_stays_put(void **state)
{
    dfle_process_opts o;
    dfle_channel *ch = channel(10.0);
    dfle_router *rt;
    dfle_flow flow;
    double S[202];
    dfle_error err;
    (void)state;
    dfle_process_opts_default(&o);
    o.flow.lambda0 = 0.0; /* full friction, mu_s = 0.384 */
    o.M0 = 20.0;          /* a thin pile: little edge pressure */
    assert_int_equal(dfle_channel_size(ch), 202);
    for (int i = 0; i < 202; i++)
        S[i] = 0.2;
    assert_ok(dfle_router_new_process(&o, &rt, &err), &err);
    assert_int_equal(dfle_flow_init(&flow, 202, NULL), DFLE_OK);
    flow.integrand = one;
    assert_ok(dfle_router_route(rt, ch, S, &flow, &err), &err);
    const dfle_process_report *rep = dfle_router_process_report(rt);
    assert_int_equal(rep->end, DFLE_PROCESS_REST);
    assert_int_equal(flow.runout_end, 0);
    assert_close(rep->volume_left, 20.0, 1e-12, 0);
    for (int i = 0; i < 202; i++)
        assert_close(flow.h[i], 0.0, 0, 0);
    dfle_flow_release(&flow);
    dfle_router_free(rt);
    dfle_channel_free(ch);
}

/* A Courant number of 3.2e-9 is accepted (it is in (0, 1]) but would
 * need ~1e11 flow steps: the routing must stop at max_steps and say why,
 * not run for days. */
static void routing_work_is_bounded(void **state)
{
    dfle_process_opts o;
    dfle_channel *ch = channel(10.0);
    dfle_router *rt;
    dfle_flow flow;
    double S[202];
    dfle_error err;
    (void)state;
    dfle_process_opts_default(&o);
    o.flow.cfl = 3.2e-9;
    o.max_steps = 2000;
    fluvial_slopes(ch, S);
    assert_ok(dfle_router_new_process(&o, &rt, &err), &err);
    assert_int_equal(dfle_flow_init(&flow, dfle_channel_size(ch), NULL), DFLE_OK);
    flow.integrand = one;
    assert_int_equal(dfle_router_route(rt, ch, S, &flow, &err), DFLE_ENUMERIC);
    assert_non_null(strstr(err.msg, "max_steps = 2000"));
    assert_non_null(strstr(err.msg, "raise cfl"));
    dfle_router_free(rt);
    o.max_steps = 0;
    assert_int_equal(dfle_router_new_process(&o, &rt, &err), DFLE_EINVAL);
    assert_non_null(strstr(err.msg, "max_steps"));
    dfle_flow_release(&flow);
    dfle_channel_free(ch);
}

static void snapshots_are_taken_at_the_requested_times(void **state)
{
    dfle_process_opts o;
    routed r;
    const double times[] = {0.0, 10.0, 30.0, 1e5};
    dfle_error err;
    (void)state;
    dfle_process_opts_default(&o);
    r.ch = channel(10.0);
    r.S = malloc(dfle_channel_size(r.ch) * sizeof *r.S);
    fluvial_slopes(r.ch, r.S);
    assert_ok(dfle_router_new_process(&o, &r.rt, &err), &err);
    assert_ok(dfle_router_process_set_snapshots(r.rt, 4, times, &err), &err);
    assert_int_equal(dfle_flow_init(&r.flow, dfle_channel_size(r.ch), NULL), DFLE_OK);
    r.flow.integrand = one;
    assert_ok(dfle_router_route(r.rt, r.ch, r.S, &r.flow, &err), &err);
    const dfle_process_report *rep = dfle_router_process_report(r.rt);
    size_t n = rep->n;
    assert_int_equal(rep->n_snapshots, 4);
    assert_close(rep->snapshot_t[0], 0.0, 0, 0);
    for (size_t i = 0; i < n; i++) /* at release the pile is all on the ghosts */
        assert_close(rep->snapshot_h[i], 0.0, 0, 0);
    assert_true(rep->snapshot_t[1] >= 10.0 && rep->snapshot_t[2] >= 30.0);
    assert_true(isnan(rep->snapshot_t[3])); /* the flow ended long before */
    double wet = 0;
    for (size_t i = 0; i < n; i++)
        wet += rep->snapshot_h[n + i];
    assert_true(wet > 0);
    const double bad[] = {5.0, 2.0};
    assert_int_equal(dfle_router_process_set_snapshots(r.rt, 2, bad, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "increasing");
    unroute(&r);
}

/* The corners of the Table G2/G4 ranges: every routing balances its
 * volume, and nothing is negative or non-finite. */
static void table_g2_g4_corners_route_cleanly(void **state)
{
    const double eta[] = {30, 90}, mu2[] = {0.532, 0.869}, D[] = {1e-6, 1e-5};
    (void)state;
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++)
            for (int c = 0; c < 2; c++) {
                dfle_process_opts o;
                routed r;
                dfle_process_opts_default(&o);
                o.flow.eta = eta[a];
                o.flow.mu_2 = mu2[b];
                o.flow.D = D[c];
                route(&r, &o, 10.0, depth);
                const dfle_process_report *rep = dfle_router_process_report(r.rt);
                assert_close(rep->volume_out + rep->volume_left, rep->volume_in, 1e-12, 0);
                for (size_t i = 0; i < dfle_channel_size(r.ch); i++) {
                    const double v[] = {r.flow.h[i], r.flow.v[i], r.flow.Q[i], r.flow.t_p[i],
                                        r.flow.tau[i], r.flow.integral[i]};
                    for (size_t k = 0; k < sizeof v / sizeof v[0]; k++)
                        assert_true(isfinite(v[k]) && v[k] >= 0);
                }
                unroute(&r);
            }
}

static void fig6_steady_state_converges_and_fits(void **state)
{
    dfle_channel *ch = channel(10.0);
    dfle_stochastic_threshold_opts so;
    dfle_process_opts po;
    dfle_power_law_opts lo;
    dfle_fluvial *fl;
    dfle_router *rt;
    dfle_law *law;
    dfle_model_opts mo;
    dfle_model *m;
    dfle_run_opts ro;
    dfle_run_result res;
    dfle_eq2_fit fit;
    dfle_error err;
    (void)state;
    dfle_stochastic_threshold_opts_default(&so);
    dfle_process_opts_default(&po);
    dfle_power_law_opts_default(&lo);
    assert_int_equal(dfle_fluvial_new_stochastic_threshold(&so, &fl, NULL), DFLE_OK);
    assert_int_equal(dfle_router_new_process(&po, &rt, NULL), DFLE_OK);
    assert_int_equal(dfle_law_new_power(&lo, &law, NULL), DFLE_OK);
    dfle_model_opts_default(&mo);
    mo.channel = ch, mo.fluvial = fl, mo.router = rt, mo.law = law;
    assert_ok(dfle_model_new(&mo, &m, &err), &err);
    dfle_run_opts_default(&ro);
    assert_ok(dfle_solver_run(m, &ro, &res, &err), &err);
    assert_true(res.converged);
    /* Routed far less often than stepped: the Eq. (11) cache at work. */
    assert_true(res.routings > 1 && res.routings < res.steps / 4);
    const double *A = dfle_model_field(m, DFLE_FIELD_A, &err);
    const double *S = dfle_model_field(m, DFLE_FIELD_S, &err);
    const double *Ef = dfle_model_field(m, DFLE_FIELD_E_F, &err);
    const double *Edf = dfle_model_field(m, DFLE_FIELD_E_DF, &err);
    for (size_t i = 0; i + 1 < dfle_model_size(m); i++)
        assert_close(Ef[i] + Edf[i], 5e-4, 1e-3, 0);
    assert_true(Edf[0] > 0.9 * 5e-4); /* debris flows shape the head */
    assert_ok(dfle_slope_area_fit(dfle_model_size(m) - 1, A, S, 100, NULL, &fit, &err), &err);
    assert_true(fit.S_df > 0.3 && fit.S_df < 3);
    assert_true(fit.A_df > 1e3 && fit.A_df < 8e6);
    assert_true(fit.r2 > 0.9);
    dfle_model_free(m);
    dfle_law_free(law);
    dfle_router_free(rt);
    dfle_fluvial_free(fl);
    dfle_channel_free(ch);
}

static void bad_parameters_and_missing_integrand(void **state)
{
    dfle_process_opts o;
    dfle_router *rt = NULL;
    dfle_error err;
    routed r;
    (void)state;
    dfle_process_opts_default(&o);
    o.M0 = 0;
    assert_int_equal(dfle_router_new_process(&o, &rt, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "M0 must be > 0");
    dfle_process_opts_default(&o);
    o.flow.eta = -1;
    assert_int_equal(dfle_router_new_process(&o, &rt, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "router.process: eta must be >= 0");
    dfle_process_opts_default(&o);
    o.n_ghost = 0;
    assert_int_equal(dfle_router_new_process(&o, &rt, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "n_ghost");
    assert_null(rt);

    dfle_process_opts_default(&o);
    r.ch = channel(10.0);
    r.S = malloc(dfle_channel_size(r.ch) * sizeof *r.S);
    fluvial_slopes(r.ch, r.S);
    assert_int_equal(dfle_router_new_process(&o, &r.rt, NULL), DFLE_OK);
    assert_int_equal(dfle_flow_init(&r.flow, dfle_channel_size(r.ch), NULL), DFLE_OK);
    assert_int_equal(dfle_router_route(r.rt, r.ch, r.S, &r.flow, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "no Eq. (11) integrand");
    unroute(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(volume_in_equals_out_plus_left),
        cmocka_unit_test(erosion_sum_is_the_time_integral),
        cmocka_unit_test(appendix_d_scales_the_sum),
        cmocka_unit_test(rerouting_follows_the_slope_threshold),
        cmocka_unit_test(pile_on_a_gentle_channel_stays_put),
        cmocka_unit_test(snapshots_are_taken_at_the_requested_times),
        cmocka_unit_test(routing_work_is_bounded),
        cmocka_unit_test(table_g2_g4_corners_route_cleanly),
        cmocka_unit_test(fig6_steady_state_converges_and_fits),
        cmocka_unit_test(bad_parameters_and_missing_integrand),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
