/*
 * router_empirical.c - the empirical debris-flow router (Sect. 2.3).
 *
 * Flow properties come from Rickenmann's (1999) relations and the
 * volume-area scaling of Santi and Morandi (2013); runout ends at the
 * first node where the basal shear stress falls below the yield
 * strength (a Bingham-like stopping rule, Whipple and Dunne 1992).
 *
 * Everything that depends on drainage area alone (M, Q, t_p and the
 * constant part of h^3) is computed once per network shape and cached, because
 * the model routes this flow at every landscape step: only the slope
 * changes between calls.
 */
#include "dfle/router_empirical.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct empirical {
    dfle_empirical_opts opts;
    /* Cache of the area-only terms, valid for network `cached_id` at
     * shape `cached_for` (0 = none). */
    unsigned long long cached_for, cached_id;
    size_t n;
    double *M, *Q, *t_p;
    double *h3_coef; /* 3 mu Q / (rho_b g w): h^3 = h3_coef / S  [m^3] */
    double *ln_h3_3; /* ln(h3_coef) / 3: h = exp(ln_h3_3 - ln S / 3)      */
    /* The A and w each node's terms were made from (NaN: none): a new
     * shape of the same network recomputes only the nodes whose area or
     * width moved (on a landscape, the paths below changed receivers). */
    double *A_was, *w_was;
    /* The nodes a flow can reach (at or below a source), donors before
     * receivers: on a landscape the channel cells, so a routing walks
     * those and not the hillslopes. */
    size_t *order, n_order;
    unsigned char *mark;
    /* Nodes that could be reached in shape `dark_since` and cannot now,
     * so a flow clean for that shape needs only these zeroed; n_dark >
     * dark_cap: too many were listed, zero them all. */
    size_t *dark, n_dark, dark_cap;
    unsigned long long dark_since;
} empirical;

void dfle_empirical_opts_default(dfle_empirical_opts *o)
{
    o->M0 = 3000.0;
    o->gamma = 0.5;
    o->mu = 500.0;
    o->tau_y = 300.0;
    o->c1 = 0.135;
    o->c2 = 0.78;
    o->rho_b = 1800.0;
    o->g = 9.81;
}

static void empirical_drop_cache(empirical *e)
{
    free(e->M); /* one block: M, Q, t_p, h3_coef, ln_h3_3, A_was, w_was */
    free(e->order); /* one block: order, dark */
    free(e->mark);
    e->M = e->Q = e->t_p = e->h3_coef = e->ln_h3_3 = e->A_was = e->w_was = NULL;
    e->order = e->dark = NULL;
    e->mark = NULL;
    e->n_order = e->n_dark = e->dark_cap = 0;
    e->cached_for = e->cached_id = e->dark_since = 0;
    e->n = 0;
}

static int empirical_alloc_cache(empirical *e, size_t n, dfle_error *err)
{
    double *block = malloc(7 * n * sizeof *block);
    const size_t cap = n / 16 + 1;
    empirical_drop_cache(e);
    e->order = malloc((n + cap) * sizeof *e->order);
    e->mark = malloc(n);
    if (block == NULL || e->order == NULL || e->mark == NULL) {
        free(block);
        empirical_drop_cache(e);
        return dfle_error_set(err, DFLE_ENOMEM, "router.empirical: out of memory");
    }
    e->M = block;
    e->Q = block + n;
    e->t_p = block + 2 * n;
    e->h3_coef = block + 3 * n;
    e->ln_h3_3 = block + 4 * n;
    e->A_was = block + 5 * n;
    e->w_was = block + 6 * n;
    e->dark = e->order + n;
    e->dark_cap = cap;
    for (size_t i = 0; i < n; i++)
        e->M[i] = e->Q[i] = e->t_p[i] = e->h3_coef[i] = e->ln_h3_3[i] = e->A_was[i] =
            e->w_was[i] = NAN;
    e->n = n;
    return DFLE_OK;
}

/* The area-only terms at node i from A and w; DFLE_OK, or the error
 * naming the term that has no finite value. */
