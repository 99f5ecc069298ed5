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
#include "routers/router_process_internal.h"

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
    /* On a network: each head's last routing (router_process_network.c). */
    process_network *net;
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
    o->reroute_dw = 0.1;
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

static int process_route(void *state, const dfle_network *net, const double *S, dfle_flow *flow,
                         dfle_error *err)
{
    process *pr = state;
    const dfle_process_opts *o = &pr->opts;
    const size_t n = dfle_network_size(net);
    process_path_result r;
    int st;

    if (flow->integrand == NULL)
        return dfle_error_set(err, DFLE_EINVAL,
                              "router.process: the erosion law has no Eq. (11) integrand, so it "
                              "cannot be used with a time-resolved router");
    if (flow->n != n)
        return dfle_error_set(err, DFLE_EINVAL, "router.process: flow has %zu nodes, network %zu",
                              flow->n, n);
    if (!dfle_network_is_chain(net) || !dfle_network_uniform_length(net)) {
        /* A network: every head's flow down its own path of receivers. */
        if (pr->n_snap > 0)
            return dfle_error_set(err, DFLE_EINVAL,
                                  "router.process: depth snapshots are taken on a single channel "
                                  "(this is a network of %zu nodes)", n);
        pr->report.routed = 0;
        if ((st = dfle_process_route_network(&pr->net, o, net, S, flow, &pr->report, err)) !=
            DFLE_OK)
            return st;
        pr->report.routed = 1;
        return DFLE_OK;
    }
    if ((st = process_reserve(pr, n, err)) != DFLE_OK)
        return st;
    {
        const process_path path = {.n = n, .dx = NULL, .dx0 = dfle_network_length(net)[0],
                                   .w = dfle_network_w(net), .S = S, .A = dfle_network_A(net)};
        const process_snaps snaps = {.n_snap = pr->n_snap, .times = pr->snap_times,
                                     .t = pr->snap_t, .h = pr->snap_h};
        if ((st = dfle_process_route_path(o, &path, flow, pr->arrival, pr->cos_theta, &snaps, &r,
                                          err)) != DFLE_OK)
            return st;
    }
    pr->report = (dfle_process_report){
        .routed = 1, .end = r.end, .volume_in = r.volume_in, .volume_out = r.volume_out,
        .volume_left = r.volume_left, .duration = r.duration, .steps = r.steps,
        .cell_steps = r.cell_steps, .n = n,
        .arrival = pr->arrival, .n_snapshots = pr->n_snap, .snapshot_t = pr->snap_t,
        .snapshot_h = pr->snap_h, .heads = 1, .heads_routed = 1,
        .head_routings = pr->report.head_routings + 1,
        .route_calls = pr->report.route_calls + 1,
        .volume_error = fabs(r.volume_in - r.volume_out - r.volume_left) / r.volume_in,
    };
    return DFLE_OK;
}

static int process_needs_reroute(void *state, size_t n, const double *S_routed,
                                 const double *S, int *reroute, dfle_error *err)
{
    const process *pr = state;
    (void)err;
    *reroute = 0;
    /* On a network the routing itself decides, head by head, against
     * each head's own last routing: a slope that moved since the caller's
     * last routing says nothing about a head routed before that. */
    if (pr->report.routed && pr->report.heads_network) {
        *reroute = 1;
        return DFLE_OK;
    }
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
        {"reroute_dw", o->reroute_dw, "", 0},
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
    dfle_process_network_free(pr->net);
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
        {"max_steps", o->max_steps, 0}, {"reroute_dw", o->reroute_dw, 0},
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
