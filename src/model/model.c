/*
 * model.c - the channel-profile model: Eq. (3), dz/dt = U - E_f - E_df,
 * stepped explicitly (forward Euler) as in McGuire et al. (2023).
 *
 * One landscape step:
 *   1. slopes from elevations (downstream difference; outlet fixed);
 *   2. fluvial erosion per node;
 *   3. route the debris flow (every step for a local router such as the
 *      empirical one, only when the router asks otherwise), evaluate the
 *      law's flow factor after each routing and its rate every step;
 *   4. dz/dt, a NaN/Inf check, the steady-state check;
 *   5. a CFL-limited time step and the Euler update.
 *
 * Why the CFL condition has this form: erosion depends on the slope to
 * the downstream node, so a perturbation travels upstream like a
 * kinematic wave with speed c = dE/dS [m/yr].  Forward Euler with an
 * upwind difference is stable while c dt / dx <= 1.  dE/dS
 * is exact for the fluvial power law and a one-sided finite difference
 * for the debris-flow part, which works for any router and law behind
 * the ops tables (a Lua law included) without asking them for
 * derivatives.
 */
#include "dfle/model.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/flow.h"
#include "model/model_internal.h"

/* Relative slope perturbation of the finite-difference dE/dS: large
 * enough to stay clear of round-off in E, small enough to be local. */
#define CELERITY_EPS 1e-6
/* Steps between progress reports. */
#define PROGRESS_EVERY 256

void dfle_model_opts_default(dfle_model_opts *o)
{
    memset(o, 0, sizeof *o);
    o->U = 5e-4;
    o->cfl = 0.5;
    o->dt_max = 1000.0;
}

void dfle_run_opts_default(dfle_run_opts *o)
{
    memset(o, 0, sizeof *o);
    o->max_time = 2e7;
    o->tol = 1e-3;
    o->max_steps = 10000000u;
    o->method = DFLE_METHOD_EXPLICIT;
    o->rtol = 1e-3;
    o->direct_tol = 2e-3;
}

static const struct {
    const char *name, *unit;
} field_info[DFLE_FIELD_COUNT] = {
    [DFLE_FIELD_X] = {"x", "m"},           [DFLE_FIELD_A] = {"A", "m^2"},
    [DFLE_FIELD_W] = {"w", "m"},           [DFLE_FIELD_Z] = {"z", "m"},
    [DFLE_FIELD_S] = {"S", "-"},           [DFLE_FIELD_E_F] = {"E_f", "m/yr"},
    [DFLE_FIELD_E_DF] = {"E_df", "m/yr"},  [DFLE_FIELD_DZDT] = {"dzdt", "m/yr"},
    [DFLE_FIELD_M] = {"M", "m^3"},         [DFLE_FIELD_Q] = {"Q", "m^3/s"},
    [DFLE_FIELD_H] = {"h", "m"},           [DFLE_FIELD_V] = {"v", "m/s"},
    [DFLE_FIELD_T_P] = {"t_p", "s"},       [DFLE_FIELD_TAU] = {"tau", "Pa"},
    [DFLE_FIELD_THETA] = {"Theta", "-"},
};

int dfle_field_lookup(const char *name)
{
    for (int f = 0; f < DFLE_FIELD_COUNT; f++)
        if (strcmp(name, field_info[f].name) == 0)
            return f;
    return -1;
}

const char *dfle_field_name(int f)
{
    return f >= 0 && f < DFLE_FIELD_COUNT ? field_info[f].name : NULL;
}

const char *dfle_field_unit(int f)
{
    return f >= 0 && f < DFLE_FIELD_COUNT ? field_info[f].unit : NULL;
}

const char *dfle_stop_reason_name(int reason)
{
    switch (reason) {
    case DFLE_STOP_STEADY: return "steady";
    case DFLE_STOP_TIME: return "time";
    case DFLE_STOP_STEPS: return "steps";
    default: return "unknown";
    }
}

enum { MODEL_ARRAYS = 13 };

