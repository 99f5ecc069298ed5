/*
 * router_process.c - the process-based debris-flow router (Sect. 2.2,
 * Appendix E), behind the same dfle_router_ops as the empirical one.
 *
 * A routing builds a flow1d grid of n_ghost + n cells (ghosts first),
 * places the pile, and steps the two-phase equations until the flow has
 * left or come to rest (router_process.h states the criterion), summing
 * the erosion law's integrand over the flow's own time steps (Eq. 11).
 * Routing costs thousands of flow steps, so the router remembers the
 * slopes it last routed over and asks to be routed again only when one
 * has moved by reroute_dS (0.05 in the paper).
 */
#include "dfle/router_process.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_SNAPSHOTS 1000
#define MAX_GHOSTS 10000

/* Nothing here depends on which model routes: the slopes a routing was
 * made for are the model's to keep (router.h), so one router serves any
 * number of models.  The report describes this router's last routing,
 * whoever asked for it. */
typedef struct process {
    dfle_process_opts opts;
    /* Report of the last routing and its arrays (n_alloc nodes). */
    dfle_process_report report;
    size_t n_alloc, snap_alloc;
    double *arrival;
    double *cos_theta; /* cos(atan(S)) per node, set when the flow first erodes there */
    /* Snapshot request and results. */
    size_t n_snap;
    double *snap_times, *snap_t, *snap_h;
} process;

void dfle_process_opts_default(dfle_process_opts *o)
{
    dfle_flow1d_params_default(&o->flow);
    o->M0 = 200.0;
    o->n_ghost = 20;
    o->reroute_dS = 0.05;
    o->q_erode = 0.01;
    o->q_rest = 1e-3;
    o->volume_tol = 1e-4;
    o->t_max = 3600.0;
    o->max_steps = 1e6;
    o->frequency_scaling = 0;
    o->gamma = 0.0;
}

const char *dfle_process_end_name(int end)
{
    switch (end) {
    case DFLE_PROCESS_LEFT: return "left";
    case DFLE_PROCESS_REST: return "rest";
    case DFLE_PROCESS_TIME: return "time";
    default: return "unknown";
    }
}

/* Make room for n-node results (arrival times, snapshots). */
static int process_reserve(process *pr, size_t n, dfle_error *err)
{
    if (pr->n_alloc == n && pr->snap_alloc == pr->n_snap && pr->arrival != NULL)
        return DFLE_OK;
    free(pr->arrival);
    free(pr->cos_theta);
    free(pr->snap_h);
    pr->report.routed = 0; /* the report's arrays go */
    pr->arrival = calloc(n, sizeof *pr->arrival);
    pr->cos_theta = calloc(n, sizeof *pr->cos_theta);
    pr->snap_h = calloc(pr->n_snap * n + 1, sizeof *pr->snap_h);
    pr->n_alloc = pr->snap_alloc = 0;
    if (pr->arrival == NULL || pr->cos_theta == NULL || pr->snap_h == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "router.process: out of memory for %zu nodes", n);
    pr->n_alloc = n;
    pr->snap_alloc = pr->n_snap;
    return DFLE_OK;
}

static void record_snapshots(process *pr, size_t *next, double t, const double *h, size_t n)
{
    while (*next < pr->n_snap && t >= pr->snap_times[*next]) {
        pr->snap_t[*next] = t;
        memcpy(pr->snap_h + *next * n, h, n * sizeof *h);
        (*next)++;
    }
}