static int empirical_node_terms(empirical *e, size_t i, double A, double w, dfle_error *err)
{
    const dfle_empirical_opts *o = &e->opts;
    e->M[i] = o->M0 * pow(1e-6 * A, o->gamma);
    e->Q[i] = o->c1 * pow(e->M[i], o->c2);
    e->t_p[i] = e->M[i] / e->Q[i];
    e->h3_coef[i] = 3.0 * o->mu * e->Q[i] / (o->rho_b * o->g * w);
    e->ln_h3_3[i] = log(e->h3_coef[i]) / 3.0;
    e->A_was[i] = A;
    e->w_was[i] = w;
    /* Every parameter may be valid on its own and the flow still not
     * exist (c2 = 2.5e6 makes M^c2 overflow): say which term and why,
     * rather than route infinities the model reports as "E_df". */
    if (!(isfinite(e->M[i]) && e->M[i] > 0 && isfinite(e->Q[i]) && e->Q[i] > 0 &&
          isfinite(e->t_p[i]) && e->t_p[i] > 0 && isfinite(e->h3_coef[i]) && e->h3_coef[i] > 0)) {
        const char *what = !(isfinite(e->M[i]) && e->M[i] > 0)       ? "volume M = M0 (1e-6 A)^gamma"
                           : !(isfinite(e->Q[i]) && e->Q[i] > 0)     ? "peak discharge Q = c1 M^c2"
                           : !(isfinite(e->t_p[i]) && e->t_p[i] > 0) ? "passage time t_p = M/Q"
                                                                     : "depth term 3 mu Q / (rho_b g w)";
        return dfle_error_set(
            err, DFLE_EINVAL,
            "router.empirical: the %s is %g at node %zu (A = %g m^2, w = %g m): with M0 = %g, "
            "gamma = %g, c1 = %g, c2 = %g, mu = %g, rho_b = %g, g = %g the flow has no finite "
            "properties",
            what, !(isfinite(e->M[i]) && e->M[i] > 0)       ? e->M[i]
                  : !(isfinite(e->Q[i]) && e->Q[i] > 0)     ? e->Q[i]
                  : !(isfinite(e->t_p[i]) && e->t_p[i] > 0) ? e->t_p[i]
                                                            : e->h3_coef[i],
            i + 1, A, w, o->M0, o->gamma, o->c1, o->c2, o->mu, o->rho_b, o->g);
    }
    return DFLE_OK;
}

static int empirical_fill_cache(empirical *e, const dfle_network *net, dfle_error *err)
{
    const size_t n = dfle_network_size(net);
    const double *A = dfle_network_A(net), *w = dfle_network_w(net);
    const unsigned char *source = dfle_network_sources(net);
    const size_t *stack = dfle_network_stack(net), *recv = dfle_network_receivers(net);
    unsigned long long before = e->cached_for;
    int st;

    if (e->n != n || e->cached_id != dfle_network_id(net)) {
        if ((st = empirical_alloc_cache(e, n, err)) != DFLE_OK)
            return st;
        before = 0;
    }
    e->cached_for = 0; /* until every term below is made */
    /* Only nodes at or below a source ever carry a flow: on a landscape
     * the channel cells, a tenth of the grid.  Walking the stack from its
     * end lists every donor before its receiver. */
    memcpy(e->mark, source, n);
    e->n_order = 0;
    for (size_t k = n; k-- > 0;) {
        const size_t i = stack[k];
        if (e->mark[i]) {
            e->order[e->n_order++] = i;
            if (recv[i] != i)
                e->mark[recv[i]] = 1;
        }
    }
    e->n_dark = 0;
    for (size_t i = 0; i < n; i++) {
        if (!e->mark[i]) { /* never reached: nothing to cache */
            if (!isnan(e->M[i])) {
                if (e->n_dark < e->dark_cap)
                    e->dark[e->n_dark] = i;
                e->n_dark++;
                e->M[i] = e->Q[i] = e->t_p[i] = e->h3_coef[i] = e->ln_h3_3[i] = NAN;
                e->A_was[i] = e->w_was[i] = NAN;
            }
            continue;
        }
        if (A[i] == e->A_was[i] && w[i] == e->w_was[i])
            continue; /* the same terms as in the last shape */
        if ((st = empirical_node_terms(e, i, A[i], w[i], err)) != DFLE_OK) {
            empirical_drop_cache(e);
            return st;
        }
    }
    e->dark_since = before;
    e->cached_id = dfle_network_id(net);
    e->cached_for = dfle_network_version(net);
    return DFLE_OK;
}