static int model_alloc(dfle_model *m, dfle_error *err)
{
    size_t n = m->n;
    double *block = calloc(MODEL_ARRAYS * n, sizeof *block);
    int st;

    if (block == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "model: out of memory for %zu nodes", n);
    m->z = block;
    m->S = block + n;
    m->E_f = block + 2 * n;
    m->E_df = block + 3 * n;
    m->dzdt = block + 4 * n;
    m->F = block + 5 * n;
    m->KAm = block + 6 * n;
    m->S_pert = block + 7 * n;
    m->E_pert = block + 8 * n;
    m->F_pert = block + 9 * n;
    m->celerity = block + 10 * n;
    m->z_save = block + 11 * n;
    m->z_work = block + 12 * n;
    m->node.n = 1;
    m->node.M = m->node_block;
    m->node.Q = m->node_block + 1;
    m->node.h = m->node_block + 2;
    m->node.v = m->node_block + 3;
    m->node.t_p = m->node_block + 4;
    m->node.tau = m->node_block + 5;
    m->node.Theta = m->node_block + 6;
    m->node.integral = m->node_block + 7;
    st = dfle_flow_init(&m->flow, n, err);
    if (st == DFLE_OK)
        st = dfle_flow_init(&m->flow_pert, n, err);
    return st;
}

void dfle_model_free(dfle_model *m)
{
    if (m == NULL)
        return;
    dfle_flow_release(&m->flow);
    dfle_flow_release(&m->flow_pert);
    free(m->z); /* the block starts at z */
    free(m);
}

int dfle_model_new(const dfle_model_opts *o, dfle_model **out, dfle_error *err)
{
    dfle_model *m;
    int st;

    *out = NULL;
    if (o->channel == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "model: channel is required");
    if (o->router != NULL && o->law == NULL)
        return dfle_error_set(err, DFLE_EINVAL,
                              "model: a debris-flow router needs an erosion law (law)");
    if (!(isfinite(o->U) && o->U > 0))
        return dfle_error_set(err, DFLE_EINVAL, "model: U must be > 0 m/yr (got %g)", o->U);
    if (!(isfinite(o->cfl) && o->cfl > 0 && o->cfl <= 1))
        return dfle_error_set(err, DFLE_EINVAL, "model: cfl must be in (0, 1] (got %g)", o->cfl);
    if (!(isfinite(o->dt_max) && o->dt_max > 0))
        return dfle_error_set(err, DFLE_EINVAL, "model: dt_max must be > 0 yr (got %g)",
                              o->dt_max);

    m = calloc(1, sizeof *m);
    if (m == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "model: out of memory");
    m->ch = o->channel;
    m->fl = o->fluvial;
    m->rt = o->router;
    m->law = o->router != NULL ? o->law : NULL;
    m->U = o->U;
    m->cfl = o->cfl;
    m->dt_max = o->dt_max;
    m->n = dfle_channel_size(o->channel);
    m->dx = dfle_channel_dx(o->channel);
    st = model_alloc(m, err);
    if (st == DFLE_OK && m->fl != NULL) {
        /* K A^m is fixed per node: hoist its pow() out of the step loop. */
        const double *A = dfle_channel_A(m->ch);
        for (size_t i = 0; i < m->n; i++)
            m->KAm[i] = dfle_fluvial_K(m->fl) * pow(A[i], dfle_fluvial_m(m->fl));
    }
    if (st == DFLE_OK)
        st = dfle_model_init_fluvial_steady(m, NULL, err);
    if (st != DFLE_OK) {
        dfle_model_free(m);
        return st;
    }
    *out = m;
    return DFLE_OK;
}

size_t dfle_model_size(const dfle_model *m) { return m->n; }
double dfle_model_time(const dfle_model *m) { return m->time; }
double dfle_model_U(const dfle_model *m) { return m->U; }
const dfle_channel *dfle_model_channel(const dfle_model *m) { return m->ch; }
const dfle_fluvial *dfle_model_fluvial(const dfle_model *m) { return m->fl; }
dfle_router *dfle_model_router(const dfle_model *m) { return m->rt; }
dfle_law *dfle_model_law(const dfle_model *m) { return m->law; }

