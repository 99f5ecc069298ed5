/*
 * model_rates.c - the rates of Eq. (3) for the model's state: slopes,
 * fluvial erosion, the debris flow and its erosion, dz/dt; their slope
 * derivative (the kinematic-wave speed that limits explicit steps); and
 * the erosion at one node as a function of its own slope, which the
 * implicit and direct solvers turn into one scalar equation per node.
 *
 * One evaluation:
 *   1. slopes from elevations, S_i = (z_i - z_r) / L_i (receiver r);
 *   2. fluvial erosion per node;
 *   3. route the debris flow (every step for a local router such as the
 *      empirical one; otherwise only when the router says the slopes have
 *      moved far enough from those of this model's last routing), the
 *      law's flow factor after each routing and its rate every time;
 *   4. dz/dt, and a check that everything produced is finite.
 */
#include <assert.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "model/model_internal.h"

/* Relative slope perturbation of the finite-difference dE/dS: large
 * enough to stay clear of round-off in E, small enough to be local. */
#define CELERITY_EPS 1e-6

/* The nodes `flow` reaches (reach > 0), and whether they are a prefix.
 * On a chain the router's runout_end says it at once. */
static void find_reached(const dfle_model *m, const dfle_flow *flow, reached_set *r)
{
    r->n = 0;
    r->prefix = 1;
    if (dfle_network_is_chain(m->net)) {
        for (; r->n < flow->runout_end; r->n++)
            r->node[r->n] = r->n;
        return;
    }
    for (size_t i = 0; i < flow->n; i++)
        if (flow->reach[i] > 0) {
            r->prefix = r->prefix && i == r->n;
            r->node[r->n++] = i;
        }
}

/* The factor the combine rule gives a node reached by `count` flows. */
static double combine_factor(const dfle_model *m, double count, double A)
{
    switch (m->combine) {
    case DFLE_DF_COUNT: return count;
    case DFLE_DF_CUSTOM: return m->frequency(m->frequency_ud, count, A);
    default: return 1.0;
    }
}

/* The multiplier of E_df at node i: the erodibility scale, 0 on a
 * hillslope (network.h's channel mask). */
static double node_df_scale(const dfle_model *m, size_t i)
{
    if (m->channel != NULL && !m->channel[i])
        return 0.0;
    return m->df_scale != NULL ? m->df_scale[i] : 1.0;
}

/* The law on the reached nodes r of `flow`: F (after a routing, when
 * route is set) and E.  A prefix is read in place; otherwise the nodes
 * are gathered into contiguous arrays, as every law expects, and the
 * results scattered back. */
static int law_on_reached(dfle_model *m, const double *S, const dfle_flow *flow,
                          const reached_set *r, double *F, double *E, int route, dfle_error *err)
{
    const double *A = dfle_network_A(m->net), *w = dfle_network_w(m->net);
    dfle_law_ctx ctx;
    int st;

    ctx.n = r->n;
    if (r->prefix) {
        ctx.S = S;
        ctx.A = A;
        ctx.w = w;
        ctx.flow = flow;
        if (route && (st = dfle_law_flow_factor(m->law, &ctx, F, err)) != DFLE_OK)
            return st;
        return dfle_law_rate(m->law, &ctx, F, E, err);
    }
    if (m->g_block == NULL) {
        const size_t n = m->n;
        m->g_block = malloc((5 + DFLE_FLOW_ARRAYS) * n * sizeof *m->g_block);
        if (m->g_block == NULL)
            return dfle_error_set(err, DFLE_ENOMEM, "model: out of memory for %zu nodes", n);
        dfle_flow_bind(&m->g_flow, m->g_block + 5 * n, n);
    }
    {
        const size_t n = m->n, k = r->n;
        double *gS = m->g_block, *gA = gS + n, *gw = gA + n, *gF = gw + n, *gE = gF + n;
        dfle_flow *g = &m->g_flow;
        for (size_t j = 0; j < k; j++) {
            const size_t i = r->node[j];
            gS[j] = S[i], gA[j] = A[i], gw[j] = w[i], gF[j] = F[i];
            g->M[j] = flow->M[i], g->Q[j] = flow->Q[i], g->h[j] = flow->h[i];
            g->v[j] = flow->v[i], g->t_p[j] = flow->t_p[i], g->tau[j] = flow->tau[i];
            g->Theta[j] = flow->Theta[i], g->reach[j] = flow->reach[i];
            g->integral[j] = flow->integral[i];
        }
        g->n = k;
        g->runout_end = k;
        g->time_resolved = flow->time_resolved;
        ctx.S = gS, ctx.A = gA, ctx.w = gw, ctx.flow = g;
        if (route && (st = dfle_law_flow_factor(m->law, &ctx, gF, err)) != DFLE_OK)
            return st;
        if ((st = dfle_law_rate(m->law, &ctx, gF, gE, err)) != DFLE_OK)
            return st;
        for (size_t j = 0; j < k; j++) {
            F[r->node[j]] = gF[j];
            E[r->node[j]] = gE[j];
        }
    }
    return DFLE_OK;
}