static int process_route(void *state, const dfle_network *net, const double *S, dfle_flow *flow,
                         dfle_error *err)
{
    process *pr = state;
    const dfle_process_opts *o = &pr->opts;
    const size_t n = dfle_network_size(net), G = (size_t)o->n_ghost, N = G + n;
    const double dx = dfle_network_length(net)[0];
    const double *w = dfle_network_w(net), *A = dfle_network_A(net);
    double *cw = NULL, *cS = NULL, *pile, released, out_total = 0.0, t = 0.0, t_entry = -1.0;
    const double *h, *q, *face_vol;
    double phi_max;
    dfle_flow1d *f = NULL;
    size_t steps = 0, next_snap = 0, cell_steps = 0;
    int st, end, moved = 0;

    /* Two-phase flow down one channel: the equations are 1D. */
    if (!dfle_network_is_chain(net) || !dfle_network_uniform_length(net))
        return dfle_error_set(err, DFLE_EINVAL,
                              "router.process: routes down a single channel of even spacing (a 1D "
                              "model); for a network or a landscape use router.empirical");
    if (flow->integrand == NULL)
        return dfle_error_set(err, DFLE_EINVAL,
                              "router.process: the erosion law has no Eq. (11) integrand, so it "
                              "cannot be used with a time-resolved router");
    if (flow->n != n)
        return dfle_error_set(err, DFLE_EINVAL, "router.process: flow has %zu nodes, network %zu",
                              flow->n, n);
    if ((st = process_reserve(pr, n, err)) != DFLE_OK)
        return st;
    cw = malloc(N * sizeof *cw);
    cS = malloc(N * sizeof *cS);
    if (cw == NULL || cS == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "router.process: out of memory");
        goto done;
    }
    /* Ghost cells extend the head: its width, its slope. */
    for (size_t k = 0; k < N; k++) {
        cw[k] = k < G ? w[0] : w[k - G];
        cS[k] = k < G ? S[0] : S[k - G];
    }
    if ((st = dfle_flow1d_new(N, dx, cw, cS, &o->flow, &f, err)) != DFLE_OK)
        goto done;
    pile = dfle_flow1d_h(f);
    for (size_t k = 0; k < G; k++)
        pile[k] = o->M0 / ((double)G * dx * w[0]); /* a static pile of volume M0 */
    released = dfle_flow1d_volume(f, 0, N);
    h = dfle_flow1d_depth(f);
    q = dfle_flow1d_discharge(f);
    face_vol = dfle_flow1d_face_volumes(f);
    phi_max = dfle_flow1d_phi_max(f);

    dfle_flow_clear(flow);
    flow->time_resolved = 1;
    for (size_t i = 0; i < n; i++)
        pr->arrival[i] = NAN;
    for (size_t j = 0; j < pr->n_snap; j++)
        pr->snap_t[j] = NAN;
    record_snapshots(pr, &next_snap, 0.0, h + G, n);

    /* The loop's constants and record arrays as locals: the records'
     * stores cannot then be taken to change them, so they stay in
     * registers. */
    const double q_erode = o->q_erode, rho = o->flow.rho, grav = o->flow.g;
    double *const rec_h = flow->h, *const rec_M = flow->M, *const rec_tau = flow->tau,
                 *const rec_integral = flow->integral, *const rec_t_p = flow->t_p,
                 *const rec_v = flow->v, *const rec_Q = flow->Q, *const arrival = pr->arrival,
                 *const cos_theta = pr->cos_theta;
    for (;;) {
        double dt = dfle_flow1d_stable_dt(f), outflow, left, qmax = 0.0, L;
        size_t k0, k1;
        if (isinf(dt)) { /* everything dry: nothing left to move */
            end = DFLE_PROCESS_LEFT;
            break;
        }
        if (dt > o->t_max - t)
            dt = o->t_max - t;
        if ((double)steps >= o->max_steps) {
            st = dfle_error_set(err, DFLE_ENUMERIC,
                                "router.process: the flow needed more than max_steps = %.0f time "
                                "steps (stopped at t = %g s of t_max = %g s, step %g s, cfl = %g); "
                                "raise cfl or max_steps",
                                o->max_steps, t, o->t_max, dt, o->flow.cfl);
            goto done;
        }
        if ((st = dfle_flow1d_step(f, dt, t_entry < 0 ? -1.0 : t - t_entry, &outflow, err)) != DFLE_OK)
            goto done;
        t += dt;
        steps++;
        out_total += outflow;
        /* The flow enters the domain when it first crosses the head. */
        if (t_entry < 0 && face_vol[G] > 0)
            t_entry = t;
        /* Only the cells the step worked on: outside its window the depth,
         * discharge and face volumes are exactly 0, which would add
         * nothing to any record below. */
        dfle_flow1d_window(f, &k0, &k1);
        cell_steps += k1 - k0;
        L = dfle_flow1d_pore_length(f, t_entry < 0 ? -1.0 : t - t_entry);
        for (size_t k = k0 > G ? k0 : G; k < k1; k++) {
            const size_t i = k - G;
            const double hk = h[k], qk = fabs(q[k]);
            if (qk > qmax)
                qmax = qk;
            if (hk > rec_h[i])
                rec_h[i] = hk;
            rec_M[i] += face_vol[k + 1];
            if (qk > q_erode) { /* Phi = 1 */
                const double v = qk / hk;
                const double lam = dfle_flow1d_lambda_at(f, hk, L);
                double tau, g;
                if (isnan(arrival[i])) { /* first erosion here */
                    arrival[i] = t;
                    cos_theta[i] = cos(atan(S[i]));
                }
                /* The peak Coulomb stress (1 - lambda) rho g_z h phi: phi
                 * (a division and a root) only when its bound could beat
                 * the peak so far. */
                tau = (1.0 - lam) * rho * grav * cos_theta[i] * hk * phi_max;
                if (tau > rec_tau[i])
                    tau = (1.0 - lam) * rho * grav * cos_theta[i] * hk *
                          dfle_flow1d_phi(f, k, hk, v);
                if ((st = flow->integrand(flow->integrand_state, hk, v, lam, &g, err)) != DFLE_OK)
                    goto done;
                rec_integral[i] += g * dt;
                rec_t_p[i] += dt;
                if (v > rec_v[i])
                    rec_v[i] = v;
                if (qk * w[i] > rec_Q[i])
                    rec_Q[i] = qk * w[i];
                if (tau > rec_tau[i])
                    rec_tau[i] = tau;
            }
        }
        for (size_t k = k0; k < k1 && k < G; k++)
            if (fabs(q[k]) > qmax)
                qmax = fabs(q[k]);
        record_snapshots(pr, &next_snap, t, h + G, n);
        left = dfle_flow1d_volume(f, 0, N);
        if (!isfinite(left) || !isfinite(qmax)) {
            st = dfle_error_set(err, DFLE_ENUMERIC,
                                "router.process: the flow became non-finite at t = %g s", t);
            goto done;
        }
        if (left <= o->volume_tol * released) {
            end = DFLE_PROCESS_LEFT;
            break;
        }
        /* At rest: held still by friction (q = 0 everywhere), or moving
         * once and slow everywhere now.  A pile only just released is
         * slow too, because it has not had time to accelerate: after a
         * first step of 1e-8 s (a tiny cfl) it must not count as at rest. */
        moved = moved || qmax > o->q_rest;
        if (qmax == 0.0 || (moved && qmax <= o->q_rest)) {
            end = DFLE_PROCESS_REST;
            break;
        }
        if (t >= o->t_max) {
            end = DFLE_PROCESS_TIME;
            break;
        }
    }

    /* Results: reach, threshold factor, Appendix D scaling. */
    flow->runout_end = 0;
    for (size_t i = 0; i < n; i++) {
        if (flow->t_p[i] > 0) {
            flow->runout_end = i + 1;
            flow->Theta[i] = 1.0;
        }
        if (o->frequency_scaling)
            flow->integral[i] *= 1000.0 * pow(1e-6 * A[i], o->gamma) / o->M0;
    }
    /* The one flow reaches the channel down to its furthest wet node. */
    for (size_t i = 0; i < n; i++)
        flow->reach[i] = i < flow->runout_end;
    pr->report = (dfle_process_report){
        .routed = 1, .end = end, .volume_in = released, .volume_out = out_total,
        .volume_left = dfle_flow1d_volume(f, 0, N), .duration = t, .steps = steps,
        .cell_steps = cell_steps, .n = n,
        .arrival = pr->arrival, .n_snapshots = pr->n_snap, .snapshot_t = pr->snap_t,
        .snapshot_h = pr->snap_h,
    };
    st = DFLE_OK;