int dfle_model_set_U(dfle_model *m, double U, dfle_error *err)
{
    if (!(isfinite(U) && U > 0))
        return dfle_error_set(err, DFLE_EINVAL, "model: U must be > 0 m/yr (got %g)", U);
    m->U = U;
    m->evaluated = 0;
    return DFLE_OK;
}

static void invalidate(dfle_model *m)
{
    m->evaluated = 0;
    m->flow_valid = 0;
}

int dfle_model_init_fluvial_steady(dfle_model *m, const dfle_fluvial *fl,
                                   dfle_error *err)
{
    dfle_fluvial *own = NULL;
    const double *A = dfle_channel_A(m->ch);
    int st;

    if (fl == NULL)
        fl = m->fl;
    if (fl == NULL || !(dfle_fluvial_K(fl) > 0)) {
        /* The paper's runs all start from Eq. (26) with the Table G1 law,
         * including those that switch fluvial erosion off. */
        dfle_stochastic_threshold_opts o;
        dfle_stochastic_threshold_opts_default(&o);
        st = dfle_fluvial_new_stochastic_threshold(&o, &own, err);
        if (st != DFLE_OK)
            return st;
        fl = own;
    }
    m->z[m->n - 1] = 0.0;
    for (size_t i = m->n - 1; i-- > 0;)
        m->z[i] = m->z[i + 1] + m->dx * dfle_fluvial_steady_slope(fl, m->U, A[i]);
    dfle_fluvial_free(own);
    invalidate(m);
    return DFLE_OK;
}

void dfle_mi_touch(dfle_model *m)
{
    m->evaluated = 0;
}

void dfle_model_invalidate_flow(dfle_model *m)
{
    invalidate(m);
}

int dfle_model_set_z(dfle_model *m, const double *z, size_t n, dfle_error *err)
{
    if (n != m->n)
        return dfle_error_set(err, DFLE_EINVAL, "model: z has %zu values, the channel %zu nodes",
                              n, m->n);
    for (size_t i = 0; i < n; i++)
        if (!isfinite(z[i]))
            return dfle_error_set(err, DFLE_EINVAL, "model: z at node %zu is not finite (%g)",
                                  i + 1, z[i]);
    memcpy(m->z, z, n * sizeof *z);
    invalidate(m);
    return DFLE_OK;
}

/* Debris-flow erosion for slopes S into E; routes into `flow` when asked
 * (route != 0), otherwise reuses the flow factor F. */
static int debris_flow_erosion(dfle_model *m, const double *S, dfle_flow *flow,
                               double *F, double *E, int route, dfle_error *err)
{
    dfle_law_ctx ctx;
    int st;

    if (route) {
        /* Time-resolved routers sum the law's Eq. (11) integrand as they go. */
        flow->integrand = dfle_law_get_ops(m->law)->integrand;
        flow->integrand_state = dfle_law_state(m->law);
        st = dfle_router_route(m->rt, m->ch, S, flow, err);
        if (st != DFLE_OK)
            return st;
    }
    ctx.n = flow->runout_end;
    ctx.S = S;
    ctx.A = dfle_channel_A(m->ch);
    ctx.w = dfle_channel_w(m->ch);
    ctx.flow = flow;
    if (route) {
        st = dfle_law_flow_factor(m->law, &ctx, F, err);
        if (st != DFLE_OK)
            return st;
    }
    st = dfle_law_rate(m->law, &ctx, F, E, err);
    if (st != DFLE_OK)
        return st;
    for (size_t i = ctx.n; i < m->n; i++)
        E[i] = 0.0;
    return DFLE_OK;
}

