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
#include "dfle/network.h"
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
    dfle_network *net;
    dfle_router *rt;
    dfle_flow flow;
    double *S;
} routed;

static void route(routed *r, const dfle_process_opts *o, double dx,
                  int (*g)(void *, double, double, double, double *, dfle_error *))
{
    dfle_error err;
    r->ch = channel(dx);
    assert_int_equal(dfle_network_new_chain(r->ch, &r->net, NULL), DFLE_OK);
    r->S = malloc(dfle_channel_size(r->ch) * sizeof *r->S);
    fluvial_slopes(r->ch, r->S);
    assert_ok(dfle_router_new_process(o, &r->rt, &err), &err);
    assert_int_equal(dfle_flow_init(&r->flow, dfle_channel_size(r->ch), NULL), DFLE_OK);
    r->flow.integrand = g;
    assert_ok(dfle_router_route(r->rt, r->net, r->S, &r->flow, &err), &err);
}

static void unroute(routed *r)
{
    dfle_flow_release(&r->flow);
    dfle_router_free(r->rt);
    dfle_network_free(r->net);
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
    dfle_network *net;
    dfle_router *rt;
    dfle_flow flow;
    double S[202];
    dfle_error err;
    (void)state;
    assert_int_equal(dfle_network_new_chain(ch, &net, NULL), DFLE_OK);
    dfle_process_opts_default(&o);
    o.flow.lambda0 = 0.0; /* full friction, mu_s = 0.384 */
    o.M0 = 20.0;          /* a thin pile: little edge pressure */
    assert_int_equal(dfle_channel_size(ch), 202);
    for (int i = 0; i < 202; i++)
        S[i] = 0.2;
    assert_ok(dfle_router_new_process(&o, &rt, &err), &err);
    assert_int_equal(dfle_flow_init(&flow, 202, NULL), DFLE_OK);
    flow.integrand = one;
    assert_ok(dfle_router_route(rt, net, S, &flow, &err), &err);
    const dfle_process_report *rep = dfle_router_process_report(rt);
    assert_int_equal(rep->end, DFLE_PROCESS_REST);
    assert_int_equal(flow.runout_end, 0);
    assert_close(rep->volume_left, 20.0, 1e-12, 0);
    for (int i = 0; i < 202; i++)
        assert_close(flow.h[i], 0.0, 0, 0);
    dfle_flow_release(&flow);
    dfle_router_free(rt);
    dfle_network_free(net);
    dfle_channel_free(ch);
}

/* A Courant number of 3.2e-9 is accepted (it is in (0, 1]) but would
 * need ~1e11 flow steps: the routing must stop at max_steps and say why,
 * not run for days. */
