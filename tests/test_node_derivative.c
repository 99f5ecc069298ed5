/* test_node_derivative.c - how erosion at one node answers its slope:
 * the empirical router's node_flow_dlnS, each built-in law's rate_dlnS
 * and the model's dfle_model_node_erosion_dlnS against centred
 * differences in ln S, over many slopes and areas: flat and very steep,
 * and on both sides of tau = tau_y, where Theta -> 0. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dfle_test.h"
#include "dfle/law_excess_stress.h"
#include "dfle/law_inertial.h"
#include "dfle/law_power.h"
#include "dfle/model.h"
#include "dfle/network.h"
#include "dfle/router_empirical.h"
#include "dfle/router_process.h"
#include "dfle/solver.h"

/* Half-width of the centred differences in ln S: truncation ~h^2/6 and
 * round-off ~1e-16/h, both ~1e-11 relative. */
#define H 1e-5

typedef struct rig {
    dfle_channel *ch;
    dfle_network *net;
    dfle_router *rt[2]; /* tau_y = 300 Pa (the default) and 0 */
    dfle_flow node;     /* one node's flow */
} rig;

static int setup(void **state)
{
    static rig r;
    dfle_channel_opts co;
    dfle_empirical_opts eo;
    memset(&r, 0, sizeof r);
    dfle_channel_opts_default(&co); /* dx = 5 m, A to 8 km^2: 403 nodes */
    dfle_empirical_opts_default(&eo);
    if (dfle_channel_new(&co, &r.ch, NULL) != DFLE_OK ||
        dfle_network_new_chain(r.ch, &r.net, NULL) != DFLE_OK ||
        dfle_router_new_empirical(&eo, &r.rt[0], NULL) != DFLE_OK ||
        dfle_flow_init(&r.node, 1, NULL) != DFLE_OK)
        return -1;
    eo.tau_y = 0;
    if (dfle_router_new_empirical(&eo, &r.rt[1], NULL) != DFLE_OK)
        return -1;
    *state = &r;
    return 0;
}

static int teardown(void **state)
{
    rig *r = *state;
    dfle_flow_release(&r->node);
    dfle_router_free(r->rt[0]);
    dfle_router_free(r->rt[1]);
    dfle_network_free(r->net);
    dfle_channel_free(r->ch);
    return 0;
}

static const size_t nodes[] = {0, 7, 40, 150, 300, 402};

/* The slope [-] at which tau = tau_y at node i (bisection in ln S; tau
 * grows with S over [1e-8, 1] on this channel). */
static double threshold_slope(rig *r, size_t i)
{
    double lo = log(1e-8), hi = 0.0;
    int on;
    for (int k = 0; k < 200; k++) {
        double mid = 0.5 * (lo + hi);
        assert_int_equal(dfle_router_node_flow(r->rt[0], r->net, i, exp(mid), &r->node, &on,
                                               NULL),
                         DFLE_OK);
        if (on)
            hi = mid;
        else
            lo = mid;
    }
    return exp(hi);
}

/* The slopes to try at node i: flat to very steep, and next to the
 * threshold on both sides.  Returns how many; h[k] is the difference
 * step for slope k, small enough not to straddle the threshold. */
static size_t slopes_at(rig *r, size_t i, double *S, double *h)
{
    static const double plain[] = {1e-6, 1e-3, 0.03, 0.3, 0.8, 3.0, 30.0, 300.0};
    static const double near[] = {1 - 1e-2, 1 - 1e-5, 1 + 1e-6, 1 + 1e-4, 1 + 1e-2};
    const double s_y = threshold_slope(r, i);
    size_t k = 0;
    for (size_t j = 0; j < sizeof plain / sizeof plain[0]; j++, k++) {
        S[k] = plain[j];
        h[k] = fmin(H, 0.1 * fabs(log(S[k] / s_y)));
    }
    for (size_t j = 0; j < sizeof near / sizeof near[0]; j++, k++) {
        S[k] = s_y * near[j];
        h[k] = fmin(H, 0.1 * fabs(log(near[j])));
    }
    return k;
}

/* Where the derivatives are tried: each router (k), node and slope. */
typedef struct point {
    int k;
    size_t i;
    double S, h; /* slope [-], and the half-width of its difference */
} point;
#define MAX_POINTS (2 * sizeof nodes / sizeof nodes[0] * 16)

static size_t points_of(rig *r, point *pt)
{
    size_t np = 0;
    for (int k = 0; k < 2; k++)
        for (size_t j = 0; j < sizeof nodes / sizeof nodes[0]; j++) {
            double S[16], h[16];
            size_t ns = slopes_at(r, nodes[j], S, h);
            for (size_t q = 0; q < ns; q++)
                pt[np++] = (point){.k = k, .i = nodes[j], .S = S[q], .h = h[q]};
        }
    return np;
}