/* Name the first non-finite value so the user can see where it began. */
static int report_nonfinite(const dfle_model *m, size_t i, dfle_error *err)
{
    const char *what = !isfinite(m->z[i])      ? "z"
                       : !isfinite(m->S[i])    ? "S"
                       : !isfinite(m->E_f[i])  ? "E_f"
                       : !isfinite(m->E_df[i]) ? "E_df"
                                               : "dz/dt";
    return dfle_error_set(err, DFLE_ENUMERIC,
                          "model: %s is not finite at node %zu (x = %g m) at t = %g yr "
                          "(z = %g m, S = %g, E_f = %g, E_df = %g m/yr)",
                          what, i + 1, dfle_channel_x(m->ch)[i], m->time, m->z[i], m->S[i],
                          m->E_f[i], m->E_df[i]);
}

/* Bring every field up to date with z. */
int dfle_mi_evaluate(dfle_model *m, dfle_error *err)
{
    const size_t n = m->n;
    const double inv_dx = 1.0 / m->dx;
    size_t nonpositive = 0;
    int st;

    for (size_t i = 0; i + 1 < n; i++) {
        m->S[i] = (m->z[i] - m->z[i + 1]) * inv_dx;
        nonpositive += !(m->S[i] > 0);
    }
    m->S[n - 1] = m->S[n - 2];
    m->nonpositive = nonpositive;

    if (m->fl != NULL) {
        const double n_s = dfle_fluvial_n(m->fl);
        for (size_t i = 0; i < n; i++)
            m->E_f[i] = m->S[i] > 0 ? m->KAm[i] * pow(m->S[i], n_s) : 0.0;
    }
    if (m->rt != NULL) {
        int route = !m->flow_valid || dfle_router_needs_reroute(m->rt, n, m->S);
        st = debris_flow_erosion(m, m->S, &m->flow, m->F, m->E_df, route, err);
        if (st != DFLE_OK)
            return st;
        if (route) {
            m->routings++;
            m->flow_valid = 1;
        }
    }
    for (size_t i = 0; i + 1 < n; i++)
        m->dzdt[i] = m->U - m->E_f[i] - m->E_df[i];
    m->dzdt[n - 1] = 0.0;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(m->dzdt[i]) || !isfinite(m->E_f[i]) || !isfinite(m->E_df[i]))
            return report_nonfinite(m, i, err);
    m->evaluated = 1;
    return DFLE_OK;
}

/* Largest |dE/dS| over the evolving nodes [m/yr per unit slope]. */
static int max_celerity(dfle_model *m, double *c_max, dfle_error *err)
{
    const size_t n = m->n;
    double c = 0.0;

    for (size_t i = 0; i < n; i++)
        m->celerity[i] = 0.0;
    if (m->fl != NULL) {
        const double n_s = dfle_fluvial_n(m->fl);
        for (size_t i = 0; i + 1 < n; i++)
            if (m->S[i] > 0)
                m->celerity[i] = n_s * m->E_f[i] / m->S[i];
    }
    if (m->rt != NULL && m->flow.runout_end > 0) {
        int local = dfle_router_is_local(m->rt);
        size_t active;
        int st;

        for (size_t i = 0; i < n; i++)
            m->S_pert[i] = m->S[i] > 0 ? m->S[i] * (1.0 + CELERITY_EPS) : m->S[i];
        if (local) {
            st = debris_flow_erosion(m, m->S_pert, &m->flow_pert, m->F_pert, m->E_pert, 1, err);
        } else {
            /* The flow stays as routed; only the slope term moves. */
            st = debris_flow_erosion(m, m->S_pert, &m->flow, m->F, m->E_pert, 0, err);
        }
        if (st != DFLE_OK)
            return st;
        /* A node the perturbed flow newly reaches would show a jump, not
         * a derivative: use only nodes both flows reach. */
        active = m->flow.runout_end;
        if (local && m->flow_pert.runout_end < active)
            active = m->flow_pert.runout_end;
        if (active > n - 1)
            active = n - 1;
        for (size_t i = 0; i < active; i++)
            if (m->S[i] > 0)
                m->celerity[i] += fabs(m->E_pert[i] - m->E_df[i]) / (CELERITY_EPS * m->S[i]);
    }
    for (size_t i = 0; i + 1 < n; i++)
        if (m->celerity[i] > c)
            c = m->celerity[i];
    if (!isfinite(c))
        return dfle_error_set(err, DFLE_ENUMERIC,
                              "model: erosion rate has no finite slope derivative at t = %g yr",
                              m->time);
    *c_max = c;
    return DFLE_OK;
}