static void zero_node(dfle_flow *flow, size_t j)
{
    flow->M[j] = flow->Q[j] = flow->t_p[j] = flow->h[j] = flow->v[j] = flow->tau[j] =
        flow->Theta[j] = flow->reach[j] = 0.0;
}

/* The flow at node i for slope s > 0 with depth h, written to node j of
 * `flow`; returns tau [Pa].  Theta may come out negative (tau < tau_y):
 * callers decide. */
static double empirical_at_depth(const empirical *e, const double *w, size_t i, double s,
                                 double h, dfle_flow *flow, size_t j)
{
    const double rho_g = e->opts.rho_b * e->opts.g;
    double Rh = w[i] * h / (w[i] + 2.0 * h);
    double tau = rho_g * Rh * s / sqrt(1.0 + s * s); /* sin(atan s) */
    flow->M[j] = e->M[i];
    flow->Q[j] = e->Q[i];
    flow->t_p[j] = e->t_p[i];
    flow->h[j] = h;
    flow->v[j] = e->Q[i] / (w[i] * h);
    flow->tau[j] = tau;
    flow->Theta[j] = 1.0 - e->opts.tau_y / tau;
    return tau;
}

/* The same for slope s alone: h^3 = h3_coef / s. */
static double empirical_at(const empirical *e, const double *w, size_t i, double s,
                           dfle_flow *flow, size_t j)
{
    return empirical_at_depth(e, w, i, s, cbrt(e->h3_coef[i] / s), flow, j);
}

static int ensure_cache(empirical *e, const dfle_network *net, dfle_error *err)
{
    /* Each shape of a network has a version of its own, unique for the
     * process, so it identifies the cached terms. */
    return e->cached_for == dfle_network_version(net) ? DFLE_OK : empirical_fill_cache(e, net, err);
}

/* Slow path of the finiteness check (one sum per routing is the fast
 * one): name the first node whose flow is not finite. */
static int check_finite(const dfle_flow *flow, const double *S, dfle_error *err)
{
    for (size_t i = 0; i < flow->n; i++)
        if (!(isfinite(flow->h[i]) && isfinite(flow->v[i]) && isfinite(flow->tau[i])))
            return dfle_error_set(err, DFLE_ENUMERIC,
                                  "router.empirical: the flow at node %zu (S = %g) is not finite "
                                  "(h = %g m, v = %g m/s, tau = %g Pa)",
                                  i + 1, S[i], flow->h[i], flow->v[i], flow->tau[i]);
    return DFLE_OK; /* the sum overflowed, nothing else */
}

/* One flow starts at every source and travels down the receivers; at a
 * node it goes on while S > 0 and tau >= tau_y there, and stops at the
 * first node where it does not (no erosion from that node on).  Taken in
 * reverse stack order every node comes after its donors, so the flows
 * arriving at a node are counted (reach) before it is reached.  On a
 * 1D channel this is the runout rule from the head down. */
