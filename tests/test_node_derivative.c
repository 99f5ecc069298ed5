/* test_node_derivative.c - how erosion at one node answers its slope:
 * the empirical router's node_flow_dlnS, each built-in law's rate_dlnS
 * and the model's dfle_model_node_erosion_dlnS against centred
 * differences in ln S, over many slopes and areas: flat and very steep,
 * and on both sides of tau = tau_y, where Theta -> 0; and laws written
 * in Lua, whose op differentiates their compiled programs. */
#include <math.h>
#include <stdio.h>
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

#include <lauxlib.h>
#include <lua.h>
#include <lualib.h>

#include "dfle/lua.h"
#include "lua/core/dfle_lua.h"

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
        assert_ok(dfle_router_node_flow_dlnS(rt, r->net, i, S, log(S), &r->node, &d, &on, &err), &err);
        assert_ok(dfle_router_node_flow(rt, r->net, i, S, &f2, &on2, &err), &err);
        assert_int_equal(on, on2);
        /* The same flow to rounding: the depth comes from ln S by an exp
         * on one path, from S by a cbrt on the other. */
        assert_close(r->node.h[0], f2.h[0], 1e-14, 0.0);
        assert_close(r->node.tau[0], f2.tau[0], 1e-14, 0.0);
        assert_close(r->node.Theta[0], f2.Theta[0], 1e-13, 1e-15);
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
    assert_ok(dfle_router_node_flow_dlnS(rt, r->net, i, S, log(S), &r->node, &d, &on, &err), &err);
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
    assert_ok(dfle_model_node_erosion_dlnS(m, i, S, log(S), flows, &E, &dE, &on, &err), &err);
    assert_ok(dfle_model_node_erosion(m, i, S, flows, &E1, &on1, &err), &err);
    assert_close(E, E1, 1e-13, 0.0); /* the same E, to rounding (ln S against S) */
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
    assert_ok(dfle_model_node_erosion_dlnS(m, 3, -0.1, NAN, 1.0, &E, &dE, &on, &err), &err);
    assert_true(E == 0 && dE == 0); /* a reverse slope erodes nothing */
    dfle_model_free(m);

    /* Without the law's op: E as before, dE NaN. */
    plain = dfle_test_without_rate_dlnS(law, &ops);
    mo.law = plain;
    assert_ok(dfle_model_new(&mo, &m, &err), &err);
    assert_false(dfle_model_node_dlnS(m));
    assert_ok(dfle_model_node_erosion_dlnS(m, 40, 0.5, log(0.5), 1.0, &E, &dE, &on, &err), &err);
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

/* ---- laws written in Lua: rate_dlnS by differentiating the programs ---- */

/* A law defined by `def` (the table of dfle.law.define, in Lua), kept
 * in L's registry (alive until lua_close). */
static dfle_law *lua_law(lua_State *L, const char *def)
{
    char code[1024];
    dfle_law *law;
    snprintf(code, sizeof code, "return dfle.law.define%s", def);
    if (luaL_loadstring(L, code) != LUA_OK || lua_pcall(L, 0, 1, 0) != LUA_OK) {
        print_error("%s\n", lua_tostring(L, -1));
        fail();
    }
    law = dfle_lua_check_law(L, -1);
    luaL_ref(L, LUA_REGISTRYINDEX);
    return law;
}

static lua_State *lua_with_dfle(void)
{
    lua_State *L = luaL_newstate();
    assert_non_null(L);
    luaL_openlibs(L);
    luaL_requiref(L, "dfle", luaopen_dfle, 1);
    lua_pop(L, 1);
    return L;
}

/* Lua laws that mirror built-in ones (with a factor and without), one
 * with exp, log, min, sqrt, abs, a division and a slope-dependent
 * exponent, and one with the other operations: their compiled programs'
 * rate_dlnS against a centred difference, and against the built-in
 * law's own op, with the flow following S and held (d = NULL). */