double dfle_mi_rate_ratio(const dfle_model *m)
{
    double r = 0.0;
    for (size_t i = 0; i + 1 < m->n; i++) {
        double a = fabs(m->dzdt[i]);
        if (a > r)
            r = a;
    }
    return r / m->U;
}

/* Rough completion estimate: the larger of the time used and how far the
 * rate ratio has fallen (on a log scale) from its start towards tol. */
double dfle_mi_progress_fraction(double t, double max_time, double r0, double r, double tol)
{
    double f = t / max_time;
    if (tol > 0 && r0 > tol && r > 0) {
        double fc = log(r0 / r) / log(r0 / tol);
        if (fc > f)
            f = fc;
    }
    return f < 0 ? 0 : f > 1 ? 1 : f;
}

/* Forward Euler with the CFL step (the paper's method). */
int dfle_mi_explicit_advance(dfle_model *m, double dt_limit, double *dt_taken, void *state,
                            dfle_error *err)
{
    double c = 0.0, dt;
    int st;
    (void)state;
    if ((st = max_celerity(m, &c, err)) != DFLE_OK)
        return st;
    dt = c > 0 ? m->cfl * m->dx / c : m->dt_max;
    if (dt > m->dt_max)
        dt = m->dt_max;
    if (dt > dt_limit)
        dt = dt_limit;
    for (size_t i = 0; i + 1 < m->n; i++)
        m->z[i] += dt * m->dzdt[i];
    m->evaluated = 0;
    *dt_taken = dt;
    return DFLE_OK;
}

/* Copy z for every record time reached at time t of the run. */
static void take_records(const dfle_model *m, const dfle_run_opts *o, double t,
                         dfle_run_result *res)
{
    while (res->n_recorded < o->n_record &&
           t >= o->record_times[res->n_recorded] * (1.0 - 1e-12)) {
        memcpy(o->record_z + res->n_recorded * m->n, m->z, m->n * sizeof *m->z);
        res->n_recorded++;
    }
}

/* Time-varying uplift U(t) (doc/laws.md): the run's uplift callback,
 * if any, sets U for the coming step, so forcing can change within a run
 * instead of only between runs (m:set_U). */
static int apply_uplift(dfle_model *m, const dfle_run_opts *o, dfle_error *err)
{
    double U = m->U;
    int st;
    if (o->uplift == NULL)
        return DFLE_OK;
    if ((st = o->uplift(o->uplift_ud, m->time, &U, err)) != DFLE_OK)
        return st;
    if (!(isfinite(U) && U > 0))
        return dfle_error_set(err, DFLE_EINVAL, "model: U(t) must be > 0 m/yr (got %g at t = %g yr)",
                              U, m->time);
    if (U != m->U) {
        m->U = U;
        m->evaluated = 0; /* dz/dt = U - E changes */
    }
    return DFLE_OK;
}

