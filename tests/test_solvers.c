/* test_solvers.c - the implicit and direct methods reach the explicit
 * method's steady state (and the analytical ones), follow it through a
 * transient, and fall back when no direct solution exists. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dfle_test.h"
#include "dfle/analysis.h"
#include "dfle/analytical.h"
#include "dfle/law_excess_stress.h"
#include "dfle/law_inertial.h"
#include "dfle/law_power.h"
#include "dfle/model.h"
#include "dfle/solver.h"
#include "dfle/router_empirical.h"
#include "dfle/router_process.h"

typedef struct parts {
    dfle_channel *ch;
    dfle_fluvial *fl;
    dfle_router *rt;
    dfle_law *law;
} parts;

static void parts_free(parts *p)
{
    dfle_law_free(p->law);
    dfle_router_free(p->rt);
    dfle_fluvial_free(p->fl);
    dfle_channel_free(p->ch);
    memset(p, 0, sizeof *p);
}

static void make_channel(parts *p, double dx)
{
    dfle_channel_opts co;
    dfle_channel_opts_default(&co);
    co.dx = dx;
    assert_int_equal(dfle_channel_new(&co, &p->ch, NULL), DFLE_OK);
}

static void make_fluvial(parts *p)
{
    dfle_stochastic_threshold_opts so;
    dfle_stochastic_threshold_opts_default(&so);
    assert_int_equal(dfle_fluvial_new_stochastic_threshold(&so, &p->fl, NULL), DFLE_OK);
}

static void make_law(parts *p, double k_df, double alpha, double beta)
{
    dfle_power_law_opts lo = {.k_df = k_df, .alpha = alpha, .beta = beta};
    assert_int_equal(dfle_law_new_power(&lo, &p->law, NULL), DFLE_OK);
}

/* Run a fresh model of these parts to steady state with `method`; return
 * its slopes (caller frees) and, optionally, the run result. */
static double *steady_slopes(const parts *p, double U, int method, dfle_run_result *res_out)
{
    dfle_model_opts mo;
    dfle_model *m;
    dfle_run_opts ro;
    dfle_run_result res;
    dfle_error err;
    dfle_model_opts_default(&mo);
    mo.channel = p->ch, mo.fluvial = p->fl, mo.router = p->rt, mo.law = p->law, mo.U = U;
    assert_ok(dfle_model_new(&mo, &m, &err), &err);
    dfle_run_opts_default(&ro);
    ro.method = method;
    assert_ok(dfle_solver_run(m, &ro, &res, &err), &err);
    if (!res.converged || res.fallback)
        print_message("method %s: reason %s, ratio %g, note %s\n", dfle_method_name(method),
                      dfle_stop_reason_name(res.reason), res.rate_ratio, res.note);
    assert_true(res.converged);
    assert_int_equal(res.fallback, 0);
    size_t n = dfle_model_size(m);
    double *S = malloc(n * sizeof *S);
    memcpy(S, dfle_model_field(m, DFLE_FIELD_S, &err), n * sizeof *S);
    if (res_out != NULL)
        *res_out = res;
    dfle_model_free(m);
    return S;
}

/* Every method's slopes within rel of the explicit ones at every node,
 * and the Eq. (2) fits within 1 %. */
static void methods_agree(const parts *p, double U, double rel)
{
    size_t n = dfle_channel_size(p->ch);
    double *ref = steady_slopes(p, U, DFLE_METHOD_EXPLICIT, NULL);
    dfle_eq2_fit fref, f;
    const double *A = dfle_channel_A(p->ch);
    int have_fit = dfle_slope_area_fit(n - 1, A, ref, 100, NULL, &fref, NULL) == DFLE_OK;
    for (int method = DFLE_METHOD_IMPLICIT; method <= DFLE_METHOD_DIRECT; method++) {
        double *S = steady_slopes(p, U, method, NULL);
        for (size_t i = 0; i + 1 < n; i++)
            assert_close(S[i], ref[i], rel, 0);
        if (have_fit) {
            assert_ok(dfle_slope_area_fit(n - 1, A, S, 100, NULL, &f, &(dfle_error){0}),
                      &(dfle_error){0});
            assert_close(f.S_df, fref.S_df, 0.01, 0);
            assert_close(f.A_df, fref.A_df, 0.01, 0);
        }
        free(S);
    }
    free(ref);
}