/* Debris-flow erosion for slopes S into E; routes into `flow` when asked
 * (route != 0; r then becomes the nodes it reaches), otherwise reuses
 * the flow factor F on the nodes r. */
static int debris_flow_erosion(dfle_model *m, const double *S, dfle_flow *flow, reached_set *r,
                               double *F, double *E, int route, dfle_error *err)
{
    const dfle_law_ops *lops = dfle_law_get_ops(m->law);
    const double *A = dfle_network_A(m->net);
    int st;

    if (route) {
        /* Time-resolved routers sum the law's Eq. (11) integrand as they go. */
        flow->integrand = lops->integrand;
        flow->integrand_state = dfle_law_state(m->law);
        st = dfle_router_route(m->rt, m->net, S, flow, err);
        if (st != DFLE_OK)
            return st;
        assert(flow->runout_end <= m->n);
        find_reached(m, flow, r);
    }
    if (!r->prefix)
        for (size_t i = 0; i < m->n; i++)
            E[i] = 0.0;
    if ((st = law_on_reached(m, S, flow, r, F, E, route, err)) != DFLE_OK)
        return st;
    if (r->prefix)
        for (size_t i = r->n; i < m->n; i++)
            E[i] = 0.0;
    if (m->combine != DFLE_DF_ANY)
        for (size_t j = 0; j < r->n; j++) {
            const size_t i = r->node[j];
            E[i] *= combine_factor(m, flow->reach[i], A[i]);
        }
    if (m->df_scale != NULL || m->channel != NULL)
        for (size_t j = 0; j < r->n; j++) {
            const size_t i = r->node[j];
            E[i] *= node_df_scale(m, i);
        }
    return DFLE_OK;
}

/* Where node i lies, for messages: x if the network has one. */
static double node_x(const dfle_model *m, size_t i)
{
    return dfle_network_x(m->net)[i];
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
                          what, i + 1, node_x(m, i), m->time, m->z[i], m->S[i],
                          m->E_f[i], m->E_df[i]);
}

/* Slow path of the finiteness check: the first bad node, named. */
static int check_finite(const dfle_model *m, dfle_error *err)
{
    for (size_t i = 0; i < m->n; i++)
        if (!isfinite(m->z[i]) || !isfinite(m->S[i]) || !isfinite(m->dzdt[i]) ||
            !isfinite(m->E_f[i]) || !isfinite(m->E_df[i]))
            return report_nonfinite(m, i, err);
    return DFLE_OK;
}

/* Step 1: slopes of the current z into S; returns how many non-base
 * nodes have S <= 0.  The domain must be in sync. */
static size_t slopes_of(const dfle_model *m, double *S)
{
    const size_t n = m->n;
    const size_t *recv = dfle_network_receivers(m->net), *base;
    size_t nonpositive = 0, n_base;

    base = dfle_network_bases(m->net, &n_base);
    /* Branch-free over all nodes: a base node is its own receiver, so its
     * slope comes out 0 (counted, then taken back) and is then replaced
     * by its donor's. */
    for (size_t i = 0; i < n; i++) {
        S[i] = (m->z[i] - m->z[recv[i]]) * m->inv_len[i];
        nonpositive += !(S[i] > 0);
    }
    for (size_t k = 0; k < n_base; k++) {
        const size_t i = base[k], d = dfle_network_base_donor(m->net, i);
        nonpositive -= !(S[i] > 0);
        S[i] = d != NO_NODE ? S[d] : 0.0;
    }
    return nonpositive;
}

void dfle_model_slopes(dfle_model *m, double *S)
{
    dfle_model_sync_domain(m);
    (void)slopes_of(m, S);
}