int dfle_mi_drive(dfle_model *m, const dfle_run_opts *o, dfle_mi_advance_fn advance,
                  void *state, dfle_run_result *res, dfle_error *err)
{
    double t = 0.0, r0 = -1.0;
    size_t steps = 0, routings0 = m->routings;
    int st;

    res->dt_min = INFINITY;
    res->dt_max = 0.0;
    take_records(m, o, 0.0, res);
    for (;;) {
        double r, dt, limit;

        if ((st = apply_uplift(m, o, err)) != DFLE_OK)
            return st;
        if (!m->evaluated && (st = dfle_mi_evaluate(m, err)) != DFLE_OK)
            return st;
        r = dfle_mi_rate_ratio(m);
        if (r0 < 0)
            r0 = r;
        res->nonpositive_slope_nodes += m->nonpositive;
        if (o->tol > 0 && r <= o->tol) {
            res->reason = DFLE_STOP_STEADY;
            break;
        }
        /* Tolerate round-off in the accumulated time. */
        if (t >= o->max_time * (1.0 - 1e-12)) {
            res->reason = DFLE_STOP_TIME;
            break;
        }
        if (steps >= o->max_steps) {
            res->reason = DFLE_STOP_STEPS;
            break;
        }
        /* Land exactly on the end of the run and on every record time. */
        limit = o->max_time - t;
        if (res->n_recorded < o->n_record && o->record_times[res->n_recorded] - t < limit)
            limit = o->record_times[res->n_recorded] - t;
        if ((st = advance(m, limit, &dt, state, err)) != DFLE_OK)
            return st;
        t += dt;
        m->time += dt;
        steps++;
        if (dt < res->dt_min)
            res->dt_min = dt;
        if (dt > res->dt_max)
            res->dt_max = dt;
        take_records(m, o, t, res);
        if (o->progress != NULL && steps % PROGRESS_EVERY == 0) {
            dfle_run_status s = {
                .time = t, .max_time = o->max_time, .steps = steps, .dt = dt,
                .rate_ratio = r, .tol = o->tol,
                .fraction = dfle_mi_progress_fraction(t, o->max_time, r0, r, o->tol),
            };
            if (o->progress(o->progress_ud, &s) != 0)
                return dfle_error_set(err, DFLE_ECANCELED,
                                      "model: run stopped by the progress callback at t = %g yr", t);
        }
    }
    res->converged = res->reason == DFLE_STOP_STEADY;
    res->time += t;
    res->steps += steps;
    res->routings += m->routings - routings0;
    res->rate_ratio = dfle_mi_rate_ratio(m);
    if (res->dt_min > res->dt_max)
        res->dt_min = 0.0;
    return DFLE_OK;
}

const char *dfle_method_name(int method)
{
    static const char *const names[] = {"explicit", "implicit", "direct", "auto"};
    return method >= 0 && method <= DFLE_METHOD_AUTO ? names[method] : "unknown";
}

int dfle_method_lookup(const char *name)
{
    for (int k = 0; k <= DFLE_METHOD_AUTO; k++)
        if (strcmp(name, dfle_method_name(k)) == 0)
            return k;
    return -1;
}