static int empirical_route(void *state, const dfle_network *net,
                           const double *S, dfle_flow *flow, dfle_error *err)
{
    empirical *e = state;
    const double *w = dfle_network_w(net);
    const size_t *recv = dfle_network_receivers(net);
    const unsigned char *source = dfle_network_sources(net);
    size_t n = dfle_network_size(net), reached = 0, first_gap = n;
    double chk = 0.0;
    int st;

    if (flow->n != n)
        return dfle_error_set(err, DFLE_EINVAL,
                              "router.empirical: flow has %zu nodes, network %zu", flow->n, n);
    if ((st = ensure_cache(e, net, err)) != DFLE_OK)
        return st;
    flow->time_resolved = 0;
    if (dfle_network_is_chain(net) && source[0] && (n < 2 || !source[1])) {
        /* A channel: the one flow from the head down to its runout, the
         * work of the 1D model and no more (the general walk below visits
         * every node through the stack). */
        size_t i;
        double sum = 0.0;
        for (i = 0; i < n; i++) {
            if (!(S[i] > 0) || empirical_at(e, w, i, S[i], flow, i) < e->opts.tau_y)
                break;
            sum += flow->h[i] + flow->v[i] + flow->tau[i];
            flow->reach[i] = 1.0;
        }
        flow->runout_end = i;
        for (; i < n; i++)
            zero_node(flow, i);
        return isfinite(sum) ? DFLE_OK : check_finite(flow, S, err);
    }
    /* Nodes no flow can reach are zeroed once per network shape and
     * flow; after that only the reachable ones are walked. */
    if (flow->clean_for != e->cached_for) {
        if (flow->clean_for != 0 && flow->clean_for == e->dark_since &&
            e->n_dark <= e->dark_cap) {
            for (size_t k = 0; k < e->n_dark; k++)
                zero_node(flow, e->dark[k]);
        } else {
            for (size_t i = 0; i < n; i++)
                if (isnan(e->M[i]))
                    zero_node(flow, i);
        }
        flow->clean_for = e->cached_for;
    }
    for (size_t k = 0; k < e->n_order; k++)
        flow->reach[e->order[k]] = source[e->order[k]];
    for (size_t k = 0; k < e->n_order; k++) {
        const size_t i = e->order[k];
        const double arriving = flow->reach[i];
        /* No flow on a flat or reverse slope, nor where tau < tau_y. */
        if (!(arriving > 0) || !(S[i] > 0) ||
            empirical_at(e, w, i, S[i], flow, i) < e->opts.tau_y) {
            zero_node(flow, i);
            continue;
        }
        chk += flow->h[i] + flow->v[i] + flow->tau[i];
        reached++;
        if (recv[i] != i)
            flow->reach[recv[i]] += arriving;
    }
    for (size_t i = 0; i < n && first_gap == n; i++)
        if (!(flow->reach[i] > 0))
            first_gap = i;
    flow->runout_end = dfle_network_is_chain(net) ? first_gap : reached;
    return isfinite(chk) ? DFLE_OK : check_finite(flow, S, err);
}

/* How the flow empirical_at put in node j answers ln S at node i.
 * h = (h3_coef / S)^(1/3): d ln h = -1/3, and v = Q / (w h): +1/3.  The
 * hydraulic radius R_h = w h / (w + 2 h) follows h with the weight
 * w / (w + 2 h); tau = rho_b g R_h sin(atan S) adds
 * d ln sin(atan S) / d ln S = 1 / (1 + S^2); Theta = 1 - tau_y / tau
 * moves by (tau_y / tau) d ln tau.  M, Q and t_p depend on A alone. */
static void empirical_dlnS(const empirical *e, const double *w, size_t i, double S,
                           const dfle_flow *flow, size_t j, dfle_flow_dlnS *d)
{
    const double h = flow->h[j];
    d->M = d->Q = d->t_p = 0.0;
    d->h = -1.0 / 3.0;
    d->v = 1.0 / 3.0;
    d->tau = d->h * w[i] / (w[i] + 2.0 * h) + 1.0 / (1.0 + S * S);
    d->Theta = e->opts.tau_y / flow->tau[j] * d->tau;
}

/* node_flow, and node_flow_dlnS when d is set (with lnS = ln S). */
static int empirical_node(empirical *e, const dfle_network *net, size_t i, double S, double lnS,
                          dfle_flow *node, dfle_flow_dlnS *d, int *goes_on, dfle_error *err)
{
    const double *w = dfle_network_w(net);
    int st;
    *goes_on = 0;
    if ((st = ensure_cache(e, net, err)) != DFLE_OK)
        return st;
    assert(i < e->n && node->n >= 1);
    node->time_resolved = 0;
    if (!(S > 0)) {
        zero_node(node, 0);
        if (d != NULL)
            *d = (dfle_flow_dlnS){0};
        return DFLE_OK;
    }
    /* The depth by one exp of the cached ln h3_coef where ln S is known
     * (Newton's node solves): a cbrt costs three times as much. */
    if ((d != NULL ? empirical_at_depth(e, w, i, S, exp(e->ln_h3_3[i] - lnS / 3.0), node, 0)
                   : empirical_at(e, w, i, S, node, 0)) < e->opts.tau_y) {
        node->Theta[0] = 0.0; /* arriving, it stops here: no erosion */
        node->reach[0] = 0.0;
    } else {
        node->reach[0] = 1.0;
        *goes_on = 1;
    }
    if (d != NULL) {
        empirical_dlnS(e, w, i, S, node, 0, d);
        if (!*goes_on)
            d->Theta = 0.0; /* Theta is held at 0 below tau_y */
    }
    return DFLE_OK;
}

