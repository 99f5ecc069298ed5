/* test_router_process_network.c - the process-based router on a
 * drainage network: two heads joining (each flow as the 1D model on its
 * own path, combined by the rule), volume conservation of every flow,
 * paths of unequal cell lengths, and the re-routing rule per head (on
 * the cells each flow felt). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dfle_test.h"
#include "dfle/law_power.h"
#include "dfle/model.h"
#include "dfle/network.h"
#include "dfle/router_process.h"

/* A Y: tributary a (nodes 0-9), tributary b (10-16), both into the
 * trunk at node 17, down to the base level 39. */
enum { NA = 10, NB = 7, NT = 200, NN = NA + NB + NT, JUNCTION = NA + NB };

typedef struct ynet {
    size_t recv[NN];
    double len[NN], A[NN], w[NN], S[NN], z[NN];
    dfle_network *net;
} ynet;

static double hack_area(double x) { return 1000.0 + 25.0 * pow(x, 5.0 / 3.0); }

static void y_build(ynet *y, double dx, int diagonal_b)
{
    dfle_network_shape sh;
    for (size_t i = 0; i < NN; i++) {
        y->recv[i] = i + 1;
        y->len[i] = dx;
    }
    y->recv[NA - 1] = JUNCTION;
    y->recv[NN - 1] = NN - 1;
    for (size_t i = 0; i < NA; i++)
        y->A[i] = hack_area(dx * (double)i);
    for (size_t j = 0; j < NB; j++) {
        y->A[NA + j] = 0.7 * hack_area(dx * (double)j);
        if (diagonal_b)
            y->len[NA + j] = dx * sqrt(2.0); /* a grid's diagonal steps */
    }
    for (size_t j = 0; j < NT; j++)
        y->A[JUNCTION + j] = y->A[NA - 1] + y->A[JUNCTION - 1] + 25.0 * pow(dx * (double)(j + 1), 5.0 / 3.0);
    for (size_t i = 0; i < NN; i++) {
        y->w[i] = 0.05 * pow(y->A[i], 0.3);
        /* Steep near the heads, gentler down the trunk: the flows slow
         * and come to rest on it. */
        y->S[i] = i < NA ? 0.9 - 0.02 * (double)i
                  : i < JUNCTION ? 0.8 - 0.02 * (double)(i - NA)
                                 : fmax(0.04, 0.45 - 0.02 * (double)(i - JUNCTION));
    }
    y->S[NN - 1] = y->S[NN - 2];
    y->z[NN - 1] = 0.0;
    for (size_t k = NN - 1; k-- > 0;) /* receivers have larger numbers */
        y->z[k] = y->z[y->recv[k]] + y->S[k] * y->len[k];
    memset(&sh, 0, sizeof sh);
    sh.receiver = y->recv, sh.length = y->len, sh.A = y->A, sh.w = y->w;
    assert_int_equal(dfle_network_new(NN, &y->net, NULL), DFLE_OK);
    dfle_error err;
    assert_ok(dfle_network_set(y->net, &sh, &err), &err);
}

/* The nodes of a head's path, and its length. */
static size_t y_path(const ynet *y, size_t head, size_t *node)
{
    size_t n = 0, i = head;
    for (;;) {
        node[n++] = i;
        if (y->recv[i] == i)
            return n;
        i = y->recv[i];
    }
}

static int depth(void *s, double h, double v, double lambda, double *g, dfle_error *err)
{
    (void)s, (void)err, (void)v, (void)lambda;
    *g = h;
    return DFLE_OK;
}