/* Fig. 9: Table G1 fluvial law, the empirical router and Eq. (6) with
 * alpha = 6, beta = 1, on a 5 m grid. */
static void make_fig9(parts *p)
{
    dfle_empirical_opts eo;
    make_channel(p, 5.0);
    make_fluvial(p);
    dfle_empirical_opts_default(&eo);
    assert_int_equal(dfle_router_new_empirical(&eo, &p->rt, NULL), DFLE_OK);
    make_law(p, 1e-4, 6, 1);
}

static void fig9_defaults(void **state)
{
    parts p = {0};
    (void)state;
    make_fig9(&p);
    methods_agree(&p, 5e-4, 5e-3);
    parts_free(&p);
}

/* Corners of Tables G3 and G5 (empirical router). */
static void table_g3_g5_sample(void **state)
{
    const struct { double M0, gamma, mu, tau_y, alpha, beta, k_df, U; } set[] = {
        {500, 0.0, 100, 100, 2, 0.5, 8e-5, 5e-4},    /* G3, low corner   */
        {3000, 1.0, 500, 600, 8, 3, 2e-4, 5e-4},     /* G3, high corner  */
        {1000, 0.3, 1000, 600, 6, 1, 5e-5, 1e-4},    /* G5 */
        {5000, 0.8, 100, 100, 6, 1, 1e-3, 1e-3},     /* G5 */
    };
    (void)state;
    for (size_t k = 0; k < sizeof set / sizeof set[0]; k++) {
        parts p = {0};
        dfle_empirical_opts eo;
        make_channel(&p, 10.0);
        make_fluvial(&p);
        dfle_empirical_opts_default(&eo);
        eo.M0 = set[k].M0, eo.gamma = set[k].gamma, eo.mu = set[k].mu, eo.tau_y = set[k].tau_y;
        assert_int_equal(dfle_router_new_empirical(&eo, &p.rt, NULL), DFLE_OK);
        make_law(&p, set[k].k_df, set[k].alpha, set[k].beta);
        methods_agree(&p, set[k].U, 5e-3);
        parts_free(&p);
    }
}

/* Fig. 6 defaults.  The explicit reference re-routes only when a slope
 * has moved by reroute_dS; at the paper's 0.05 that lag alone shifts its
 * steady state by ~1 %, so the comparison uses a tight 0.002. */
static void fig6_defaults(void **state)
{
    parts p = {0};
    dfle_process_opts po;
    (void)state;
    make_channel(&p, 10.0);
    make_fluvial(&p);
    dfle_process_opts_default(&po);
    po.reroute_dS = 0.002;
    assert_int_equal(dfle_router_new_process(&po, &p.rt, NULL), DFLE_OK);
    make_law(&p, 1e-4, 6, 1);
    methods_agree(&p, 5e-4, 5e-3);
    parts_free(&p);
}

/* The implicit and direct steady states against a known S(A). */
static void matches_known_slopes(const parts *p, double (*known)(const void *, double),
                                 const void *ctx)
{
    for (int method = DFLE_METHOD_IMPLICIT; method <= DFLE_METHOD_DIRECT; method++) {
        double *S = steady_slopes(p, 5e-4, method, NULL);
        for (size_t i = 0; i + 1 < dfle_channel_size(p->ch); i++)
            assert_close(S[i], known(ctx, dfle_channel_A(p->ch)[i]), 5e-3, 0);
        free(S);
    }
}

static double eq26(const void *fl, double A) { return dfle_fluvial_steady_slope(fl, 5e-4, A); }
static double eq19(const void *ap, double A) { return dfle_analytical_slope(ap, A); }

static void analytical_steady_states(void **state)
{
    parts p = {0};
    dfle_empirical_opts eo;
    const dfle_analytical_params ap = {
        .U = 5e-4, .k_df = 1e-4, .alpha = 6, .beta = 1, .M0 = 3000, .gamma = 0.5,
        .mu = 500, .c1 = 0.135, .c2 = 0.78, .rho_b = 1800, .g = 9.81, .k_w = 0.05, .b = 0.3,
    };
    (void)state;
    make_channel(&p, 5.0);
    make_fluvial(&p);
    matches_known_slopes(&p, eq26, p.fl); /* fluvial only: Eq. (26) */
    dfle_fluvial_free(p.fl);
    p.fl = NULL;
    dfle_empirical_opts_default(&eo);
    eo.tau_y = 0;
    assert_int_equal(dfle_router_new_empirical(&eo, &p.rt, NULL), DFLE_OK);
    make_law(&p, 1e-4, 6, 1);
    matches_known_slopes(&p, eq19, &ap); /* debris flows only, tau_y = 0: Eq. (19) */
    parts_free(&p);
}