int dfle_model_evaluate(dfle_model *m, dfle_error *err)
{
    const size_t n = m->n;
    const size_t *base;
    size_t n_base;
    double sum = 0.0;
    int st;

    dfle_model_sync_domain(m);
    base = dfle_network_bases(m->net, &n_base);
    m->nonpositive = slopes_of(m, m->S);

    if (m->fl != NULL) {
        const double n_s = dfle_fluvial_n(m->fl);
        for (size_t i = 0; i < n; i++) /* KAm = 0 off the channels: no pow() there */
            m->E_f[i] = m->S[i] > 0 && m->KAm[i] != 0 ? m->KAm[i] * pow(m->S[i], n_s) : 0.0;
    }
    if (m->rt != NULL) {
        int route = 1;
        if (m->flow_valid &&
            (st = dfle_router_needs_reroute(m->rt, n, m->S_routed, m->S, &route, err)) != DFLE_OK)
            return st;
        st = m->pop != NULL
                 ? dfle_model_pop_erosion(m, m->S, &m->flow, &m->reached, m->F, m->E_df, 1, err)
                 : debris_flow_erosion(m, m->S, &m->flow, &m->reached, m->F, m->E_df, route, err);
        if (st != DFLE_OK)
            return st;
        if (route) {
            m->routings++;
            m->flow_valid = 1;
            if (!dfle_router_is_local(m->rt)) /* what the next needs_reroute compares with */
                memcpy(m->S_routed, m->S, n * sizeof *m->S);
        }
    }
    for (size_t i = 0; i < n; i++) {
        m->dzdt[i] = m->U - m->E_f[i] - m->E_df[i];
        /* A sum is finite only if every term is (or it overflowed, which
         * the slow path then clears): one test per node, not five. */
        sum += m->z[i] + m->S[i] + m->dzdt[i];
    }
    for (size_t k = 0; k < n_base; k++)
        m->dzdt[base[k]] = 0.0;
    /* Everything a step produces, not only the rates: a NaN elevation
     * gives S = NaN, which every law reads as "no erosion". */
    if (!isfinite(sum) && (st = check_finite(m, err)) != DFLE_OK)
        return st;
    m->evaluated = 1;
    return DFLE_OK;
}

int dfle_model_route(dfle_model *m, const double **S, const double **reach, dfle_error *err)
{
    int st;
    if (m->rt == NULL || m->pop != NULL || !dfle_router_is_local(m->rt)) {
        /* The node solves read the cached flow factor (a router routed
         * rarely) or every member's flow: all of it is needed. */
        if (!m->evaluated && (st = dfle_model_evaluate(m, err)) != DFLE_OK)
            return st;
    } else {
        dfle_model_sync_domain(m);
        m->nonpositive = slopes_of(m, m->S);
        if ((st = dfle_router_route(m->rt, m->net, m->S, &m->flow, err)) != DFLE_OK)
            return st;
        m->routings++;
        /* The law's flow factor was not taken: the next evaluation routes
         * again rather than trust F. */
        m->flow_valid = 0;
        m->evaluated = 0;
    }
    *S = m->S;
    *reach = m->flow.reach;
    return DFLE_OK;
}

int dfle_model_is_evaluated(const dfle_model *m) { return m->evaluated; }
size_t dfle_model_nonpositive_slopes(const dfle_model *m) { return m->nonpositive; }
size_t dfle_model_routings(const dfle_model *m) { return m->routings; }

double dfle_model_flow_reaches(const dfle_model *m, size_t i)
{
    assert(i < m->n);
    return m->rt != NULL ? m->flow.reach[i] : 0.0;
}

double dfle_model_rate_ratio(const dfle_model *m)
{
    double r = 0.0;
    assert(m->evaluated);
    for (size_t i = 0; i < m->n; i++) {
        double a = fabs(m->dzdt[i]); /* 0 on base nodes */
        if (a > r)
            r = a;
    }
    /* A finite rate over a U of 5e-324 m/yr (valid: > 0) overflows; the
     * ratio is a result scripts print and compare, so never inf. */
    r /= m->U;
    return r <= DBL_MAX ? r : DBL_MAX;
}

