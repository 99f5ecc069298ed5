/* test_model.c - Eq. (3) stepping: analytical steady states, the ops
 * contract (mock routers and laws), stopping rules, NaN detection. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dfle_test.h"
#include "dfle/analytical.h"
#include "dfle/law_power.h"
#include "dfle/model.h"
#include "dfle/record.h"
#include "dfle/solver.h"
#include "dfle/router_empirical.h"

/* A model on the default channel with whichever parts a test asks for. */
typedef struct rig {
    dfle_channel *ch;
    dfle_fluvial *fl;
    dfle_router *rt;
    dfle_law *law;
    dfle_model *m;
} rig;

static void rig_fluvial(rig *r)
{
    dfle_stochastic_threshold_opts so;
    dfle_stochastic_threshold_opts_default(&so);
    assert_int_equal(dfle_fluvial_new_stochastic_threshold(&so, &r->fl, NULL), DFLE_OK);
}

/* Empirical router (Fig. 9 defaults, given tau_y) and the power law. */
static void rig_debris_flows(rig *r, double tau_y)
{
    dfle_empirical_opts eo;
    dfle_power_law_opts po;
    dfle_empirical_opts_default(&eo);
    eo.tau_y = tau_y;
    dfle_power_law_opts_default(&po);
    assert_int_equal(dfle_router_new_empirical(&eo, &r->rt, NULL), DFLE_OK);
    assert_int_equal(dfle_law_new_power(&po, &r->law, NULL), DFLE_OK);
}

static void rig_build(rig *r, double U, double dt_max)
{
    dfle_channel_opts co;
    dfle_model_opts mo;
    dfle_error err;
    dfle_channel_opts_default(&co);
    assert_int_equal(dfle_channel_new(&co, &r->ch, NULL), DFLE_OK);
    dfle_model_opts_default(&mo);
    mo.channel = r->ch;
    mo.fluvial = r->fl;
    mo.router = r->rt;
    mo.law = r->law;
    mo.U = U;
    if (dt_max > 0)
        mo.dt_max = dt_max;
    assert_ok(dfle_model_new(&mo, &r->m, &err), &err);
}

static void rig_free(rig *r)
{
    dfle_model_free(r->m);
    dfle_law_free(r->law);
    dfle_router_free(r->rt);
    dfle_fluvial_free(r->fl);
    dfle_channel_free(r->ch);
    memset(r, 0, sizeof *r);
}

/* Run with the default options changed by tol (< 0: keep) and max_time. */
static int rig_run(rig *r, double tol, double max_time, dfle_run_result *res, dfle_error *err)
{
    dfle_run_opts ro;
    dfle_run_opts_default(&ro);
    if (tol >= 0)
        ro.tol = tol;
    if (max_time > 0)
        ro.max_time = max_time;
    return dfle_solver_run(r->m, &ro, res, err);
}

static void fluvial_only_converges_to_eq26(void **state)
{
    rig r = {0};
    dfle_run_result res;
    dfle_error err;
    (void)state;
    rig_fluvial(&r);
    rig_build(&r, 1.5e-3, 0); /* start from the steady state of three times the uplift */
    assert_ok(dfle_model_set_U(r.m, 5e-4, &err), &err);
    assert_ok(rig_run(&r, -1, 0, &res, &err), &err);
    assert_true(res.converged);
    assert_int_equal(res.reason, DFLE_STOP_STEADY);
    assert_true(res.rate_ratio <= 1e-3);
    const double *S = dfle_model_field(r.m, DFLE_FIELD_S, &err);
    const double *A = dfle_model_field(r.m, DFLE_FIELD_A, &err);
    for (size_t i = 0; i + 1 < dfle_model_size(r.m); i++)
        assert_close(S[i], dfle_fluvial_steady_slope(r.fl, 5e-4, A[i]), 5e-3, 0);
    rig_free(&r);
}