/* Hard cases for the node solver: n_s < 1, a large alpha. */
static void awkward_exponents(void **state)
{
    parts p = {0};
    dfle_empirical_opts eo;
    (void)state;
    make_channel(&p, 10.0);
    assert_int_equal(dfle_fluvial_new_stream_power(2e-4, 0.35, 0.6, &p.fl, NULL), DFLE_OK);
    dfle_empirical_opts_default(&eo);
    assert_int_equal(dfle_router_new_empirical(&eo, &p.rt, NULL), DFLE_OK);
    make_law(&p, 1e-4, 12, 0.5);
    methods_agree(&p, 5e-4, 5e-3);
    parts_free(&p);
}

/* After an uplift step the implicit run follows the explicit solution:
 * against an explicit run at a tenth of the usual Courant number (the
 * reference), implicit with rtol = 1e-3 is at least as close as the
 * explicit run at the default Courant number, and within 1 % of the
 * profile's change. */
static void uplift_step_transient(void **state)
{
    parts p = {0};
    dfle_empirical_opts eo;
    const double times[] = {5e3, 2e4, 6e4};
    double *zr[3];
    (void)state;
    make_channel(&p, 10.0);
    make_fluvial(&p);
    dfle_empirical_opts_default(&eo);
    assert_int_equal(dfle_router_new_empirical(&eo, &p.rt, NULL), DFLE_OK);
    make_law(&p, 1e-4, 6, 1);
    size_t n = dfle_channel_size(p.ch);
    double z0[202];
    assert_int_equal(n, 202);
    for (int k = 0; k < 3; k++) {
        dfle_model_opts mo;
        dfle_model *m;
        dfle_run_opts ro;
        dfle_run_result res;
        dfle_error err;
        dfle_model_opts_default(&mo);
        mo.channel = p.ch, mo.fluvial = p.fl, mo.router = p.rt, mo.law = p.law;
        if (k == 2)
            mo.cfl = 0.05; /* the reference */
        assert_ok(dfle_model_new(&mo, &m, &err), &err);
        dfle_run_opts_default(&ro);
        ro.method = DFLE_METHOD_DIRECT;
        assert_ok(dfle_solver_run(m, &ro, &res, &err), &err);
        memcpy(z0, dfle_model_field(m, DFLE_FIELD_Z, &err), n * sizeof *z0);
        assert_ok(dfle_model_set_U(m, 1e-3, &err), &err);
        zr[k] = malloc(3 * n * sizeof *zr[k]);
        dfle_run_opts_default(&ro);
        ro.tol = 0;
        ro.max_time = 6e4;
        ro.method = k == 1 ? DFLE_METHOD_IMPLICIT : DFLE_METHOD_EXPLICIT;
        ro.n_record = 3;
        ro.record_times = times;
        ro.record_z = zr[k];
        assert_ok(dfle_solver_run(m, &ro, &res, &err), &err);
        assert_int_equal(res.n_recorded, 3);
        dfle_model_free(m);
    }
    for (int j = 0; j < 3; j++) {
        double change = 0, e_expl = 0, e_impl = 0;
        for (size_t i = 0; i < n; i++) {
            const double ref = zr[2][j * n + i];
            change = fmax(change, fabs(ref - z0[i]));
            e_expl = fmax(e_expl, fabs(zr[0][j * n + i] - ref));
            e_impl = fmax(e_impl, fabs(zr[1][j * n + i] - ref));
        }
        print_message("uplift step, t = %g yr: profile moved up to %.3g m; error against the "
                      "reference: explicit %.3g m, implicit %.3g m\n", times[j], change, e_expl,
                      e_impl);
        assert_true(change > 1.0);
        assert_true(e_impl <= 0.01 * change);
        assert_true(e_impl <= e_expl);
    }
    for (int k = 0; k < 3; k++)
        free(zr[k]);
    parts_free(&p);
}