int dfle_model_celerity(dfle_model *m, const double **c_out, dfle_error *err)
{
    const size_t n = m->n;
    int st;

    assert(m->evaluated);
    if ((st = dfle_model_pert_alloc(m, err)) != DFLE_OK)
        return st;
    if (m->fl != NULL) {
        const double n_s = dfle_fluvial_n(m->fl);
        for (size_t i = 0; i < n; i++)
            m->celerity[i] = m->S[i] > 0 ? n_s * m->E_f[i] / m->S[i] : 0.0;
    } else {
        for (size_t i = 0; i < n; i++)
            m->celerity[i] = 0.0;
    }
    if (m->rt != NULL && m->reached.n > 0) {
        int local = dfle_router_is_local(m->rt);

        for (size_t i = 0; i < n; i++)
            m->S_pert[i] = m->S[i] > 0 ? m->S[i] * (1.0 + CELERITY_EPS) : m->S[i];
        if (m->pop != NULL) {
            st = dfle_model_pop_erosion(m, m->S_pert, &m->flow_pert, &m->reached_pert, m->F_pert,
                                        m->E_pert, 0, err);
        } else if (local) {
            st = debris_flow_erosion(m, m->S_pert, &m->flow_pert, &m->reached_pert, m->F_pert,
                                     m->E_pert, 1, err);
        } else {
            /* The flow stays as routed; only the slope term moves. */
            st = debris_flow_erosion(m, m->S_pert, &m->flow, &m->reached, m->F, m->E_pert, 0, err);
        }
        if (st != DFLE_OK)
            return st;
        /* A node the perturbed flow newly reaches would show a jump, not
         * a derivative: use only nodes both flows reach. */
        for (size_t j = 0; j < m->reached.n; j++) {
            const size_t i = m->reached.node[j];
            if (m->S[i] > 0 && (!local || m->flow_pert.reach[i] > 0))
                m->celerity[i] += fabs(m->E_pert[i] - m->E_df[i]) / (CELERITY_EPS * m->S[i]);
        }
    }
    {
        size_t n_base;
        const size_t *base = dfle_network_bases(m->net, &n_base);
        for (size_t k = 0; k < n_base; k++)
            m->celerity[base[k]] = 0.0; /* held fixed: no wave there */
    }
    *c_out = m->celerity;
    return DFLE_OK;
}



/* A one-node view of the model's routed flow at node i. */
static dfle_flow flow_at(const dfle_flow *f, size_t i)
{
    dfle_flow v;
    memset(&v, 0, sizeof v);
    v.n = 1;
    v.runout_end = f->reach[i] > 0;
    v.M = f->M + i, v.Q = f->Q + i, v.h = f->h + i, v.v = f->v + i;
    v.t_p = f->t_p + i, v.tau = f->tau + i, v.Theta = f->Theta + i, v.reach = f->reach + i;
    v.integral = f->integral + i;
    v.time_resolved = f->time_resolved;
    return v;
}

/* E_f + E_df at node i for slope S, and d(E_f + E_df)/d ln S into *dE
 * when dE is set (the caller has checked dfle_model_node_dlnS); lnS = ln S
 * then. */