static void debris_flow_only_matches_eq19(void **state)
{
    rig r = {0};
    dfle_run_result res;
    dfle_error err;
    (void)state;
    rig_debris_flows(&r, 0.0); /* Theta = 1, runout to the outlet: Eq. (19)'s assumptions */
    rig_build(&r, 5e-4, 0);
    assert_ok(rig_run(&r, -1, 0, &res, &err), &err);
    assert_true(res.converged);
    assert_int_equal(res.routings, res.steps + 1); /* local router: every step */

    dfle_analytical_params p = {
        .U = 5e-4, .k_df = 1e-4, .alpha = 6, .beta = 1, .M0 = 3000, .gamma = 0.5,
        .mu = 500, .c1 = 0.135, .c2 = 0.78, .rho_b = 1800, .g = 9.81, .k_w = 0.05, .b = 0.3,
    };
    const double *S = dfle_model_field(r.m, DFLE_FIELD_S, &err);
    const double *A = dfle_model_field(r.m, DFLE_FIELD_A, &err);
    for (size_t i = 0; i + 1 < dfle_model_size(r.m); i++)
        assert_close(S[i], dfle_analytical_slope(&p, A[i]), 5e-3, 0);
    rig_free(&r);
}

static void steady_state_balances_uplift(void **state)
{
    rig r = {0};
    dfle_run_result res;
    dfle_error err;
    int df_seen = 0, fl_seen = 0;
    (void)state;
    rig_fluvial(&r);
    rig_debris_flows(&r, 300.0);
    rig_build(&r, 5e-4, 0);
    assert_ok(rig_run(&r, 1e-4, 0, &res, &err), &err);
    assert_true(res.converged);
    const double *Ef = dfle_model_field(r.m, DFLE_FIELD_E_F, &err);
    const double *Edf = dfle_model_field(r.m, DFLE_FIELD_E_DF, &err);
    const double *S = dfle_model_field(r.m, DFLE_FIELD_S, &err);
    for (size_t i = 0; i + 1 < dfle_model_size(r.m); i++) {
        assert_close(Ef[i] + Edf[i], 5e-4, 1e-4, 0);
        assert_true(S[i] > 0);
        df_seen |= Edf[i] > 0.9 * 5e-4;
        fl_seen |= Ef[i] > 0.9 * 5e-4;
    }
    /* Both processes dominate somewhere: debris flows at the head,
     * rivers at the outlet. */
    assert_true(df_seen && fl_seen);
    assert_true(Edf[0] > Ef[0]);
    rig_free(&r);
}

static void uplift_alone_raises_every_node_by_U_t(void **state)
{
    rig r = {0};
    dfle_run_result res;
    dfle_error err;
    (void)state;
    rig_build(&r, 5e-4, 300);
    double z0 = dfle_model_field(r.m, DFLE_FIELD_Z, &err)[10];
    assert_ok(rig_run(&r, 0, 1000, &res, &err), &err);
    assert_int_equal(res.reason, DFLE_STOP_TIME);
    assert_false(res.converged);
    assert_int_equal(res.steps, 4); /* 300 + 300 + 300 + 100 */
    assert_close(res.time, 1000, 1e-12, 0);
    const double *z = dfle_model_field(r.m, DFLE_FIELD_Z, &err);
    assert_close(z[10], z0 + 5e-4 * 1000, 1e-12, 0);
    assert_close(z[dfle_model_size(r.m) - 1], 0.0, 0, 0); /* base level fixed */
    assert_close(dfle_model_time(r.m), 1000, 1e-12, 0);
    rig_free(&r);
}
/* --- mocks through the ops tables -------------------------------------- */

typedef struct mock {
    int routes, factors, rates;
    int poison_after; /* rate() writes NaN at node 6 after this many calls */
    int huge_after;   /* rate() writes 1e308 at node 6 after this many calls */
} mock;

static int mock_route(void *s, const dfle_network *net, const double *S, dfle_flow *flow,
                      dfle_error *err)
{
    mock *mk = s;
    (void)S, (void)err;
    mk->routes++;
    for (size_t i = 0; i < dfle_network_size(net); i++) {
        flow->h[i] = 1.0;
        flow->t_p[i] = 1.0;
        flow->Theta[i] = 1.0;
        flow->reach[i] = 1.0;
    }
    flow->runout_end = dfle_network_size(net);
    return 0;
}

static int mock_never_again(void *s, size_t n, const double *S_routed, const double *S,
                            int *reroute, dfle_error *err)
{
    (void)s, (void)n, (void)S_routed, (void)S, (void)err;
    *reroute = 0;
    return 0;
}

static int mock_factor(void *s, const dfle_law_ctx *ctx, double *F, dfle_error *err)
{
    mock *mk = s;
    (void)err;
    mk->factors++;
    for (size_t i = 0; i < ctx->n; i++)
        F[i] = ctx->flow->h[i];
    return 0;
}