static int empirical_node_flow(void *state, const dfle_network *net, size_t i, double S,
                               dfle_flow *node, int *goes_on, dfle_error *err)
{
    return empirical_node(state, net, i, S, NAN, node, NULL, goes_on, err);
}

static int empirical_node_flow_dlnS(void *state, const dfle_network *net, size_t i, double S,
                                    double lnS, dfle_flow *node, dfle_flow_dlnS *d, int *goes_on,
                                    dfle_error *err)
{
    return empirical_node(state, net, i, S, lnS, node, d, goes_on, err);
}

static size_t empirical_params(const void *state, dfle_param *out, size_t cap)
{
    const dfle_empirical_opts *o = &((const empirical *)state)->opts;
    const dfle_param p[] = {
        {"M0", o->M0, "m^(3-2 gamma)", 0}, {"gamma", o->gamma, "", 0},
        {"mu", o->mu, "Pa s", 0},          {"tau_y", o->tau_y, "Pa", 0},
        {"c1", o->c1, "", 0},              {"c2", o->c2, "", 0},
        {"rho_b", o->rho_b, "kg/m^3", 0},  {"g", o->g, "m/s^2", 0},
    };
    return dfle_param_copy(p, sizeof p / sizeof p[0], out, cap);
}

static void empirical_destroy(void *state)
{
    empirical *e = state;
    if (e == NULL)
        return;
    empirical_drop_cache(e);
    free(e);
}

static const dfle_router_ops empirical_ops = {
    .version = DFLE_ROUTER_OPS_VERSION,
    .name = "empirical",
    .route = empirical_route,
    .needs_reroute = NULL, /* cheap and local: route every step */
    .node_flow = empirical_node_flow,
    .params = empirical_params,
    .destroy = empirical_destroy,
    .node_flow_dlnS = empirical_node_flow_dlnS,
};

#define POSITIVE(field)                                                       \
    do {                                                                      \
        if (!(isfinite(o->field) && o->field > 0))                            \
            return dfle_error_set(err, DFLE_EINVAL,                           \
                                  "router.empirical: " #field                 \
                                  " must be > 0 (got %g)", o->field);         \
    } while (0)
#define NONNEGATIVE(field)                                                    \
    do {                                                                      \
        if (!(isfinite(o->field) && o->field >= 0))                           \
            return dfle_error_set(err, DFLE_EINVAL,                           \
                                  "router.empirical: " #field                 \
                                  " must be >= 0 (got %g)", o->field);        \
    } while (0)

int dfle_router_new_empirical(const dfle_empirical_opts *o,
                              dfle_router **out, dfle_error *err)
{
    empirical *e;

    *out = NULL;
    POSITIVE(M0); NONNEGATIVE(gamma); POSITIVE(mu); NONNEGATIVE(tau_y);
    POSITIVE(c1); POSITIVE(c2); POSITIVE(rho_b); POSITIVE(g);
    e = calloc(1, sizeof *e);
    if (e == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "router.empirical: out of memory");
    e->opts = *o;
    return dfle_router_new(&empirical_ops, e, out, err);
}

const dfle_empirical_opts *dfle_router_empirical_opts(const dfle_router *rt)
{
    if (rt == NULL || dfle_router_get_ops(rt) != &empirical_ops)
        return NULL;
    return &((const empirical *)dfle_router_state(rt))->opts;
}