/* The 1D model on one path: a chain of the path's cells (uniform dx). */
static void route_path_1d(const ynet *y, const size_t *node, size_t n, const dfle_process_opts *o,
                          dfle_flow *flow, dfle_process_report *rep)
{
    size_t recv[NN];
    double len[NN], A[NN], w[NN], S[NN];
    dfle_network *chain;
    dfle_network_shape sh;
    dfle_router *rt;
    dfle_error err;
    for (size_t j = 0; j < n; j++) {
        recv[j] = j + 1 < n ? j + 1 : j;
        len[j] = y->len[node[0]];
        A[j] = y->A[node[j]], w[j] = y->w[node[j]], S[j] = y->S[node[j]];
    }
    memset(&sh, 0, sizeof sh);
    sh.receiver = recv, sh.length = len, sh.A = A, sh.w = w;
    assert_int_equal(dfle_network_new(n, &chain, NULL), DFLE_OK);
    assert_ok(dfle_network_set(chain, &sh, &err), &err);
    assert_true(dfle_network_is_chain(chain));
    assert_ok(dfle_router_new_process(o, &rt, &err), &err);
    assert_int_equal(dfle_flow_init(flow, n, NULL), DFLE_OK);
    flow->integrand = depth;
    assert_ok(dfle_router_route(rt, chain, S, flow, &err), &err);
    *rep = *dfle_router_process_report(rt);
    dfle_router_free(rt);
    dfle_network_free(chain);
}

static void route_y(ynet *y, dfle_router *rt, dfle_flow *flow)
{
    dfle_error err;
    flow->integrand = depth;
    assert_ok(dfle_router_route(rt, y->net, y->S, flow, &err), &err);
}

/* Each flow down its own path is the 1D model on that path; where both
 * arrive the record holds their count, the mean of their sums and
 * passage times, the larger peak and the sum of volumes. */
static void two_heads_each_as_in_1d(void **state)
{
    ynet y;
    dfle_process_opts o;
    dfle_router *rt;
    dfle_flow flow, fa, fb;
    dfle_process_report ra, rb;
    size_t pa[NN], pb[NN], na, nb;
    double Ia[NN] = {0}, Ib[NN] = {0}, ha[NN] = {0}, hb[NN] = {0}, Ma[NN] = {0}, Mb[NN] = {0};
    double ca[NN] = {0}, cb[NN] = {0};
    dfle_error err;
    (void)state;
    y_build(&y, 5.0, 0);
    dfle_process_opts_default(&o);
    na = y_path(&y, 0, pa);
    nb = y_path(&y, NA, pb);
    route_path_1d(&y, pa, na, &o, &fa, &ra);
    route_path_1d(&y, pb, nb, &o, &fb, &rb);
    for (size_t j = 0; j < fa.runout_end; j++)
        Ia[pa[j]] = fa.integral[j], ha[pa[j]] = fa.h[j], Ma[pa[j]] = fa.M[j], ca[pa[j]] = 1;
    for (size_t j = 0; j < fb.runout_end; j++)
        Ib[pb[j]] = fb.integral[j], hb[pb[j]] = fb.h[j], Mb[pb[j]] = fb.M[j], cb[pb[j]] = 1;
    /* Both reach the junction and stop on the trunk: a real test of
     * joining and of runout. */
    assert_true(fa.runout_end > NA && fb.runout_end > NB);
    assert_true(fa.runout_end < na && fb.runout_end < nb);

    assert_ok(dfle_router_new_process(&o, &rt, &err), &err);
    assert_int_equal(dfle_flow_init(&flow, NN, NULL), DFLE_OK);
    route_y(&y, rt, &flow);
    const dfle_process_report *rep = dfle_router_process_report(rt);
    assert_true(rep->routed && rep->heads_network);
    assert_int_equal(rep->heads, 2);
    assert_int_equal(rep->heads_routed, 2);
    assert_close(rep->volume_in, 2 * o.M0, 1e-12, 0);
    assert_close(rep->volume_in, ra.volume_in + rb.volume_in, 1e-12, 0);
    assert_true(rep->volume_error < 1e-12);
    assert_true(flow.time_resolved);
    for (size_t i = 0; i < NN; i++) {
        const double c = ca[i] + cb[i];
        assert_close(flow.reach[i], c, 0, 0);
        if (c == 0) {
            assert_close(flow.integral[i], 0.0, 0, 0);
            continue;
        }
        assert_close(flow.integral[i], (Ia[i] + Ib[i]) / c, 1e-12, 1e-300);
        assert_close(flow.h[i], fmax(ha[i], hb[i]), 1e-12, 0);
        assert_close(flow.M[i], Ma[i] + Mb[i], 1e-12, 1e-12);
        assert_close(flow.Theta[i], 1.0, 0, 0);
    }
    dfle_flow_release(&flow);
    dfle_flow_release(&fa);
    dfle_flow_release(&fb);
    dfle_router_free(rt);
    dfle_network_free(y.net);
}