/* E = 1e-3 S^2 F: a debris-flow-like law with a known steady slope. */
static int mock_rate(void *s, const dfle_law_ctx *ctx, const double *F, double *E,
                     dfle_error *err)
{
    mock *mk = s;
    (void)err;
    mk->rates++;
    for (size_t i = 0; i < ctx->n; i++)
        E[i] = 1e-3 * ctx->S[i] * ctx->S[i] * F[i];
    if (mk->poison_after > 0 && mk->rates > mk->poison_after)
        E[6] = NAN;
    if (mk->huge_after > 0 && mk->rates > mk->huge_after)
        E[6] = 1e308;
    return 0;
}

static const dfle_router_ops cached_router_ops = {
    .version = DFLE_ROUTER_OPS_VERSION, .name = "mock-cached", .route = mock_route, .needs_reroute = mock_never_again};
static const dfle_law_ops mock_law_ops = {
    .version = DFLE_LAW_OPS_VERSION, .name = "mock", .flow_factor = mock_factor, .rate = mock_rate};

/* A router's table must say which version of router.h it was written for;
 * the handle owns the state even when it refuses the table. */
static int destroyed;
static void count_destroy(void *state)
{
    (void)state;
    destroyed++;
}

static void ops_tables_say_their_version(void **state)
{
    dfle_router_ops ops = cached_router_ops;
    dfle_router *rt = NULL;
    dfle_error err;
    (void)state;
    ops.version = 0;
    ops.destroy = count_destroy;
    destroyed = 0;
    assert_int_equal(dfle_router_new(&ops, NULL, &rt, &err), DFLE_EINVAL);
    assert_string_equal(err.msg, "router mock-cached: ops version 0, this library knows 1 to 2 "
                                 "(set .version = DFLE_ROUTER_OPS_VERSION)");
    assert_null(rt);
    assert_int_equal(destroyed, 1);
    ops.version = DFLE_ROUTER_OPS_VERSION;
    assert_int_equal(dfle_router_new(&ops, NULL, &rt, &err), DFLE_OK);
    dfle_router_free(rt);
    assert_int_equal(destroyed, 2);
}

static void rig_mocks(rig *r, mock *rk, mock *lk)
{
    assert_int_equal(dfle_router_new(&cached_router_ops, rk, &r->rt, NULL), DFLE_OK);
    assert_int_equal(dfle_law_new(&mock_law_ops, lk, &r->law, NULL), DFLE_OK);
    rig_build(r, 5e-4, 0);
}

static void non_local_router_is_routed_once_and_law_cached(void **state)
{
    rig r = {0};
    mock rk = {0}, lk = {0};
    dfle_run_result res;
    dfle_error err;
    (void)state;
    rig_mocks(&r, &rk, &lk);
    assert_ok(rig_run(&r, -1, 0, &res, &err), &err);
    assert_true(res.converged);
    assert_true(res.steps > 10);
    assert_int_equal(rk.routes, 1);
    assert_int_equal(res.routings, 1);
    assert_int_equal(lk.factors, 1);
    assert_true(lk.rates > (int)res.steps); /* every step, plus dE/dS */
    /* Steady state of U = 1e-3 S^2: S = sqrt(U / 1e-3) everywhere. */
    const double *S = dfle_model_field(r.m, DFLE_FIELD_S, &err);
    for (size_t i = 0; i + 1 < dfle_model_size(r.m); i++)
        assert_close(S[i], sqrt(0.5), 1e-3, 0);
    rig_free(&r);
}

/* Every rate finite, yet the step overflows z: a finite but absurd
 * erosion rate times the step is -inf, and the next evaluation must
 * name z, not pass the profile on (a NaN z reads as "no erosion"). */
static void overflowing_elevation_is_reported(void **state)
{
    rig r = {0};
    mock rk = {0}, lk = {.huge_after = 20};
    dfle_run_result res;
    dfle_error err;
    (void)state;
    rig_mocks(&r, &rk, &lk);
    assert_int_equal(rig_run(&r, -1, 0, &res, &err), DFLE_ENUMERIC);
    assert_msg_contains(err.msg, "is not finite at node");
    rig_free(&r);
}