static void routing_work_is_bounded(void **state)
{
    dfle_process_opts o;
    dfle_channel *ch = channel(10.0);
    dfle_network *net;
    dfle_router *rt;
    dfle_flow flow;
    double S[202];
    dfle_error err;
    (void)state;
    assert_int_equal(dfle_network_new_chain(ch, &net, NULL), DFLE_OK);
    dfle_process_opts_default(&o);
    o.flow.cfl = 3.2e-9;
    o.max_steps = 2000;
    fluvial_slopes(ch, S);
    assert_ok(dfle_router_new_process(&o, &rt, &err), &err);
    assert_int_equal(dfle_flow_init(&flow, dfle_channel_size(ch), NULL), DFLE_OK);
    flow.integrand = one;
    assert_int_equal(dfle_router_route(rt, net, S, &flow, &err), DFLE_ENUMERIC);
    assert_non_null(strstr(err.msg, "max_steps = 2000"));
    assert_non_null(strstr(err.msg, "raise cfl"));
    dfle_router_free(rt);
    o.max_steps = 0;
    assert_int_equal(dfle_router_new_process(&o, &rt, &err), DFLE_EINVAL);
    assert_non_null(strstr(err.msg, "max_steps"));
    dfle_flow_release(&flow);
    dfle_network_free(net);
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
    assert_int_equal(dfle_network_new_chain(r.ch, &r.net, NULL), DFLE_OK);
    r.S = malloc(dfle_channel_size(r.ch) * sizeof *r.S);
    fluvial_slopes(r.ch, r.S);
    assert_ok(dfle_router_new_process(&o, &r.rt, &err), &err);
    assert_ok(dfle_router_process_set_snapshots(r.rt, 4, times, &err), &err);
    assert_int_equal(dfle_flow_init(&r.flow, dfle_channel_size(r.ch), NULL), DFLE_OK);
    r.flow.integrand = one;
    assert_ok(dfle_router_route(r.rt, r.net, r.S, &r.flow, &err), &err);
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

/* A model with the Fig. 6 defaults on a 10 m channel, routing with a
 * process router of these options (its parts freed by fig6_free). */
typedef struct fig6 {
    dfle_channel *ch;
    dfle_fluvial *fl;
    dfle_router *rt;
    dfle_law *law;
    dfle_model *m;
} fig6;

static void fig6_new(fig6 *x, const dfle_process_opts *po)
{
    dfle_stochastic_threshold_opts so;
    dfle_power_law_opts lo;
    dfle_model_opts mo;
    dfle_error err;
    x->ch = channel(10.0);
    dfle_stochastic_threshold_opts_default(&so);
    dfle_power_law_opts_default(&lo);
    assert_int_equal(dfle_fluvial_new_stochastic_threshold(&so, &x->fl, NULL), DFLE_OK);
    assert_int_equal(dfle_router_new_process(po, &x->rt, NULL), DFLE_OK);
    assert_int_equal(dfle_law_new_power(&lo, &x->law, NULL), DFLE_OK);
    dfle_model_opts_default(&mo);
    mo.channel = x->ch, mo.fluvial = x->fl, mo.router = x->rt, mo.law = x->law;
    assert_ok(dfle_model_new(&mo, &x->m, &err), &err);
}

static void fig6_free(fig6 *x)
{
    dfle_model_free(x->m);
    dfle_law_free(x->law);
    dfle_router_free(x->rt);
    dfle_fluvial_free(x->fl);
    dfle_channel_free(x->ch);
}

static void fig6_steady_state_converges_and_fits(void **state)
{
    dfle_process_opts po;
    dfle_run_opts ro;
    dfle_run_result res;
    dfle_eq2_fit fit;
    dfle_error err;
    fig6 x;
    dfle_model *m;
    (void)state;
    dfle_process_opts_default(&po);
    fig6_new(&x, &po);
    m = x.m;
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
    fig6_free(&x);
}

/* --- The wet window (doc/process-router.md, Cost) --- */

/* Route slopes of the Eq. (26) fluvial steady state on a channel of
 * spacing dx [m] and head-to-outlet length `length` [m] (0: to A_max),
 * with opts o, on the wet window ([0]) and on every cell ([1]). */
static void route_twice(routed r[2], dfle_process_opts o, double dx, double length,
                        size_t n_snap, const double *snap)
{
    dfle_channel_opts co;
    dfle_error err;
    dfle_channel_opts_default(&co);
    co.dx = dx;
    co.length = length;
    for (int a = 0; a < 2; a++) {
        assert_ok(dfle_channel_new(&co, &r[a].ch, &err), &err);
        assert_int_equal(dfle_network_new_chain(r[a].ch, &r[a].net, NULL), DFLE_OK);
        r[a].S = malloc(dfle_channel_size(r[a].ch) * sizeof *r[a].S);
        fluvial_slopes(r[a].ch, r[a].S);
        o.flow.full_domain = a;
        assert_ok(dfle_router_new_process(&o, &r[a].rt, &err), &err);
        if (n_snap > 0)
            assert_ok(dfle_router_process_set_snapshots(r[a].rt, n_snap, snap, &err), &err);
        assert_int_equal(dfle_flow_init(&r[a].flow, dfle_channel_size(r[a].ch), NULL), DFLE_OK);
        r[a].flow.integrand = depth;
        assert_ok(dfle_router_route(r[a].rt, r[a].net, r[a].S, &r[a].flow, &err), &err);
    }
}

static void assert_same_double(double a, double b)
{
    if (isnan(b))
        assert_true(isnan(a));
    else
        assert_close(a, b, 0, 0);
}

/* Every record and report of the two routings, to the bit. */
static void assert_same_routing(const routed r[2])
{
    const dfle_process_report *a = dfle_router_process_report(r[0].rt),
                              *b = dfle_router_process_report(r[1].rt);
    const size_t n = dfle_channel_size(r[0].ch), N = n + 20;
    const double *fa[] = {r[0].flow.M, r[0].flow.Q, r[0].flow.h, r[0].flow.v, r[0].flow.t_p,
                          r[0].flow.tau, r[0].flow.Theta, r[0].flow.reach, r[0].flow.integral,
                          a->arrival};
    const double *fb[] = {r[1].flow.M, r[1].flow.Q, r[1].flow.h, r[1].flow.v, r[1].flow.t_p,
                          r[1].flow.tau, r[1].flow.Theta, r[1].flow.reach, r[1].flow.integral,
                          b->arrival};
    for (size_t j = 0; j < sizeof fa / sizeof fa[0]; j++)
        for (size_t i = 0; i < n; i++)
            assert_same_double(fa[j][i], fb[j][i]);
    assert_int_equal(r[0].flow.runout_end, r[1].flow.runout_end);
    assert_int_equal(a->end, b->end);
    assert_int_equal(a->steps, b->steps);
    assert_close(a->duration, b->duration, 0, 0);
    assert_close(a->volume_in, b->volume_in, 0, 0);
    assert_close(a->volume_out, b->volume_out, 0, 0);
    assert_close(a->volume_left, b->volume_left, 0, 0);
    assert_int_equal(a->n_snapshots, b->n_snapshots);
    for (size_t j = 0; j < a->n_snapshots; j++) {
        assert_same_double(a->snapshot_t[j], b->snapshot_t[j]);
        for (size_t i = 0; i < n; i++)
            assert_close(a->snapshot_h[j * n + i], b->snapshot_h[j * n + i], 0, 0);
    }
    /* Volume in = out + left on both; the full domain works on every
     * cell at every step, the window on fewer. */
    assert_close(a->volume_out + a->volume_left, a->volume_in, 1e-12, 0);
    assert_int_equal(b->cell_steps, b->steps * N);
    assert_true(a->cell_steps < b->cell_steps);
}

static void wet_window_matches_full_domain(void **state)
{
    const double snap[] = {1.0, 5.0, 20.0, 60.0};
    dfle_process_opts o;
    routed r[2];
    (void)state;

    /* Fig. 6 defaults: the flow comes to rest part way down. */
    dfle_process_opts_default(&o);
    route_twice(r, o, 10.0, 0.0, 4, snap);
    assert_same_routing(r);
    assert_int_equal(dfle_router_process_report(r[0].rt)->end, DFLE_PROCESS_REST);
    assert_true(r[0].flow.runout_end < dfle_channel_size(r[0].ch) / 2);
    /* ... on that grid the window averages under half of it. */
    assert_true(2 * dfle_router_process_report(r[0].rt)->cell_steps <
                dfle_router_process_report(r[1].rt)->cell_steps);
    for (int a = 0; a < 2; a++)
        unroute(&r[a]);

    /* Little friction, no drag, a short channel: the flow leaves. */
    o.flow.mu_s = o.flow.mu_2 = 0.1;
    o.flow.eta = 0.0;
    route_twice(r, o, 5.0, 300.0, 0, NULL);
    assert_same_routing(r);
    assert_int_equal(dfle_router_process_report(r[0].rt)->end, DFLE_PROCESS_LEFT);
    assert_true(dfle_router_process_report(r[0].rt)->volume_out > 199.9);
    for (int a = 0; a < 2; a++)
        unroute(&r[a]);

    /* Table G2/G4 corner with slow pore-pressure diffusion: ends on t_max. */
    dfle_process_opts_default(&o);
    o.flow.eta = 90.0;
    o.flow.D = 1e-6;
    o.t_max = 900.0;
    route_twice(r, o, 10.0, 0.0, 0, NULL);
    assert_same_routing(r);
    assert_int_equal(dfle_router_process_report(r[0].rt)->end, DFLE_PROCESS_TIME);
    for (int a = 0; a < 2; a++)
        unroute(&r[a]);
}

/* A model run that re-routes several times as its profile evolves: the
 * same profile to the bit on either path. */
static void model_run_matches_full_domain(void **state)
{
    dfle_process_opts po;
    dfle_run_result res[2];
    dfle_error err;
    fig6 x[2];
    (void)state;
    for (int a = 0; a < 2; a++) {
        dfle_run_opts ro;
        dfle_process_opts_default(&po);
        po.flow.full_domain = a;
        fig6_new(&x[a], &po);
        dfle_run_opts_default(&ro);
        ro.tol = 0.0; /* a transient of fixed length */
        ro.max_time = 3e4;
        assert_ok(dfle_solver_run(x[a].m, &ro, &res[a], &err), &err);
    }
    assert_true(res[0].routings >= 3);
    assert_int_equal(res[0].routings, res[1].routings);
    assert_int_equal(res[0].steps, res[1].steps);
    for (size_t i = 0; i < dfle_model_size(x[0].m); i++)
        assert_close(dfle_model_z(x[0].m)[i], dfle_model_z(x[1].m)[i], 0, 0);
    for (int a = 0; a < 2; a++)
        fig6_free(&x[a]);
}

/* What the router gave before the work on its speed (commit bca4821,
 * printed with %.17g): no speed-up may move a result. */
static void results_match_the_solver_before_the_window(void **state)
{
    const struct {
        size_t i;
        double sum, t_p, h, v, Q, tau, M, arrival;
    } stop[] = {
        {0, 18.286514519121003, 127.43321016979812, 2.2334107681215625, 68.562619777048937,
         53.591799861282993, 294.08578778763439, 197.133913819112, 2.8592327686358976},
        {20, 3.1208708676846513, 19.741417383802752, 1.0267836279896916, 65.395998157928915,
         104.06957354493326, 1027.4719058676073, 175.73522826938029, 7.4084934547117731},
        {60, 1.2369284116675474, 5.492298215671557, 0.68601972284177815, 29.382666100816277,
         64.295995778623919, 724.85718360145052, 76.1378370996526, 16.061730197627494},
    }, leave[] = {
        {5, 7.5118525789125998, 4.5667047844450801, 2.8053747888191012, 75.939249481744866,
         87.401341337612607, 175.15838529384993, 199.99995868528492, 1.8652384497907448},
        {60, 1.3822077186906747, 3.1358826572739322, 1.3102002614490669, 81.389633556762945,
         190.90266186827796, 224.76542337734324, 199.98501472645412, 7.4800255115152288},
    };
    dfle_process_opts o;
    routed r[2];
    (void)state;
    for (int c = 0; c < 2; c++) {
        const size_t k = c == 0 ? sizeof stop / sizeof stop[0] : sizeof leave / sizeof leave[0];
        const dfle_process_report *rep;
        dfle_process_opts_default(&o);
        if (c == 1) {
            o.flow.mu_s = o.flow.mu_2 = 0.1;
            o.flow.eta = 0.0;
        }
        route_twice(r, o, c == 0 ? 10.0 : 5.0, c == 0 ? 0.0 : 300.0, 0, NULL);
        rep = dfle_router_process_report(r[0].rt);
        assert_int_equal(rep->steps, c == 0 ? 251 : 244);
        assert_int_equal(r[0].flow.runout_end, c == 0 ? 76 : 61);
        assert_close(rep->duration, c == 0 ? 304.85182877810865 : 10.586362166148975, 1e-12, 0);
        assert_close(rep->volume_left, c == 0 ? 199.99999999999997 : 0.014985273545682512, 1e-12,
                     0);
        for (size_t j = 0; j < k; j++) {
            const size_t i = c == 0 ? stop[j].i : leave[j].i;
            const double *want = c == 0 ? &stop[j].sum : &leave[j].sum;
            const double got[] = {r[0].flow.integral[i], r[0].flow.t_p[i], r[0].flow.h[i],
                                  r[0].flow.v[i], r[0].flow.Q[i], r[0].flow.tau[i],
                                  r[0].flow.M[i], rep->arrival[i]};
            for (size_t f = 0; f < sizeof got / sizeof got[0]; f++)
                assert_close(got[f], want[f], 1e-12, 0);
        }
        for (int a = 0; a < 2; a++)
            unroute(&r[a]);
    }
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
    assert_int_equal(dfle_network_new_chain(r.ch, &r.net, NULL), DFLE_OK);
    r.S = malloc(dfle_channel_size(r.ch) * sizeof *r.S);
    fluvial_slopes(r.ch, r.S);
    assert_int_equal(dfle_router_new_process(&o, &r.rt, NULL), DFLE_OK);
    assert_int_equal(dfle_flow_init(&r.flow, dfle_channel_size(r.ch), NULL), DFLE_OK);
    assert_int_equal(dfle_router_route(r.rt, r.net, r.S, &r.flow, &err), DFLE_EINVAL);
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
        cmocka_unit_test(wet_window_matches_full_domain),
        cmocka_unit_test(model_run_matches_full_domain),
        cmocka_unit_test(results_match_the_solver_before_the_window),
        cmocka_unit_test(bad_parameters_and_missing_integrand),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