static double root_count(void *ud, double count, double A)
{
    (void)ud, (void)A;
    return sqrt(count);
}

/* E_df of the model on the network: k_df S^alpha times the mean sum,
 * weighed by the rule: "any" the mean, "count" the sum of both flows'
 * erosion, a function f(c, A) f times the mean. */
static void combine_rules_on_the_model(void **state)
{
    ynet y;
    dfle_process_opts o;
    dfle_power_law_opts lo;
    dfle_flow fa, fb;
    dfle_process_report ra, rb;
    size_t pa[NN], pb[NN], na, nb;
    double Ia[NN] = {0}, Ib[NN] = {0}, ca[NN] = {0}, cb[NN] = {0};
    const int rules[3] = {DFLE_DF_ANY, DFLE_DF_COUNT, DFLE_DF_CUSTOM};
    dfle_error err;
    (void)state;
    y_build(&y, 5.0, 0);
    dfle_process_opts_default(&o);
    dfle_power_law_opts_default(&lo);
    lo.beta = 1.0; /* the law's integrand is h, as depth() */
    na = y_path(&y, 0, pa);
    nb = y_path(&y, NA, pb);
    route_path_1d(&y, pa, na, &o, &fa, &ra);
    route_path_1d(&y, pb, nb, &o, &fb, &rb);
    for (size_t j = 0; j < fa.runout_end; j++)
        Ia[pa[j]] = fa.integral[j], ca[pa[j]] = 1;
    for (size_t j = 0; j < fb.runout_end; j++)
        Ib[pb[j]] = fb.integral[j], cb[pb[j]] = 1;
    for (int r = 0; r < 3; r++) {
        dfle_model_opts mo;
        dfle_model *m;
        dfle_router *rt;
        dfle_law *law;
        size_t both = 0;
        assert_ok(dfle_router_new_process(&o, &rt, &err), &err);
        assert_ok(dfle_law_new_power(&lo, &law, &err), &err);
        dfle_model_opts_default(&mo);
        mo.network = y.net;
        mo.router = rt;
        mo.law = law;
        mo.df_combine = rules[r];
        mo.df_frequency = root_count;
        assert_ok(dfle_model_new(&mo, &m, &err), &err);
        memcpy(dfle_model_z(m), y.z, NN * sizeof *y.z);
        dfle_model_touch(m);
        assert_ok(dfle_model_evaluate(m, &err), &err);
        const double *E = dfle_model_field(m, DFLE_FIELD_E_DF, &err);
        const double *S = dfle_model_field(m, DFLE_FIELD_S, &err);
        for (size_t i = 0; i + 1 < NN; i++) {
            const double c = ca[i] + cb[i], sum = Ia[i] + Ib[i];
            const double one = lo.k_df * pow(S[i], lo.alpha);
            double want = 0.0;
            if (c > 0 && S[i] > 0) /* no erosion up a reverse slope */
                want = rules[r] == DFLE_DF_COUNT ? one * sum
                       : rules[r] == DFLE_DF_ANY ? one * sum / c
                                                 : sqrt(c) * one * sum / c;
            both += c == 2 && sum > 0;
            assert_close(E[i], want, 1e-10, 1e-300);
        }
        assert_true(both > 3); /* the rule was exercised */
        dfle_model_free(m);
        dfle_law_free(law);
        dfle_router_free(rt);
    }
    dfle_flow_release(&fa);
    dfle_flow_release(&fb);
    dfle_network_free(y.net);
}

/* A tributary of diagonal steps (sqrt 2 longer cells): every flow keeps
 * its volume to round-off, and the flow down b is longer in time than
 * down the same slopes on cells of dx (it travels further). */
static void unequal_cells_keep_volume(void **state)
{
    ynet y;
    dfle_process_opts o;
    dfle_router *rt;
    dfle_flow flow;
    dfle_error err;
    (void)state;
    y_build(&y, 5.0, 1);
    assert_false(dfle_network_uniform_length(y.net));
    dfle_process_opts_default(&o);
    assert_ok(dfle_router_new_process(&o, &rt, &err), &err);
    assert_int_equal(dfle_flow_init(&flow, NN, NULL), DFLE_OK);
    route_y(&y, rt, &flow);
    const dfle_process_report *rep = dfle_router_process_report(rt);
    assert_int_equal(rep->heads, 2);
    assert_true(rep->volume_error < 1e-12);
    assert_close(rep->volume_out + rep->volume_left, rep->volume_in, 1e-12, 0);
    for (size_t i = NA; i < JUNCTION; i++)
        assert_true(flow.reach[i] == 1 && flow.integral[i] > 0);
    dfle_flow_release(&flow);
    dfle_router_free(rt);
    dfle_network_free(y.net);
}