/* No finite starting profile: (U/K)^(1/n_s) overflows for n_s = 0.0014. */
static void infinite_starting_profile_is_refused(void **state)
{
    dfle_channel_opts co;
    dfle_channel *ch;
    dfle_fluvial *fl;
    dfle_model_opts mo;
    dfle_model *m = NULL;
    dfle_error err;
    (void)state;
    dfle_channel_opts_default(&co);
    assert_int_equal(dfle_channel_new(&co, &ch, NULL), DFLE_OK);
    assert_int_equal(dfle_fluvial_new_stream_power(1e-5, 0.5, 0.0014, &fl, NULL), DFLE_OK);
    dfle_model_opts_default(&mo);
    mo.channel = ch;
    mo.fluvial = fl;
    assert_int_equal(dfle_model_new(&mo, &m, &err), DFLE_ENUMERIC);
    assert_null(m);
    assert_msg_contains(err.msg, "starting profile");
    assert_msg_contains(err.msg, "n_s = 0.0014");
    dfle_fluvial_free(fl);
    dfle_channel_free(ch);
}

static void nan_is_reported_with_node_and_time(void **state)
{
    rig r = {0};
    mock rk = {0}, lk = {.poison_after = 20};
    dfle_run_result res;
    dfle_error err;
    (void)state;
    rig_mocks(&r, &rk, &lk);
    assert_int_equal(rig_run(&r, -1, 0, &res, &err), DFLE_ENUMERIC);
    assert_msg_contains(err.msg, "E_df is not finite at node 7");
    assert_msg_contains(err.msg, "t = ");
    rig_free(&r);
}

static int cancel_at_once(void *ud, const dfle_run_status *st)
{
    int *calls = ud;
    (*calls)++;
    assert_true(st->fraction >= 0 && st->fraction <= 1);
    assert_true(st->steps > 0);
    return 1;
}