/* Both flows of a field: the derivative op's, against the difference of
 * the field at S e^{-h} and S e^{+h} (of its log for a positive field). */
static void check_field(double analytic, double minus, double plus, double h, int logarithmic,
                        double scale, const char *what, size_t i, double S)
{
    double fd = logarithmic ? (log(plus) - log(minus)) / (2 * h) : (plus - minus) / (2 * h);
    if (!(fabs(analytic - fd) <= 1e-6 * fabs(fd) + 1e-9 * scale)) {
        print_error("%s at node %zu, S = %.10g: op %.12g, difference %.12g\n", what, i, S,
                    analytic, fd);
        fail();
    }
}

/* The empirical router: every field's derivative, and the same flow as
 * node_flow, bit for bit. */
static void router_node_flow_dlnS(void **state)
{
    rig *r = *state;
    dfle_flow f2;
    double block[2][DFLE_FLOW_ARRAYS];
    dfle_flow fm, fp;
    point pt[MAX_POINTS];
    size_t np = points_of(r, pt), stopped = 0;
    dfle_flow_bind(&fm, block[0], 1);
    dfle_flow_bind(&fp, block[1], 1);
    assert_int_equal(dfle_flow_init(&f2, 1, NULL), DFLE_OK);
    for (size_t q = 0; q < np; q++) {
        dfle_router *rt = r->rt[pt[q].k];
        const size_t i = pt[q].i;
        const double S = pt[q].S, h = pt[q].h;
        dfle_flow_dlnS d;
        int on, on2, onm, onp;
        dfle_error err;
        assert_ok(dfle_router_node_flow_dlnS(rt, r->net, i, S, &r->node, &d, &on, &err), &err);
        assert_ok(dfle_router_node_flow(rt, r->net, i, S, &f2, &on2, &err), &err);
        assert_int_equal(on, on2);
        assert_memory_equal(r->node.h, f2.h, sizeof(double));
        assert_memory_equal(r->node.tau, f2.tau, sizeof(double));
        assert_memory_equal(r->node.Theta, f2.Theta, sizeof(double));
        assert_ok(dfle_router_node_flow(rt, r->net, i, S * exp(-h), &fm, &onm, &err), &err);
        assert_ok(dfle_router_node_flow(rt, r->net, i, S * exp(h), &fp, &onp, &err), &err);
        assert_int_equal(onm, on); /* the step stays on one side */
        assert_int_equal(onp, on);
        check_field(d.h, fm.h[0], fp.h[0], h, 1, 1, "d ln h", i, S);
        check_field(d.v, fm.v[0], fp.v[0], h, 1, 1, "d ln v", i, S);
        check_field(d.tau, fm.tau[0], fp.tau[0], h, 1, 1, "d ln tau", i, S);
        check_field(d.Theta, fm.Theta[0], fp.Theta[0], h, 0, 1, "dTheta", i, S);
        check_field(d.M, fm.M[0], fp.M[0], h, 1, 1, "d ln M", i, S);
        check_field(d.t_p, fm.t_p[0], fp.t_p[0], h, 1, 1, "d ln t_p", i, S);
        stopped += !on;
    }
    /* Both sides of the threshold were seen. */
    assert_true(stopped > 10 && stopped < np - 10);
    dfle_flow_release(&f2);
}

/* E_df of `law` at node i for slope S, the flow following S; and its
 * derivative op's dE/d ln S when dE is set. */
static double law_at(rig *r, dfle_router *rt, dfle_law *law, size_t i, double S, double *dE)
{
    const double *A = dfle_network_A(r->net), *w = dfle_network_w(r->net);
    dfle_law_ctx ctx = {.n = 1, .S = &S, .A = A + i, .w = w + i, .flow = &r->node};
    dfle_flow_dlnS d;
    double F, E;
    int on;
    dfle_error err;
    assert_ok(dfle_router_node_flow_dlnS(rt, r->net, i, S, &r->node, &d, &on, &err), &err);
    assert_ok(dfle_law_flow_factor(law, &ctx, &F, &err), &err);
    assert_ok(dfle_law_rate(law, &ctx, &F, &E, &err), &err);
    if (dE != NULL)
        assert_ok(dfle_law_rate_dlnS(law, &ctx, &F, &E, &d, dE, &err), &err);
    return E;
}

/* Each built-in law's rate_dlnS, with the flow moving with S as the
 * empirical router moves it. */