int dfle_model_run(dfle_model *m, const dfle_run_opts *o, dfle_run_result *res,
                   dfle_error *err)
{
    dfle_run_opts opts = *o;

    memset(res, 0, sizeof *res);
    if (!(isfinite(o->max_time) && o->max_time > 0))
        return dfle_error_set(err, DFLE_EINVAL, "model: max_time must be > 0 yr (got %g)",
                              o->max_time);
    if (!(isfinite(o->tol) && o->tol >= 0))
        return dfle_error_set(err, DFLE_EINVAL, "model: tol must be >= 0 (got %g)", o->tol);
    if (o->max_steps == 0)
        return dfle_error_set(err, DFLE_EINVAL, "model: max_steps must be > 0");
    if (!(isfinite(o->rtol) && o->rtol > 0 && o->rtol < 1))
        return dfle_error_set(err, DFLE_EINVAL, "model: rtol must be in (0, 1) (got %g)", o->rtol);
    if (!(isfinite(o->direct_tol) && o->direct_tol > 0 && o->direct_tol < 1))
        return dfle_error_set(err, DFLE_EINVAL, "model: direct_tol must be in (0, 1) (got %g)",
                              o->direct_tol);
    if (o->n_record > 0 && (o->record_times == NULL || o->record_z == NULL))
        return dfle_error_set(err, DFLE_EINVAL, "model: record times need a place to record");
    for (size_t k = 0; k < o->n_record; k++)
        if (!(isfinite(o->record_times[k]) && o->record_times[k] >= 0 &&
              o->record_times[k] <= o->max_time &&
              (k == 0 || o->record_times[k] > o->record_times[k - 1])))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "model: record times must increase within [0, max_time = %g yr] "
                                  "(time %zu is %g)", o->max_time, k + 1, o->record_times[k]);
    if (opts.method == DFLE_METHOD_AUTO)
        opts.method = o->tol > 0 ? DFLE_METHOD_DIRECT : DFLE_METHOD_EXPLICIT;
    res->method = opts.method;
    switch (opts.method) {
    case DFLE_METHOD_EXPLICIT:
        return dfle_mi_drive(m, &opts, dfle_mi_explicit_advance, NULL, res, err);
    case DFLE_METHOD_IMPLICIT:
        return dfle_mi_run_implicit(m, &opts, res, err);
    case DFLE_METHOD_DIRECT:
        if (!(o->tol > 0))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "model: the direct method finds steady states only (tol > 0)");
        if (o->n_record > 0)
            return dfle_error_set(err, DFLE_EINVAL,
                                  "model: the direct method has no time to record at");
        { /* with U(t): the steady state for U at the current time */
            int st = apply_uplift(m, o, err);
            if (st != DFLE_OK)
                return st;
        }
        return dfle_mi_run_direct(m, &opts, res, err);
    default:
        return dfle_error_set(err, DFLE_EINVAL, "model: unknown method %d", o->method);
    }
}

const double *dfle_model_field(dfle_model *m, int field, dfle_error *err)
{
    if (!m->evaluated && dfle_mi_evaluate(m, err) != DFLE_OK)
        return NULL;
    switch (field) {
    case DFLE_FIELD_X: return dfle_channel_x(m->ch);
    case DFLE_FIELD_A: return dfle_channel_A(m->ch);
    case DFLE_FIELD_W: return dfle_channel_w(m->ch);
    case DFLE_FIELD_Z: return m->z;
    case DFLE_FIELD_S: return m->S;
    case DFLE_FIELD_E_F: return m->E_f;
    case DFLE_FIELD_E_DF: return m->E_df;
    case DFLE_FIELD_DZDT: return m->dzdt;
    case DFLE_FIELD_M: return m->flow.M;
    case DFLE_FIELD_Q: return m->flow.Q;
    case DFLE_FIELD_H: return m->flow.h;
    case DFLE_FIELD_V: return m->flow.v;
    case DFLE_FIELD_T_P: return m->flow.t_p;
    case DFLE_FIELD_TAU: return m->flow.tau;
    case DFLE_FIELD_THETA: return m->flow.Theta;
    default:
        dfle_error_set(err, DFLE_EINVAL, "model: no field number %d", field);
        return NULL;
    }
}

int dfle_model_write_csv(dfle_model *m, const char *path, dfle_error *err)
{
    const double *col[DFLE_FIELD_COUNT];
    FILE *f;
    int bad;

    for (int k = 0; k < DFLE_FIELD_COUNT; k++)
        if ((col[k] = dfle_model_field(m, k, err)) == NULL)
            return err != NULL ? err->code : DFLE_ESTATE;
    f = fopen(path, "w");
    if (f == NULL)
        return dfle_error_set(err, DFLE_EIO, "model: cannot open '%s' for writing", path);
    for (int k = 0; k < DFLE_FIELD_COUNT; k++)
        fprintf(f, "%s%s (%s)", k ? "," : "", field_info[k].name, field_info[k].unit);
    fputc('\n', f);
    for (size_t i = 0; i < m->n; i++) {
        for (int k = 0; k < DFLE_FIELD_COUNT; k++)
            fprintf(f, "%s%.10g", k ? "," : "", col[k][i]);
        fputc('\n', f);
    }
    bad = ferror(f);
    if (fclose(f) != 0 || bad)
        return dfle_error_set(err, DFLE_EIO, "model: error writing '%s'", path);
    return DFLE_OK;
}