static void limits_and_cancellation(void **state)
{
    rig r = {0};
    dfle_run_opts ro;
    dfle_run_result res;
    dfle_error err;
    int calls = 0;
    (void)state;
    rig_fluvial(&r);
    rig_build(&r, 2e-3, 0);
    assert_ok(dfle_model_set_U(r.m, 5e-4, &err), &err);
    dfle_run_opts_default(&ro);
    ro.max_steps = 7;
    assert_ok(dfle_solver_run(r.m, &ro, &res, &err), &err);
    assert_int_equal(res.reason, DFLE_STOP_STEPS);
    assert_int_equal(res.steps, 7);
    assert_string_equal(dfle_stop_reason_name(res.reason), "steps");

    dfle_run_opts_default(&ro);
    ro.progress = cancel_at_once;
    ro.progress_ud = &calls;
    assert_int_equal(dfle_solver_run(r.m, &ro, &res, &err), DFLE_ECANCELED);
    assert_int_equal(calls, 1);

    ro.progress = NULL;
    ro.max_time = -1;
    assert_int_equal(dfle_solver_run(r.m, &ro, &res, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "max_time");
    rig_free(&r);
}

static void bad_options_are_named(void **state)
{
    rig r = {0};
    dfle_model_opts mo;
    dfle_model *m = NULL;
    dfle_error err;
    double z[3] = {1, 2, 3};
    (void)state;
    rig_debris_flows(&r, 300.0);
    rig_build(&r, 5e-4, 0);
    dfle_model_opts_default(&mo);
    assert_int_equal(dfle_model_new(&mo, &m, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "channel is required");
    mo.channel = r.ch;
    mo.U = 0;
    assert_int_equal(dfle_model_new(&mo, &m, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "U must be > 0");
    mo.U = 5e-4;
    mo.cfl = 1.5;
    assert_int_equal(dfle_model_new(&mo, &m, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "cfl");
    mo.cfl = 0.5;
    mo.router = r.rt; /* a router without a law */
    assert_int_equal(dfle_model_new(&mo, &m, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "needs an erosion law");
    assert_null(m);
    assert_int_equal(dfle_model_set_z(r.m, z, 3, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "z has 3 values");
    assert_int_equal(dfle_model_set_U(r.m, NAN, &err), DFLE_EINVAL);
    assert_null(dfle_model_field(r.m, 99, &err));
    rig_free(&r);
}
static void fields_and_csv(void **state)
{
    rig r = {0};
    dfle_model *m;
    dfle_error err;
    char path[] = "/tmp/dfle_test_csv_XXXXXX", line[512];
    int fd, lines = 0;
    FILE *f;
    (void)state;
    assert_int_equal(dfle_field_lookup("E_df"), DFLE_FIELD_E_DF);
    assert_int_equal(dfle_field_lookup("nope"), -1);
    assert_string_equal(dfle_field_unit(DFLE_FIELD_TAU), "Pa");
    rig_build(&r, 5e-4, 0);
    m = r.m;
    fd = mkstemp(path);
    assert_true(fd >= 0);
    assert_ok(dfle_model_write_csv(m, path, NULL, &err), &err);
    f = fopen(path, "r");
    assert_non_null(f);
    /* units above plain column names */
    assert_non_null(fgets(line, sizeof line, f));
    assert_msg_contains(line, "# units: x=m, A=m^2, w=m, z=m, S=-, E_f=m/yr");
    assert_msg_contains(line, "tau=Pa, Theta=-");
    assert_non_null(fgets(line, sizeof line, f));
    assert_string_equal(line, "x,A,w,z,S,E_f,E_df,dzdt,M,Q,h,v,t_p,tau,Theta\n");
    while (fgets(line, sizeof line, f) != NULL)
        lines++;
    fclose(f);
    assert_int_equal(lines, 403);
    remove(path);
    assert_int_equal(dfle_model_write_csv(m, "/nonexistent/dir/x.csv", NULL, &err), DFLE_EIO);
    assert_msg_contains(err.msg, "/nonexistent/dir/x.csv");
    rig_free(&r);
}

/* The model's own parameters: U as it is now, cfl, dt_max. */
static void params_are_U_cfl_dt_max(void **state)
{
    rig r = {0};
    dfle_param p[8];
    dfle_error err;
    (void)state;
    rig_build(&r, 5e-4, 0);
    assert_ok(dfle_model_set_U(r.m, 7e-4, &err), &err);
    assert_int_equal(dfle_model_params(r.m, p, 8), 3);
    assert_string_equal(p[0].name, "U");
    assert_close(p[0].value, 7e-4, 0, 0);
    assert_string_equal(p[0].unit, "m/yr");
    assert_string_equal(p[1].name, "cfl");
    assert_close(p[1].value, dfle_model_cfl(r.m), 0, 0);
    assert_string_equal(p[2].name, "dt_max");
    assert_close(p[2].value, dfle_model_dt_max(r.m), 0, 0);
    rig_free(&r);
}

/* The record of a model: each component with its kind and params, a
 * process that is off as "off", the model's own parameters and time. */
static void describe_lists_every_component(void **state)
{
    rig r = {0};
    dfle_record *rec;
    dfle_error err;
    char *text = NULL;
    size_t len = 0;
    FILE *fp;
    (void)state;
    rig_debris_flows(&r, 300);
    rig_build(&r, 5e-4, 0);
    assert_ok(dfle_record_new(&rec, &err), &err);
    dfle_model_describe(r.m, rec);
    assert_ok(dfle_record_status(rec, &err), &err);
    fp = open_memstream(&text, &len);
    assert_non_null(fp);
    dfle_record_write_comments(rec, fp);
    fclose(fp);
    assert_msg_contains(text, "# channel hack: dx=5 m, A0=1000 m^2,");
    assert_msg_contains(text, ", n=403, x_outlet=2010 m, A_head=1000 m^2,");
    assert_msg_contains(text, "\n# fluvial off\n");
    assert_msg_contains(text, "\n# router empirical: M0=3000 m^(3-2 gamma), gamma=0.5,");
    assert_msg_contains(text, "tau_y=300 Pa");
    assert_msg_contains(text, "\n# law power: k_df=0.0001, alpha=6, beta=1\n");
    assert_msg_contains(text, "\n# model: U=0.0005 m/yr, cfl=0.5, dt_max=1000 yr, time=0 yr\n");
    free(text);
    dfle_record_free(rec);
    rig_free(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(ops_tables_say_their_version),
        cmocka_unit_test(fluvial_only_converges_to_eq26),
        cmocka_unit_test(debris_flow_only_matches_eq19),
        cmocka_unit_test(steady_state_balances_uplift),
        cmocka_unit_test(uplift_alone_raises_every_node_by_U_t),
        cmocka_unit_test(non_local_router_is_routed_once_and_law_cached),
        cmocka_unit_test(nan_is_reported_with_node_and_time),
        cmocka_unit_test(overflowing_elevation_is_reported),
        cmocka_unit_test(infinite_starting_profile_is_refused),
        cmocka_unit_test(limits_and_cancellation),
        cmocka_unit_test(bad_options_are_named),
        cmocka_unit_test(fields_and_csv),
        cmocka_unit_test(params_are_U_cfl_dt_max),
        cmocka_unit_test(describe_lists_every_component),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