static void laws_rate_dlnS_with_the_flow(void **state)
{
    rig *r = *state;
    dfle_law *laws[6];
    dfle_power_law_opts po;
    dfle_inertial_law_opts io;
    dfle_excess_stress_law_opts eo;
    point pt[MAX_POINTS];
    const size_t np = points_of(r, pt);
    dfle_power_law_opts_default(&po); /* alpha = 6, beta = 1 */
    assert_int_equal(dfle_law_new_power(&po, &laws[0], NULL), DFLE_OK);
    po.alpha = 2.5, po.beta = 0.7;
    assert_int_equal(dfle_law_new_power(&po, &laws[1], NULL), DFLE_OK);
    po.alpha = 0, po.beta = 0;
    assert_int_equal(dfle_law_new_power(&po, &laws[2], NULL), DFLE_OK);
    dfle_inertial_law_opts_default(&io);
    assert_int_equal(dfle_law_new_inertial(&io, &laws[3], NULL), DFLE_OK);
    dfle_excess_stress_law_opts_default(&eo); /* tau_c = 500 Pa, p = 1.5 */
    assert_int_equal(dfle_law_new_excess_stress(&eo, &laws[4], NULL), DFLE_OK);
    eo.p = 0.6, eo.tau_c = 200;
    assert_int_equal(dfle_law_new_excess_stress(&eo, &laws[5], NULL), DFLE_OK);
    for (size_t l = 0; l < 6; l++) {
        size_t nonzero = 0;
        for (size_t q = 0; q < np; q++) {
            dfle_router *rt = r->rt[pt[q].k];
            const size_t i = pt[q].i;
            const double S = pt[q].S, h = pt[q].h;
            double dE, E = law_at(r, rt, laws[l], i, S, &dE);
            double Em = law_at(r, rt, laws[l], i, S * exp(-h), NULL);
            double Ep = law_at(r, rt, laws[l], i, S * exp(h), NULL);
            /* The excess-stress law's own threshold, tau = tau_c: not a
             * point to difference across. */
            if ((Em == 0) != (Ep == 0))
                continue;
            check_field(dE, Em, Ep, h, 0, fabs(E), dfle_law_name(laws[l]), i, S);
            nonzero += dE != 0;
        }
        assert_true(nonzero > 20);
        dfle_law_free(laws[l]);
    }
}

/* A flow held as it is (d = NULL: a router routed rarely): only S^alpha
 * moves, and the excess-stress law, all flow, does not move at all. */
static void laws_rate_dlnS_with_the_flow_held(void **state)
{
    rig *r = *state;
    dfle_power_law_opts po;
    dfle_inertial_law_opts io;
    dfle_excess_stress_law_opts eo;
    dfle_law *laws[3];
    const double *A = dfle_network_A(r->net), *w = dfle_network_w(r->net);
    dfle_power_law_opts_default(&po);
    po.alpha = 4.3;
    dfle_inertial_law_opts_default(&io);
    dfle_excess_stress_law_opts_default(&eo);
    assert_int_equal(dfle_law_new_power(&po, &laws[0], NULL), DFLE_OK);
    assert_int_equal(dfle_law_new_inertial(&io, &laws[1], NULL), DFLE_OK);
    assert_int_equal(dfle_law_new_excess_stress(&eo, &laws[2], NULL), DFLE_OK);
    for (size_t l = 0; l < 3; l++) {
        int on;
        double F;
        dfle_law_ctx ctx = {.n = 1, .A = A + 40, .w = w + 40, .flow = &r->node};
        assert_int_equal(dfle_router_node_flow(r->rt[1], r->net, 40, 0.6, &r->node, &on, NULL),
                         DFLE_OK);
        assert_int_equal(dfle_law_flow_factor(laws[l], &ctx, &F, NULL), DFLE_OK);
        for (double S = 1e-3; S < 100; S *= 3.7) {
            double E, Em, Ep, dE, s;
            ctx.S = &s;
            s = S * exp(-H);
            assert_int_equal(dfle_law_rate(laws[l], &ctx, &F, &Em, NULL), DFLE_OK);
            s = S * exp(H);
            assert_int_equal(dfle_law_rate(laws[l], &ctx, &F, &Ep, NULL), DFLE_OK);
            s = S;
            assert_int_equal(dfle_law_rate(laws[l], &ctx, &F, &E, NULL), DFLE_OK);
            assert_int_equal(dfle_law_rate_dlnS(laws[l], &ctx, &F, &E, NULL, &dE, NULL),
                             DFLE_OK);
            check_field(dE, Em, Ep, H, 0, fabs(E), dfle_law_name(laws[l]), 40, S);
        }
        dfle_law_free(laws[l]);
    }
}