/* Fluvial erosion off and a flow that stops half way: below it nothing
 * erodes, so no steady state exists.  The direct method must say so and
 * hand over to time stepping, which then runs out of time. */
static void direct_falls_back_and_says_why(void **state)
{
    parts p = {0};
    dfle_empirical_opts eo;
    dfle_model_opts mo;
    dfle_model *m;
    dfle_run_opts ro;
    dfle_run_result res;
    dfle_error err;
    (void)state;
    make_channel(&p, 10.0);
    dfle_empirical_opts_default(&eo);
    eo.tau_y = 3000; /* stops early */
    assert_int_equal(dfle_router_new_empirical(&eo, &p.rt, NULL), DFLE_OK);
    make_law(&p, 1e-4, 6, 1);
    dfle_model_opts_default(&mo);
    mo.channel = p.ch, mo.router = p.rt, mo.law = p.law;
    assert_ok(dfle_model_new(&mo, &m, &err), &err);
    dfle_run_opts_default(&ro);
    ro.method = DFLE_METHOD_DIRECT;
    ro.max_time = 1e4;
    assert_ok(dfle_solver_run(m, &ro, &res, &err), &err);
    assert_true(res.fallback);
    assert_int_equal(res.method, DFLE_METHOD_IMPLICIT);
    assert_false(res.converged);
    assert_int_equal(res.reason, DFLE_STOP_TIME);
    assert_msg_contains(res.note, "direct:");
    assert_msg_contains(res.note, "continued by implicit stepping");
    dfle_model_free(m);
    parts_free(&p);
}