done:
    dfle_flow1d_free(f);
    free(cw);
    free(cS);
    return st;
}

static int process_needs_reroute(void *state, size_t n, const double *S_routed,
                                 const double *S, int *reroute, dfle_error *err)
{
    const process *pr = state;
    (void)err;
    *reroute = 0;
    for (size_t i = 0; i < n; i++)
        if (fabs(S[i] - S_routed[i]) >= pr->opts.reroute_dS) {
            *reroute = 1;
            break;
        }
    return DFLE_OK;
}

static size_t process_params(const void *state, dfle_param *out, size_t cap)
{
    const dfle_process_opts *o = &((const process *)state)->opts;
    /* Named as in dfle.router.process{...}. */
    const dfle_param p[] = {
        {"M0", o->M0, "m^3", 0},          {"eta", o->flow.eta, "Pa s", 0},
        {"mu2", o->flow.mu_2, "", 0},     {"mu_s", o->flow.mu_s, "", 0},
        {"I0", o->flow.I0, "", 0},        {"D", o->flow.D, "m^2/s", 0},
        {"D_eff", o->flow.D_eff, "m", 0}, {"lambda0", o->flow.lambda0, "", 0},
        {"v_f", o->flow.v_f, "", 0},      {"rho_b", o->flow.rho, "kg/m^3", 0},
        {"rho_s", o->flow.rho_s, "kg/m^3", 0}, {"g", o->flow.g, "m/s^2", 0},
        {"cfl", o->flow.cfl, "", 0},      {"h_dry", o->flow.h_dry, "m", 0},
        {"n_ghost", o->n_ghost, "", 0},   {"reroute_dS", o->reroute_dS, "", 0},
        {"q_erode", o->q_erode, "m^2/s", 0}, {"q_rest", o->q_rest, "m^2/s", 0},
        {"volume_tol", o->volume_tol, "", 0}, {"t_max", o->t_max, "s", 0},
        {"max_steps", o->max_steps, "", 0},
        {"gamma", o->gamma, "", 0},       {"frequency_scaling", o->frequency_scaling, "", 1},
    };
    return dfle_param_copy(p, sizeof p / sizeof p[0], out, cap);
}