static void lua_laws_rate_dlnS(void **state)
{
    rig *r = *state;
    lua_State *L = lua_with_dfle();
    dfle_power_law_opts po;
    dfle_excess_stress_law_opts eo;
    dfle_law *lua[6], *builtin[6] = {NULL};
    point pt[MAX_POINTS];
    const size_t np = points_of(r, pt);
    lua[0] = lua_law(L, "{ params = { k_df = 1e-4, alpha = 6, beta = 1 },"
                        "  factor = function(c, p) return c.t_p * c.h ^ p.beta * c.Theta end,"
                        "  rate = function(c, p) return p.k_df * c.S ^ p.alpha * c.F end }");
    lua[1] = lua_law(L, "{ params = { k_df = 1e-4, alpha = 2.5, beta = 0.7 },"
                        "  rate = function(c, p)"
                        "    return p.k_df * c.S ^ p.alpha * c.t_p * c.h ^ p.beta * c.Theta end }");
    /* tau_c above the router's tau_y = 300 Pa: where the excess is
     * positive the flow goes on, as the built-in law requires. */
    lua[2] = lua_law(L, "{ params = { k = 1e-9, tau_c = 500, p = 1.5 },"
                        "  factor = function(c, p) return math.max(c.tau - p.tau_c, 0) ^ p.p end,"
                        "  rate = function(c, p) return p.k * c.F end }");
    lua[3] = lua_law(L, "{ params = { k = 1e-9, tau_c = 400, p = 0.6 },"
                        "  rate = function(c, p) return p.k * math.max(c.tau - p.tau_c, 0) ^ p.p end }");
    lua[4] = lua_law(L, "{ params = { k = 1e-5, a = 3.5, hmax = 2 },"
                        "  rate = function(c, p)"
                        "    return p.k * math.exp(p.a * math.log(c.S)) * math.min(c.h, p.hmax)"
                        "      * math.sqrt(c.t_p) * c.Theta / (1 + math.abs(c.v - 5))"
                        "      * c.S ^ (0.1 * c.Theta) end }");
    /* Every other operation with a rule: trigonometry, log to a base,
     * deg and rad, and the quotients flat between their jumps. */
    lua[5] = lua_law(
        L, "{ params = { k = 1e-4 }, rate = function(c, p)"
           "  return p.k * c.S ^ 2 * (2 + math.sin(c.h)) * (2 + math.cos(0.01 * c.v))"
           "    * (1 + math.atan(c.tau, 100)) * (2 + math.tan(0.3 * c.Theta))"
           "    * (1 + math.asin(0.5 * c.Theta)) * (2 + math.acos(0.5 * c.Theta))"
           "    * math.log(1 + c.S, 10) / math.log(2 + c.S, 3) * math.log(1 + c.S, 2)"
           "    * (1 + math.rad(math.deg(c.Theta)))"
           "    * (1 + c.h % 7 + math.fmod(c.h, 5) + c.h // 3 + math.floor(c.h) - math.ceil(c.h))"
           "  end }");
    dfle_power_law_opts_default(&po);
    assert_int_equal(dfle_law_new_power(&po, &builtin[0], NULL), DFLE_OK);
    po.alpha = 2.5, po.beta = 0.7;
    assert_int_equal(dfle_law_new_power(&po, &builtin[1], NULL), DFLE_OK);
    dfle_excess_stress_law_opts_default(&eo);
    assert_int_equal(dfle_law_new_excess_stress(&eo, &builtin[2], NULL), DFLE_OK);
    eo.tau_c = 400, eo.p = 0.6;
    assert_int_equal(dfle_law_new_excess_stress(&eo, &builtin[3], NULL), DFLE_OK);
    for (size_t l = 0; l < 6; l++) {
        size_t nonzero = 0;
        /* No op before the programs are compiled and checked against Lua
         * (the first evaluation does both), then one. */
        assert_false(dfle_law_has_rate_dlnS(lua[l]));
        law_at(r, r->rt[0], lua[l], 40, 0.3, NULL);
        assert_true(dfle_law_has_rate_dlnS(lua[l]));
        for (size_t q = 0; q < np; q++) {
            dfle_router *rt = r->rt[pt[q].k];
            const size_t i = pt[q].i;
            const double S = pt[q].S, h = pt[q].h;
            double dE, E = law_at(r, rt, lua[l], i, S, &dE), Em, Ep;
            if (builtin[l] != NULL) {
                /* The same flow at S; then held (d = NULL). */
                dfle_law_ctx ctx = {.n = 1, .S = &S, .A = dfle_network_A(r->net) + i,
                                    .w = dfle_network_w(r->net) + i, .flow = &r->node};
                double dEb, Eb = law_at(r, rt, builtin[l], i, S, &dEb), F[2], Eh[2], dEh[2];
                dfle_error err;
                assert_close(E, Eb, 1e-13, 0);
                assert_close(dE, dEb, 1e-10, 1e-12 * fabs(Eb));
                for (int b = 0; b < 2; b++) {
                    dfle_law *law = b ? builtin[l] : lua[l];
                    assert_ok(dfle_law_flow_factor(law, &ctx, &F[b], &err), &err);
                    assert_ok(dfle_law_rate(law, &ctx, &F[b], &Eh[b], &err), &err);
                    assert_ok(dfle_law_rate_dlnS(law, &ctx, &F[b], &Eh[b], NULL, &dEh[b], &err),
                              &err);
                }
                assert_close(dEh[0], dEh[1], 1e-10, 1e-12 * fabs(Eb));
            }
            Em = law_at(r, rt, lua[l], i, S * exp(-h), NULL);
            Ep = law_at(r, rt, lua[l], i, S * exp(h), NULL);
            /* A threshold of the law's own (tau = tau_c, min's switch) is
             * not a point to difference across. */
            if ((Em == 0) != (Ep == 0))
                continue;
            if (l == 4 && (r->node.h[0] - 2) * (r->node.h[0] - 2) < 1e-6)
                continue;
            check_field(dE, Em, Ep, h, 0, fabs(E), dfle_law_name(lua[l]), i, S);
            nonzero += dE != 0;
        }
        assert_true(nonzero > 20);
    }
    for (size_t l = 0; l < 6; l++)
        dfle_law_free(builtin[l]);
    lua_close(L);
}