static void records_land_on_their_times(void **state)
{
    parts p = {0};
    dfle_model_opts mo;
    dfle_model *a, *b;
    dfle_run_opts ro;
    dfle_run_result res;
    dfle_error err;
    const double times[] = {0.0, 1234.5};
    double rec[2 * 202];
    (void)state;
    make_channel(&p, 10.0);
    make_fluvial(&p);
    dfle_model_opts_default(&mo);
    mo.channel = p.ch, mo.fluvial = p.fl, mo.U = 2e-3;
    assert_ok(dfle_model_new(&mo, &a, &err), &err);
    assert_ok(dfle_model_new(&mo, &b, &err), &err);
    assert_ok(dfle_model_set_U(a, 5e-4, &err), &err);
    assert_ok(dfle_model_set_U(b, 5e-4, &err), &err);
    dfle_run_opts_default(&ro);
    ro.tol = 0;
    ro.max_time = 3000;
    ro.n_record = 2, ro.record_times = times, ro.record_z = rec;
    assert_ok(dfle_solver_run(a, &ro, &res, &err), &err);
    assert_int_equal(res.n_recorded, 2);
    dfle_run_opts_default(&ro);
    ro.tol = 0;
    ro.max_time = 1234.5;
    assert_ok(dfle_solver_run(b, &ro, &res, &err), &err);
    const double *z = dfle_model_field(b, DFLE_FIELD_Z, &err);
    for (size_t i = 0; i < 202; i++)
        assert_close(rec[202 + i], z[i], 1e-9, 1e-9);
    /* Record times must increase within the run. */
    const double bad[] = {10.0, 5.0};
    ro.n_record = 2, ro.record_times = bad, ro.record_z = rec;
    assert_int_equal(dfle_solver_run(b, &ro, &res, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "record times");
    ro.n_record = 0;
    ro.method = DFLE_METHOD_DIRECT;
    assert_int_equal(dfle_solver_run(b, &ro, &res, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "steady states only");
    dfle_model_free(a);
    dfle_model_free(b);
    parts_free(&p);
}

/* One steady state of p by `method`, into S (n values); returns the
 * one-node erosions per solved node it took. */
static double solve_counted(const parts *p, dfle_law *law, double U, int method, double *S)
{
    dfle_model_opts mo;
    dfle_model *m;
    dfle_run_opts ro;
    dfle_run_result res;
    dfle_error err;
    size_t n;
    double per_node;
    dfle_model_opts_default(&mo);
    mo.channel = p->ch, mo.fluvial = p->fl, mo.router = p->rt, mo.law = law, mo.U = U;
    assert_ok(dfle_model_new(&mo, &m, &err), &err);
    n = dfle_model_size(m);
    dfle_run_opts_default(&ro);
    ro.method = method;
    assert_ok(dfle_solver_run(m, &ro, &res, &err), &err);
    assert_true(res.converged && !res.fallback);
    memcpy(S, dfle_model_field(m, DFLE_FIELD_S, &err), n * sizeof *S);
    per_node = (double)dfle_model_node_evaluations(m) / (double)(n - 1);
    dfle_model_free(m);
    return per_node;
}

/* The Newton path (the law's rate_dlnS and the router's node_flow_dlnS)
 * and the difference path (the same law without the op) solve the same
 * equations: the direct steady states agree to the tolerance of the
 * difference path (1e-10 relative in S; Newton's own error is below
 * 1e-12), the implicit ones to what 1e-10 per step leaves after the
 * steps; the Newton path takes at most `bound` one-node erosions per
 * node of a direct steady state. */
static void paths_agree(const parts *p, double U, double bound)
{
    const size_t n = dfle_channel_size(p->ch);
    dfle_law_ops ops;
    dfle_law *plain = dfle_test_without_rate_dlnS(p->law, &ops);
    double *S = malloc(2 * n * sizeof *S), *S0 = S + n, per[2], d = 0;
    for (int method = DFLE_METHOD_IMPLICIT; method <= DFLE_METHOD_DIRECT; method++) {
        per[0] = solve_counted(p, p->law, U, method, S);
        per[1] = solve_counted(p, plain, U, method, S0);
        d = 0;
        for (size_t i = 0; i + 1 < n; i++) {
            d = fmax(d, fabs(S[i] / S0[i] - 1));
            assert_close(S[i], S0[i], method == DFLE_METHOD_DIRECT ? 2e-10 : 1e-8, 0);
        }
        print_message("%s: slopes within %.2g; one-node erosions per node %.2f (Newton) "
                      "against %.2f\n", dfle_method_name(method), d, per[0], per[1]);
        assert_true(per[0] <= per[1]); /* equal when no step was needed */
        if (method == DFLE_METHOD_DIRECT)
            assert_true(per[0] < per[1] && per[0] <= bound);
    }
    free(S);
    dfle_law_free(plain);
}

static void newton_and_difference_paths_agree(void **state)
{
    parts p = {0};
    dfle_empirical_opts eo;
    dfle_inertial_law_opts io;
    dfle_excess_stress_law_opts xo;
    (void)state;
    /* Fig. 9 (the bound is the figure make bench reports: 2.15). */
    make_fig9(&p);
    paths_agree(&p, 5e-4, 2.3);
    /* Stock and Dietrich's law: E_df jumps to 0 where the flow stops. */
    dfle_law_free(p.law);
    dfle_inertial_law_opts_default(&io);
    io.k = 3e-7, io.alpha = 1.5; /* as in examples/custom_laws.lua */
    assert_int_equal(dfle_law_new_inertial(&io, &p.law, NULL), DFLE_OK);
    paths_agree(&p, 5e-4, 3.0);
    /* A threshold law on tau (as in examples/custom_laws.lua). */
    dfle_law_free(p.law);
    dfle_excess_stress_law_opts_default(&xo);
    xo.k = 2e-9, xo.tau_c = 400, xo.p = 1.5;
    assert_int_equal(dfle_law_new_excess_stress(&xo, &p.law, NULL), DFLE_OK);
    paths_agree(&p, 5e-4, 3.0);
    parts_free(&p);
    /* Debris flows alone with tau_y = 0 (Eq. 19: ln E linear in ln S). */
    make_channel(&p, 10.0);
    dfle_empirical_opts_default(&eo);
    eo.tau_y = 0;
    assert_int_equal(dfle_router_new_empirical(&eo, &p.rt, NULL), DFLE_OK);
    make_law(&p, 1e-4, 6, 1);
    paths_agree(&p, 5e-4, 2.3);
    parts_free(&p);
    /* n_s < 1 and alpha = 12; and the high corner of Table G3. */
    make_channel(&p, 10.0);
    assert_int_equal(dfle_fluvial_new_stream_power(2e-4, 0.35, 0.6, &p.fl, NULL), DFLE_OK);
    dfle_empirical_opts_default(&eo);
    assert_int_equal(dfle_router_new_empirical(&eo, &p.rt, NULL), DFLE_OK);
    make_law(&p, 1e-4, 12, 0.5);
    paths_agree(&p, 5e-4, 3.0);
    dfle_fluvial_free(p.fl);
    make_fluvial(&p);
    dfle_router_free(p.rt);
    eo.M0 = 3000, eo.gamma = 1.0, eo.mu = 500, eo.tau_y = 600;
    assert_int_equal(dfle_router_new_empirical(&eo, &p.rt, NULL), DFLE_OK);
    dfle_law_free(p.law);
    make_law(&p, 2e-4, 8, 3);
    paths_agree(&p, 5e-4, 3.0);
    parts_free(&p);
}

/* A derivative op that is broken: NaN or infinite (unusable), or wrong
 * but positive (the law's part negated, or left out: the model still
 * adds the fluvial law's n_s E_f), by bad_kind. */
static int bad_kind;
static int bad_rate_dlnS(void *state, const dfle_law_ctx *ctx, const double *F, const double *E,
                         const dfle_flow_dlnS *d, double *dE, dfle_error *err)
{
    static const double factor[] = {NAN, INFINITY, -1.0, 0.0};
    (void)state, (void)F, (void)d, (void)err;
    for (size_t i = 0; i < ctx->n; i++)
        dE[i] = factor[bad_kind] * E[i];
    return DFLE_OK;
}

/* Newton's safeguards: with a derivative that is unusable at every slope
 * each node solve falls back to doubling and bisection; with one that is
 * wrong, the check against the secant of the values stops it from
 * accepting a slope on the derivative's word.  Either way the solve
 * finds the root the values-only path finds (to that path's tolerance),
 * in a bounded number of evaluations. */
static void newton_survives_a_bad_derivative(void **state)
{
    parts p = {0};
    dfle_law_ops plain_ops, bad_ops;
    dfle_law *plain, *bad;
    size_t n;
    double *S, *S0;
    (void)state;
    make_fig9(&p);
    n = dfle_channel_size(p.ch);
    S = malloc(2 * n * sizeof *S), S0 = S + n;
    plain = dfle_test_without_rate_dlnS(p.law, &plain_ops);
    bad_ops = plain_ops;
    bad_ops.rate_dlnS = bad_rate_dlnS;
    assert_int_equal(dfle_law_new(&bad_ops, dfle_law_state(p.law), &bad, NULL), DFLE_OK);
    (void)solve_counted(&p, plain, 5e-4, DFLE_METHOD_DIRECT, S0);
    for (bad_kind = 0; bad_kind < 4; bad_kind++) {
        double per = solve_counted(&p, bad, 5e-4, DFLE_METHOD_DIRECT, S);
        for (size_t i = 0; i + 1 < n; i++)
            assert_close(S[i], S0[i], 2e-10, 0);
        print_message("bad derivative %d: %.1f one-node erosions per node\n", bad_kind, per);
        /* Bisection of a bracket found by doubling takes tens of
         * evaluations per node, far below the 200 a solve may take; a
         * wrong derivative still speeds the solve up now and then. */
        assert_true(per < 60);
        if (bad_kind < 2)
            assert_true(per > 6.61);
    }
    dfle_law_free(bad);
    dfle_law_free(plain);
    free(S);
    parts_free(&p);
}

/* --- The stepping loop (solver.h) with a stepper of its own: y' = -y,
 * steps of at most 0.3, steady when y < y_stop. */
typedef struct decay {
    double y, y_stop, t;
    int records[8];
    double record_t[8];
    size_t after;
    volatile sig_atomic_t *flag; /* raised at step raise_at */
    size_t raise_at;
} decay;

static int decay_prepare(void *self, const dfle_stepping_tally *so_far, int *steady,
                         dfle_error *err)
{
    decay *d = self;
    (void)so_far;
    (void)err;
    *steady = d->y < d->y_stop;
    return DFLE_OK;
}

static int decay_advance(void *self, double limit, double *dt, dfle_error *err)
{
    decay *d = self;
    (void)err;
    *dt = limit < 0.3 ? limit : 0.3;
    d->y *= exp(-*dt);
    d->t += *dt;
    return DFLE_OK;
}

static int decay_record(void *self, size_t k, double t, dfle_error *err)
{
    decay *d = self;
    (void)err;
    d->records[k]++;
    d->record_t[k] = t;
    return DFLE_OK;
}

static int decay_after(void *self, const dfle_stepping_tally *so_far, double dt, dfle_error *err)
{
    decay *d = self;
    (void)dt;
    d->after++;
    if (d->flag != NULL && so_far->steps == d->raise_at)
        *d->flag = 1;
    if (so_far->steps == 1000)
        return dfle_error_set(err, DFLE_ECANCELED, "stop");
    return DFLE_OK;
}

static const dfle_stepping_ops decay_ops = {1, "decay", decay_prepare, decay_advance,
                                            decay_record, decay_after};

static void stepping_loop_stops_and_lands(void **state)
{
    const double times[3] = {0.0, 0.5, 1.0};
    volatile sig_atomic_t flag = 0;
    dfle_stepping_limits lim = {2.0, 100, NULL, 3, times};
    dfle_stepping_tally t;
    dfle_error err;
    decay d = {1.0, 0.0, 0.0, {0}, {0}, 0, NULL, 0};
    (void)state;
    /* time: steps land on 0.5, 1.0 and the end 2.0 exactly */
    assert_ok(dfle_stepping_loop(&decay_ops, &d, &lim, &t, &err), &err);
    assert_int_equal(t.reason, DFLE_STOP_TIME);
    assert_close(t.time, 2.0, 1e-15, 0);
    assert_close(d.y, exp(-2.0), 1e-14, 0);
    assert_int_equal(t.n_recorded, 3);
    for (int k = 0; k < 3; k++) {
        assert_int_equal(d.records[k], 1);
        assert_close(d.record_t[k], times[k], 1e-15, 0);
    }
    /* 0.3, 0.2 (to 0.5), 0.3, 0.2 (to 1.0), 0.3 x 3, 0.1 */
    assert_int_equal(t.steps, 8);
    assert_int_equal(d.after, 8);
    assert_close(t.dt_max, 0.3, 1e-15, 0);
    assert_close(t.dt_min, 0.1, 1e-12, 0);
    /* steady: stops before the step that would have come */
    d = (decay){1.0, 0.5, 0.0, {0}, {0}, 0, NULL, 0};
    lim.n_record = 0;
    assert_ok(dfle_stepping_loop(&decay_ops, &d, &lim, &t, &err), &err);
    assert_int_equal(t.reason, DFLE_STOP_STEADY);
    assert_int_equal(t.steps, 3); /* e^-0.9 < 0.5 < e^-0.6 */
    /* steps, then the interrupt */
    d = (decay){1.0, 0.0, 0.0, {0}, {0}, 0, NULL, 0};
    lim.max_steps = 2;
    assert_ok(dfle_stepping_loop(&decay_ops, &d, &lim, &t, &err), &err);
    assert_int_equal(t.reason, DFLE_STOP_STEPS);
    assert_int_equal(t.steps, 2);
    d = (decay){1.0, 0.0, 0.0, {0}, {0}, 0, &flag, 4};
    lim.max_steps = 100;
    lim.interrupt = &flag;
    assert_ok(dfle_stepping_loop(&decay_ops, &d, &lim, &t, &err), &err);
    assert_int_equal(t.reason, DFLE_STOP_INTERRUPTED);
    assert_int_equal(t.steps, 4);
    /* a callback's error ends the loop with it */
    d = (decay){1.0, 0.0, 0.0, {0}, {0}, 0, NULL, 0};
    lim = (dfle_stepping_limits){1e6, 100000, NULL, 0, NULL};
    assert_int_equal(dfle_stepping_loop(&decay_ops, &d, &lim, &t, &err), DFLE_ECANCELED);
    assert_string_equal(err.msg, "stop");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(fig9_defaults),
        cmocka_unit_test(table_g3_g5_sample),
        cmocka_unit_test(fig6_defaults),
        cmocka_unit_test(analytical_steady_states),
        cmocka_unit_test(awkward_exponents),
        cmocka_unit_test(uplift_step_transient),
        cmocka_unit_test(direct_falls_back_and_says_why),
        cmocka_unit_test(records_land_on_their_times),
        cmocka_unit_test(newton_and_difference_paths_agree),
        cmocka_unit_test(newton_survives_a_bad_derivative),
        cmocka_unit_test(stepping_loop_stops_and_lands),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