static void process_destroy(void *state)
{
    process *pr = state;
    if (pr == NULL)
        return;
    free(pr->arrival);
    free(pr->cos_theta);
    free(pr->snap_times);
    free(pr->snap_t);
    free(pr->snap_h);
    free(pr);
}

static const dfle_router_ops process_ops = {
    .version = DFLE_ROUTER_OPS_VERSION,
    .name = "process",
    .route = process_route,
    .needs_reroute = process_needs_reroute,
    .params = process_params,
    .destroy = process_destroy,
};

int dfle_router_new_process(const dfle_process_opts *o, dfle_router **out, dfle_error *err)
{
    process *pr;
    int st;

    *out = NULL;
    if ((st = dfle_flow1d_params_check(&o->flow, "router.process", err)) != DFLE_OK)
        return st;
    const struct { const char *name; double v; int zero_ok; } pos[] = {
        {"M0", o->M0, 0},           {"reroute_dS", o->reroute_dS, 0},
        {"q_erode", o->q_erode, 1}, {"q_rest", o->q_rest, 1},
        {"volume_tol", o->volume_tol, 1}, {"t_max", o->t_max, 0},
        {"max_steps", o->max_steps, 0},
        {"gamma", o->gamma, 1},
    };
    for (size_t i = 0; i < sizeof pos / sizeof pos[0]; i++)
        if (!(isfinite(pos[i].v) && (pos[i].zero_ok ? pos[i].v >= 0 : pos[i].v > 0)))
            return dfle_error_set(err, DFLE_EINVAL, "router.process: %s must be %s 0 (got %g)",
                                  pos[i].name, pos[i].zero_ok ? ">=" : ">", pos[i].v);
    if (o->n_ghost < 1 || o->n_ghost > MAX_GHOSTS)
        return dfle_error_set(err, DFLE_EINVAL, "router.process: n_ghost must be in [1, %d] (got %d)",
                              MAX_GHOSTS, o->n_ghost);
    pr = calloc(1, sizeof *pr);
    if (pr == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "router.process: out of memory");
    pr->opts = *o;
    pr->opts.flow.outlet_wall = 0; /* the outlet is open */
    return dfle_router_new(&process_ops, pr, out, err);
}

const dfle_process_opts *dfle_router_process_opts(const dfle_router *rt)
{
    if (rt == NULL || dfle_router_get_ops(rt) != &process_ops)
        return NULL;
    return &((const process *)dfle_router_state(rt))->opts;
}

const dfle_process_report *dfle_router_process_report(const dfle_router *rt)
{
    if (rt == NULL || dfle_router_get_ops(rt) != &process_ops)
        return NULL;
    return &((const process *)dfle_router_state(rt))->report;
}

int dfle_router_process_set_snapshots(dfle_router *rt, size_t k, const double *times,
                                      dfle_error *err)
{
    process *pr;
    double *nt = NULL, *ns = NULL;

    if (rt == NULL || dfle_router_get_ops(rt) != &process_ops)
        return dfle_error_set(err, DFLE_EINVAL, "router: snapshots need a process-based router");
    /* The running routing writes into the snapshot arrays. */
    if (dfle_router_is_routing(rt))
        return dfle_error_set(err, DFLE_ECALLBACK, "router.process: snapshots cannot change "
                              "while it is routing (from inside the erosion law's integrand)");
    pr = dfle_router_state(rt);
    if (k > MAX_SNAPSHOTS)
        return dfle_error_set(err, DFLE_EINVAL, "router.process: at most %d snapshots (got %zu)",
                              MAX_SNAPSHOTS, k);
    for (size_t j = 0; j < k; j++)
        if (!(isfinite(times[j]) && times[j] >= 0 && (j == 0 || times[j] > times[j - 1])))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "router.process: snapshot times must be finite, >= 0 s and "
                                  "increasing (time %zu is %g)", j + 1, times[j]);
    if (k > 0) {
        nt = malloc(k * sizeof *nt);
        ns = malloc(k * sizeof *ns);
        if (nt == NULL || ns == NULL) {
            free(nt);
            free(ns);
            return dfle_error_set(err, DFLE_ENOMEM, "router.process: out of memory");
        }
        memcpy(nt, times, k * sizeof *nt);
    }
    free(pr->snap_times);
    free(pr->snap_t);
    pr->snap_times = nt;
    pr->snap_t = ns;
    pr->n_snap = k;
    pr->report.routed = 0; /* the next routing resizes the snapshot store */
    return DFLE_OK;
}