static int node_erosion(dfle_model *m, size_t i, double S, double lnS, double flows, double *E,
                        double *dE, int *goes_on, dfle_error *err)
{
    double e = 0.0, de = 0.0;
    assert(i < m->n);
    *goes_on = 0;
    m->node_evaluations++;
    dfle_model_sync_domain(m); /* K A^m of the current shape and scales */
    if (!(S > 0)) { /* no erosion up a reverse slope (model.h) */
        *E = 0.0;
        if (dE != NULL)
            *dE = 0.0;
        return DFLE_OK;
    }
    if (m->fl != NULL) {
        const double n_s = dfle_fluvial_n(m->fl);
        e = m->KAm[i] * (dE != NULL ? exp(n_s * lnS) : pow(S, n_s));
        de = n_s * e; /* E_f = K A^m S^n_s */
    }
    if (flows > 0 && m->pop != NULL) {
        double Edf, dEdf = 0.0;
        int st = dfle_model_pop_node_erosion(m, i, S, lnS, &Edf, dE != NULL ? &dEdf : NULL,
                                             goes_on, err);
        if (st != DFLE_OK)
            return st;
        e += Edf;
        de += dEdf;
    } else if (flows > 0 && m->rt != NULL) {
        dfle_law_ctx ctx = {.n = 1, .S = &S, .A = dfle_network_A(m->net) + i,
                            .w = dfle_network_w(m->net) + i};
        dfle_flow view; /* lives as long as ctx: rate may read the flow */
        dfle_flow_dlnS dflow, *dp = NULL;
        double F, Edf, dEdf = 0.0;
        int st;
        if (dfle_router_is_local(m->rt)) {
            /* The flow at this node follows its slope: re-evaluate it. */
            if (dE != NULL)
                st = dfle_router_node_flow_dlnS(m->rt, m->net, i, S, lnS, &m->node, dp = &dflow,
                                                goes_on, err);
            else
                st = dfle_router_node_flow(m->rt, m->net, i, S, &m->node, goes_on, err);
            if (st != DFLE_OK)
                return st;
            m->node.runout_end = 1;
            ctx.flow = &m->node;
            if ((st = dfle_law_flow_factor(m->law, &ctx, &F, err)) != DFLE_OK)
                return st;
        } else {
            /* Routed rarely: the cached Eq. (11) factor stands. */
            view = flow_at(&m->flow, i);
            *goes_on = m->flow.reach[i] > 0;
            if (!*goes_on) {
                *E = e;
                if (dE != NULL)
                    *dE = de;
                return DFLE_OK;
            }
            ctx.flow = &view;
            F = m->F[i];
        }
        if ((st = dfle_law_rate(m->law, &ctx, &F, &Edf, err)) != DFLE_OK)
            return st;
        /* The rate just run may have dropped the law's op (a Lua law
         * whose program failed its check): no derivative, then. */
        if (dE != NULL && !dfle_law_has_rate_dlnS(m->law))
            dEdf = NAN;
        else if (dE != NULL &&
                 (st = dfle_law_rate_dlnS(m->law, &ctx, &F, &Edf, dp, &dEdf, err)) != DFLE_OK)
            return st;
        /* The combine rule and the scales are constants in S: they
         * multiply E_df and its derivative alike. */
        if (m->combine != DFLE_DF_ANY) {
            const double c = combine_factor(m, flows, dfle_network_A(m->net)[i]);
            Edf *= c, dEdf *= c;
        }
        if (m->df_scale != NULL || m->channel != NULL) {
            const double c = node_df_scale(m, i);
            Edf *= c, dEdf *= c;
        }
        e += Edf;
        de += dEdf;
    }
    if (!isfinite(e))
        return dfle_error_set(err, DFLE_ENUMERIC,
                              "model: erosion is not finite at node %zu for S = %g", i + 1, S);
    *E = e;
    if (dE != NULL)
        *dE = de;
    return DFLE_OK;
}

int dfle_model_node_erosion(dfle_model *m, size_t i, double S, double flows, double *E,
                            int *goes_on, dfle_error *err)
{
    return node_erosion(m, i, S, NAN, flows, E, NULL, goes_on, err);
}

/* Asked each time: a law written in Lua offers rate_dlnS only while its
 * compiled programs can give it (doc/laws.md). */
int dfle_model_node_dlnS(const dfle_model *m)
{
    return m->rt == NULL || (dfle_law_has_rate_dlnS(m->law) &&
                             (!dfle_router_is_local(m->rt) || m->pop != NULL ||
                                              dfle_router_has_node_flow_dlnS(m->rt)));
}

int dfle_model_node_erosion_dlnS(dfle_model *m, size_t i, double S, double lnS, double flows,
                                 double *E, double *dE, int *goes_on, dfle_error *err)
{
    if (!dfle_model_node_dlnS(m)) {
        *dE = NAN;
        return node_erosion(m, i, S, NAN, flows, E, NULL, goes_on, err);
    }
    return node_erosion(m, i, S, lnS, flows, E, dE, goes_on, err);
}

size_t dfle_model_node_evaluations(const dfle_model *m) { return m->node_evaluations; }

/* For model_population.c: the steps above, for one member flow. */
void dfle_model_find_reached(const dfle_model *m, const dfle_flow *flow, reached_set *r)
{
    find_reached(m, flow, r);
}

int dfle_model_law_on_reached(dfle_model *m, const double *S, const dfle_flow *flow,
                              const reached_set *r, double *F, double *E, int route,
                              dfle_error *err)
{
    return law_on_reached(m, S, flow, r, F, E, route, err);
}

double dfle_model_combine_factor(const dfle_model *m, double count, double A)
{
    return m->combine != DFLE_DF_ANY ? combine_factor(m, count, A) : 1.0;
}

double dfle_model_df_scale(const dfle_model *m, size_t i) { return node_df_scale(m, i); }