/* The rule per head: a slope change below reroute_dS re-routes nothing
 * and keeps the sums; one at or above it on tributary b re-routes b
 * alone; one on the trunk both. */
static void reroute_per_head(void **state)
{
    ynet y;
    dfle_process_opts o;
    dfle_router *rt;
    dfle_flow flow;
    double I0[NN];
    dfle_error err;
    int reroute;
    (void)state;
    y_build(&y, 5.0, 0);
    dfle_process_opts_default(&o);
    assert_ok(dfle_router_new_process(&o, &rt, &err), &err);
    assert_int_equal(dfle_flow_init(&flow, NN, NULL), DFLE_OK);
    route_y(&y, rt, &flow);
    const dfle_process_report *rep = dfle_router_process_report(rt);
    assert_int_equal(rep->heads_routed, 2);
    memcpy(I0, flow.integral, sizeof I0);

    /* On a network the routing decides head by head. */
    assert_ok(dfle_router_needs_reroute(rt, NN, y.S, y.S, &reroute, &err), &err);
    assert_true(reroute);

    y.S[NA + 2] += 0.9 * o.reroute_dS; /* below the threshold */
    route_y(&y, rt, &flow);
    assert_int_equal(rep->heads_routed, 0);
    for (size_t i = 0; i < NN; i++)
        assert_close(flow.integral[i], I0[i], 0, 0);

    y.S[NA + 2] += 0.2 * o.reroute_dS; /* 1.1 dS since b's routing */
    route_y(&y, rt, &flow);
    assert_int_equal(rep->heads_routed, 1);
    for (size_t i = 0; i < NA; i++) /* a's own reach: only a's flow */
        assert_close(flow.integral[i], I0[i], 0, 0);
    assert_true(flow.integral[NA + 3] != I0[NA + 3]);

    y.S[JUNCTION + 1] -= 1.1 * o.reroute_dS; /* on both paths */
    route_y(&y, rt, &flow);
    assert_int_equal(rep->heads_routed, 2);
    assert_int_equal(rep->head_routings, 5);

    /* Another network of the same size: nothing kept applies. */
    {
        ynet y2;
        y_build(&y2, 5.0, 0);
        flow.integrand = depth;
        assert_ok(dfle_router_route(rt, y2.net, y2.S, &flow, &err), &err);
        assert_int_equal(rep->heads_routed, 2);
        for (size_t i = 0; i < NN; i++)
            assert_close(flow.integral[i], I0[i], 1e-12, 1e-300);
        dfle_network_free(y2.net);
    }
    dfle_flow_release(&flow);
    dfle_router_free(rt);
    dfle_network_free(y.net);
}

/* The network's shape again, from y's arrays. */
static void y_reshape(ynet *y)
{
    dfle_network_shape sh;
    dfle_error err;
    memset(&sh, 0, sizeof sh);
    sh.receiver = y->recv, sh.length = y->len, sh.A = y->A, sh.w = y->w;
    assert_ok(dfle_network_set(y->net, &sh, &err), &err);
}

/* Below the furthest cell a flow wetted its path does not matter: a
 * shorter path (a receiver changed) with other widths and slopes there
 * keeps every routing, and the kept sums are exactly what a fresh
 * routing of the changed network gives.  On the cells a flow felt, a
 * width moved by less than reroute_dw keeps it; by more re-routes. */