/* E and dE/d ln S of the model at node i against a difference of E. */
static void check_model_node(dfle_model *m, size_t i, double S, double flows, double h)
{
    double E, dE, Em, Ep, E1;
    int on, on1;
    dfle_error err;
    assert_ok(dfle_model_node_erosion_dlnS(m, i, S, flows, &E, &dE, &on, &err), &err);
    assert_ok(dfle_model_node_erosion(m, i, S, flows, &E1, &on1, &err), &err);
    assert_memory_equal(&E, &E1, sizeof E); /* the same E, to the bit */
    assert_int_equal(on, on1);
    assert_ok(dfle_model_node_erosion(m, i, S * exp(-h), flows, &Em, &on1, &err), &err);
    assert_ok(dfle_model_node_erosion(m, i, S * exp(h), flows, &Ep, &on1, &err), &err);
    check_field(dE, Em, Ep, h, 0, fabs(E), "dE/d ln S of the model", i, S);
}

/* The model: E_f + E_df, the flow re-evaluated for S, scaled by the
 * erodibility in space; the process router's held Eq. (11) factor; and
 * NaN where a part has no derivative op. */
static void model_node_erosion_dlnS(void **state)
{
    rig *r = *state;
    dfle_fluvial *fl;
    dfle_law *law, *plain;
    dfle_law_ops ops;
    dfle_power_law_opts po;
    dfle_model_opts mo;
    dfle_model *m;
    dfle_router *proc;
    dfle_process_opts pro;
    dfle_stochastic_threshold_opts so;
    double *scale, E, dE;
    int on;
    dfle_error err;
    const size_t n = dfle_channel_size(r->ch);
    point pt[MAX_POINTS];
    const size_t np = points_of(r, pt);

    dfle_stochastic_threshold_opts_default(&so);
    assert_int_equal(dfle_fluvial_new_stochastic_threshold(&so, &fl, NULL), DFLE_OK);
    dfle_power_law_opts_default(&po);
    assert_int_equal(dfle_law_new_power(&po, &law, NULL), DFLE_OK);
    dfle_model_opts_default(&mo);
    mo.channel = r->ch, mo.fluvial = fl, mo.router = r->rt[0], mo.law = law;
    assert_ok(dfle_model_new(&mo, &m, &err), &err);
    assert_true(dfle_model_node_dlnS(m));
    scale = malloc(n * sizeof *scale);
    for (size_t i = 0; i < n; i++)
        scale[i] = 0.5 + (double)(i % 7) / 3.0;
    assert_ok(dfle_model_set_erodibility(m, scale, scale, &err), &err);
    for (size_t q = 0; q < np; q++)
        if (pt[q].k == 0) { /* the model's router: tau_y = 300 Pa */
            check_model_node(m, pt[q].i, pt[q].S, 1.0, pt[q].h);
            check_model_node(m, pt[q].i, pt[q].S, 0.0, pt[q].h); /* no flow arrives */
        }
    assert_ok(dfle_model_node_erosion_dlnS(m, 3, -0.1, 1.0, &E, &dE, &on, &err), &err);
    assert_true(E == 0 && dE == 0); /* a reverse slope erodes nothing */
    dfle_model_free(m);

    /* Without the law's op: E as before, dE NaN. */
    plain = dfle_test_without_rate_dlnS(law, &ops);
    mo.law = plain;
    assert_ok(dfle_model_new(&mo, &m, &err), &err);
    assert_false(dfle_model_node_dlnS(m));
    assert_ok(dfle_model_node_erosion_dlnS(m, 40, 0.5, 1.0, &E, &dE, &on, &err), &err);
    assert_true(isnan(dE) && E > 0);
    dfle_model_free(m);
    dfle_law_free(plain);

    /* Routed rarely: the cached factor stands and only S moves. */
    dfle_process_opts_default(&pro);
    assert_int_equal(dfle_router_new_process(&pro, &proc, NULL), DFLE_OK);
    mo.router = proc, mo.law = law;
    assert_ok(dfle_model_new(&mo, &m, &err), &err);
    assert_true(dfle_model_node_dlnS(m));
    assert_ok(dfle_model_evaluate(m, &err), &err);
    for (size_t i = 0; i < n; i += 9)
        if (dfle_model_flow_reaches(m, i) > 0)
            for (double S = 1e-4; S < 100; S *= 5.3)
                check_model_node(m, i, S, 1.0, H);
    dfle_model_free(m);
    dfle_router_free(proc);
    free(scale);
    dfle_law_free(law);
    dfle_fluvial_free(fl);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(router_node_flow_dlnS),
        cmocka_unit_test(laws_rate_dlnS_with_the_flow),
        cmocka_unit_test(laws_rate_dlnS_with_the_flow_held),
        cmocka_unit_test(model_node_erosion_dlnS),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