/* No op where the programs cannot give one: a function the tracer
 * refuses (it branches on a flow field, so runs as Lua), or compile =
 * false. */
static void lua_laws_without_rate_dlnS(void **state)
{
    rig *r = *state;
    lua_State *L = lua_with_dfle();
    dfle_law *refused = lua_law(L, "{ rate = function(c, p)"
                                   "  if c.h > 1 then return 1e-4 * c.S ^ 2 end"
                                   "  return 1e-4 * c.S end }");
    dfle_law *plain = lua_law(L, "{ compile = false,"
                                 "  rate = function(c, p) return 1e-4 * c.S ^ 2 * c.h end }");
    law_at(r, r->rt[0], refused, 40, 0.3, NULL);
    law_at(r, r->rt[0], plain, 40, 0.3, NULL);
    assert_false(dfle_law_has_rate_dlnS(refused));
    assert_false(dfle_law_has_rate_dlnS(plain));
    lua_close(L);
}

/* The direct steady state with a compiled Lua Eq. (6) law is the
 * built-in law's, to the solvers' tolerance, and takes Newton's path:
 * about as many one-node erosions per node as the built-in law, where
 * differences take about 6.6. */
static void lua_law_direct_steady_state(void **state)
{
    rig *r = *state;
    lua_State *L = lua_with_dfle();
    dfle_law *law[2];
    dfle_power_law_opts po;
    dfle_stochastic_threshold_opts so;
    dfle_fluvial *fl;
    const size_t n = dfle_channel_size(r->ch);
    double *S = malloc(2 * n * sizeof *S), per[2];
    dfle_power_law_opts_default(&po);
    assert_int_equal(dfle_law_new_power(&po, &law[0], NULL), DFLE_OK);
    law[1] = lua_law(L, "{ params = { k_df = 1e-4, alpha = 6, beta = 1 },"
                        "  factor = function(c, p) return c.t_p * c.h ^ p.beta * c.Theta end,"
                        "  rate = function(c, p) return p.k_df * c.S ^ p.alpha * c.F end }");
    dfle_stochastic_threshold_opts_default(&so);
    assert_int_equal(dfle_fluvial_new_stochastic_threshold(&so, &fl, NULL), DFLE_OK);
    for (int k = 0; k < 2; k++) {
        dfle_model_opts mo;
        dfle_model *m;
        dfle_run_opts ro;
        dfle_run_result res;
        dfle_error err;
        dfle_model_opts_default(&mo);
        mo.channel = r->ch, mo.fluvial = fl, mo.router = r->rt[0], mo.law = law[k];
        assert_ok(dfle_model_new(&mo, &m, &err), &err);
        dfle_run_opts_default(&ro);
        ro.method = DFLE_METHOD_DIRECT;
        assert_ok(dfle_solver_run(m, &ro, &res, &err), &err);
        assert_true(res.converged && !res.fallback);
        memcpy(S + k * n, dfle_model_field(m, DFLE_FIELD_S, &err), n * sizeof *S);
        per[k] = (double)dfle_model_node_evaluations(m) / (double)(n - 1);
        dfle_model_free(m);
    }
    for (size_t i = 0; i + 1 < n; i++)
        assert_close(S[n + i], S[i], 1e-10, 0);
    print_message("one-node erosions per node: built-in %.2f, compiled Lua %.2f\n", per[0],
                  per[1]);
    assert_true(per[1] < per[0] + 0.05);
    free(S);
    dfle_fluvial_free(fl);
    dfle_law_free(law[0]);
    lua_close(L);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(router_node_flow_dlnS),
        cmocka_unit_test(laws_rate_dlnS_with_the_flow),
        cmocka_unit_test(laws_rate_dlnS_with_the_flow_held),
        cmocka_unit_test(model_node_erosion_dlnS),
        cmocka_unit_test(lua_laws_rate_dlnS),
        cmocka_unit_test(lua_laws_without_rate_dlnS),
        cmocka_unit_test(lua_law_direct_steady_state),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