static void reroute_only_where_felt(void **state)
{
    ynet y;
    dfle_process_opts o;
    dfle_router *rt, *fresh;
    dfle_flow flow, flow2;
    size_t wet_end = 0, cut = NN - 40;
    double I0[NN];
    dfle_error err;
    (void)state;
    y_build(&y, 5.0, 0);
    dfle_process_opts_default(&o);
    assert_ok(dfle_router_new_process(&o, &rt, &err), &err);
    assert_int_equal(dfle_flow_init(&flow, NN, NULL), DFLE_OK);
    assert_int_equal(dfle_flow_init(&flow2, NN, NULL), DFLE_OK);
    route_y(&y, rt, &flow);
    const dfle_process_report *rep = dfle_router_process_report(rt);
    assert_int_equal(rep->heads_routed, 2);
    for (size_t i = 0; i < NN; i++)
        if (flow.h[i] > 0 || flow.M[i] > 0)
            wet_end = i + 1;
    assert_true(wet_end > JUNCTION && wet_end + 3 < cut); /* both rest on the trunk */
    memcpy(I0, flow.integral, sizeof I0);

    y.recv[cut] = NN - 1; /* skips the cells below cut */
    for (size_t i = cut; i < NN; i++) {
        y.w[i] *= 1.5;
        y.S[i] = 0.5;
    }
    y_reshape(&y);
    /* The cell below cut is a head now, of a flow of its own: the one
     * routed; a and b keep theirs. */
    route_y(&y, rt, &flow);
    assert_int_equal(rep->heads, 3);
    assert_int_equal(rep->heads_routed, 1);
    assert_ok(dfle_router_new_process(&o, &fresh, &err), &err);
    route_y(&y, fresh, &flow2);
    assert_int_equal(dfle_router_process_report(fresh)->heads_routed, 3);
    for (size_t i = 0; i < cut; i++) {
        assert_close(flow.integral[i], I0[i], 0, 0);
        assert_close(flow2.integral[i], I0[i], 0, 0);
        assert_close(flow.reach[i], flow2.reach[i], 0, 0);
    }

    y.w[NA + 2] *= 1.0 + 0.5 * o.reroute_dw; /* on b's path, below the threshold */
    y_reshape(&y);
    route_y(&y, rt, &flow);
    assert_int_equal(rep->heads_routed, 0);
    for (size_t i = 0; i < NN; i++)
        assert_close(flow.integral[i], flow2.integral[i], 0, 0);
    y.w[NA + 2] *= 1.0 + o.reroute_dw; /* 1.5 dw since b's routing, and more */
    y_reshape(&y);
    route_y(&y, rt, &flow);
    assert_int_equal(rep->heads_routed, 1);
    assert_true(flow.integral[NA + 2] != I0[NA + 2]);
    dfle_flow_release(&flow);
    dfle_flow_release(&flow2);
    dfle_router_free(rt);
    dfle_router_free(fresh);
    dfle_network_free(y.net);
}

static int refuses(void *s, double h, double v, double lambda, double *g, dfle_error *err)
{
    (void)s, (void)h, (void)v, (void)lambda, (void)g;
    return dfle_error_set(err, DFLE_ENUMERIC, "integrand refused");
}

/* A routing that fails names the head whose flow failed, keeps nothing
 * of that routing, and the next one routes every head afresh. */
static void failing_integrand_names_the_head(void **state)
{
    ynet y;
    dfle_process_opts o;
    dfle_router *rt;
    dfle_flow flow;
    dfle_error err;
    (void)state;
    y_build(&y, 5.0, 0);
    dfle_process_opts_default(&o);
    assert_ok(dfle_router_new_process(&o, &rt, &err), &err);
    assert_int_equal(dfle_flow_init(&flow, NN, NULL), DFLE_OK);
    flow.integrand = refuses;
    assert_int_equal(dfle_router_route(rt, y.net, y.S, &flow, &err), DFLE_ENUMERIC);
    assert_msg_contains(err.msg, "integrand refused");
    assert_msg_contains(err.msg, "head node 1");
    route_y(&y, rt, &flow);
    assert_int_equal(dfle_router_process_report(rt)->heads_routed, 2);
    dfle_flow_release(&flow);
    dfle_router_free(rt);
    dfle_network_free(y.net);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(two_heads_each_as_in_1d),
        cmocka_unit_test(combine_rules_on_the_model),
        cmocka_unit_test(unequal_cells_keep_volume),
        cmocka_unit_test(reroute_per_head),
        cmocka_unit_test(reroute_only_where_felt),
        cmocka_unit_test(failing_integrand_names_the_head),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
