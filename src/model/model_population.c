/*
 * model_population.c - the debris-flow erosion of a population of flows
 * (router_population.h): the expectation over its quadrature flows,
 *
 *   E_df,i = sum_j rate_j E_df,i(flow j)      rate_j = lambda w_j [1/yr],
 *
 * each member routed with its own runout, the law and the combine rule
 * applied to each member as to a characteristic flow.
 *
 * The node solvers (implicit steps, the direct steady state) evaluate
 * the erosion at one node for trial slopes, from the heads down.  Which
 * members arrive at a node depends on the slopes above it, so the model
 * keeps, per member, the flows arriving at every node and those going
 * on: a routing sets them all, and every one-node evaluation updates the
 * node's "going on" and, by the difference, its receiver's "arriving".
 * Taken from the heads down (the direct march) each node then sees the
 * members that the slopes just solved above it let through; taken from
 * the outlet up (an implicit step) it sees those of the last routing,
 * as a characteristic flow's node solve does.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/model_events.h"
#include "dfle/router_population.h"
#include "model/model_internal.h"

struct model_population {
    const dfle_population *pop;
    size_t q, n;
    unsigned long long version; /* the network shape arrive and pass are for */
    float *arrive; /* q n: member j's flows arriving at node i (sources: 1) */
    float *pass;   /* q n: member j's flows going on at node i             */
    double *block; /* scratch: a flow, then F and E (n each)               */
    dfle_flow flow;
    double *F, *E;
    reached_set reached;
};

int dfle_model_pop_new(dfle_model *m, dfle_error *err)
{
    const dfle_population *pop = dfle_router_get_population(m->rt);
    model_population *mp;
    const size_t n = m->n;

    m->pop = NULL;
    if (pop == NULL)
        return DFLE_OK;
    mp = calloc(1, sizeof *mp);
    if (mp == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "model: out of memory for a population");
    m->pop = mp;
    mp->pop = pop;
    mp->q = dfle_population_size(pop);
    mp->n = n;
    mp->arrive = calloc(2 * mp->q * n, sizeof *mp->arrive);
    mp->block = calloc((DFLE_FLOW_ARRAYS + 2) * n, sizeof *mp->block);
    mp->reached.node = malloc(n * sizeof *mp->reached.node);
    if (mp->arrive == NULL || mp->block == NULL || mp->reached.node == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "model: out of memory for a population of %zu "
                              "flows on %zu nodes", mp->q, n);
    mp->pass = mp->arrive + mp->q * n;
    dfle_flow_bind(&mp->flow, mp->block, n);
    mp->F = mp->block + DFLE_FLOW_ARRAYS * n;
    mp->E = mp->F + n;
    return DFLE_OK; /* arrive and pass are set for the first shape seen (sync_shape) */
}

size_t dfle_model_pop_memory(const dfle_model *m)
{
    const model_population *mp = m->pop;
    if (mp == NULL)
        return 0;
    return sizeof *mp + 2 * mp->q * mp->n * sizeof *mp->arrive +
           (DFLE_FLOW_ARRAYS + 2) * mp->n * sizeof *mp->block +
           mp->n * sizeof *mp->reached.node;
}

void dfle_model_pop_free(dfle_model *m)
{
    model_population *mp = m->pop;
    if (mp == NULL)
        return;
    free(mp->arrive);
    free(mp->block);
    free(mp->reached.node);
    free(mp);
    m->pop = NULL;
}

/* Arriving flows of member j from what goes on at every node: sources
 * release one, every node passes on what goes on there. */
static void arrivals_from_passes(const dfle_model *m, model_population *mp, size_t j)
{
    const size_t n = mp->n;
    const size_t *stack = dfle_network_stack(m->net), *recv = dfle_network_receivers(m->net);
    const unsigned char *source = dfle_network_sources(m->net);
    float *arrive = mp->arrive + j * n;
    const float *pass = mp->pass + j * n;
    for (size_t i = 0; i < n; i++)
        arrive[i] = source[i];
    for (size_t k = n; k-- > 0;) {
        const size_t i = stack[k];
        if (recv[i] != i)
            arrive[recv[i]] += pass[i];
    }
}

/* A new network shape (a landscape re-routed): nothing goes on yet. */
static void sync_shape(const dfle_model *m, model_population *mp)
{
    if (mp->version == dfle_network_version(m->net))
        return;
    memset(mp->pass, 0, mp->q * mp->n * sizeof *mp->pass);
    for (size_t j = 0; j < mp->q; j++)
        arrivals_from_passes(m, mp, j);
    mp->version = dfle_network_version(m->net);
}

int dfle_model_pop_erosion(dfle_model *m, const double *S, dfle_flow *sum, reached_set *r,
                           double *F, double *E, int commit, dfle_error *err)
{
    model_population *mp = m->pop;
    const size_t n = m->n;
    const dfle_law_ops *lops = dfle_law_get_ops(m->law);
    int st;

    sync_shape(m, mp);
    dfle_flow_clear(sum);
    memset(sum->integral, 0, n * sizeof *sum->integral);
    for (size_t i = 0; i < n; i++)
        E[i] = F[i] = 0.0;
    mp->flow.integrand = lops->integrand;
    mp->flow.integrand_state = dfle_law_state(m->law);
    for (size_t j = 0; j < mp->q; j++) {
        const double rate = dfle_population_rate(mp->pop, j);
        dfle_flow *mf = &mp->flow;
        reached_set *mr = &mp->reached;
        st = dfle_router_route(dfle_population_member(mp->pop, j), m->net, S, mf, err);
        if (st != DFLE_OK)
            return st;
        dfle_model_find_reached(m, mf, mr);
        if ((st = dfle_model_law_on_reached(m, S, mf, mr, mp->F, mp->E, 1, err)) != DFLE_OK)
            return st;
        for (size_t k = 0; k < mr->n; k++) {
            const size_t i = mr->node[k];
            const double c = dfle_model_combine_factor(m, mf->reach[i], dfle_network_A(m->net)[i]) *
                             dfle_model_df_scale(m, i);
            E[i] += rate * c * mp->E[i];
            F[i] += rate * mp->F[i];
        }
        dfle_population_accumulate(mp->pop, j, mf, sum);
        if (commit) {
            float *pass = mp->pass + j * n;
            for (size_t i = 0; i < n; i++)
                pass[i] = (float)(mf->reach[i] > 0 ? mf->reach[i] : 0.0);
            arrivals_from_passes(m, mp, j);
        }
    }
    dfle_model_find_reached(m, sum, r);
    return DFLE_OK;
}

int dfle_model_pop_node_erosion(dfle_model *m, size_t i, double S, double lnS, double *E,
                                double *dE, int *goes_on, dfle_error *err)
{
    model_population *mp = m->pop;
    const size_t n = mp->n, r = dfle_network_receivers(m->net)[i];
    const double A = dfle_network_A(m->net)[i], scale = dfle_model_df_scale(m, i);
    double e = 0.0, de = 0.0;
    int st;

    *goes_on = 0;
    sync_shape(m, mp);
    for (size_t j = 0; j < mp->q; j++) {
        const double arriving = mp->arrive[j * n + i];
        dfle_router *rt = dfle_population_member(mp->pop, j);
        dfle_law_ctx ctx = {.n = 1, .S = &S, .A = dfle_network_A(m->net) + i,
                            .w = dfle_network_w(m->net) + i, .flow = &m->node};
        dfle_flow_dlnS dflow;
        double F, Edf, dEdf = 0.0, c;
        float passing;
        int on = 0;
        if (!(arriving > 0))
            continue; /* stopped above: nothing of member j here */
        if (dE != NULL)
            st = dfle_router_node_flow_dlnS(rt, m->net, i, S, lnS, &m->node, &dflow, &on, err);
        else
            st = dfle_router_node_flow(rt, m->net, i, S, &m->node, &on, err);
        if (st != DFLE_OK)
            return st;
        m->node.runout_end = 1;
        if ((st = dfle_law_flow_factor(m->law, &ctx, &F, err)) != DFLE_OK ||
            (st = dfle_law_rate(m->law, &ctx, &F, &Edf, err)) != DFLE_OK)
            return st;
        if (dE != NULL && !dfle_law_has_rate_dlnS(m->law))
            dEdf = NAN;
        else if (dE != NULL &&
                 (st = dfle_law_rate_dlnS(m->law, &ctx, &F, &Edf, &dflow, &dEdf, err)) != DFLE_OK)
            return st;
        c = dfle_population_rate(mp->pop, j) * dfle_model_combine_factor(m, arriving, A) * scale;
        e += c * Edf;
        de += c * dEdf;
        /* What goes on from here, for the receiver's arrivals. */
        passing = on ? (float)arriving : 0.0f;
        if (r != i)
            mp->arrive[j * n + r] += passing - mp->pass[j * n + i];
        mp->pass[j * n + i] = passing;
        *goes_on = *goes_on || on;
    }
    *E = e;
    if (dE != NULL)
        *dE = de;
    return DFLE_OK;
}

int dfle_model_event_erosion(dfle_model *m, double f, double *E, dfle_error *err)
{
    model_population *mp = m->pop;
    dfle_router *rt;
    reached_set *mr;
    int st;

    if (mp == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "model: debris-flow events need a population "
                              "router (dfle.router.population)");
    if (!m->evaluated && (st = dfle_model_evaluate(m, err)) != DFLE_OK)
        return st;
    if ((st = dfle_population_new_flow(mp->pop, f, &rt, err)) != DFLE_OK)
        return st;
    mp->flow.integrand = dfle_law_get_ops(m->law)->integrand;
    mp->flow.integrand_state = dfle_law_state(m->law);
    mr = &mp->reached;
    st = dfle_router_route(rt, m->net, m->S, &mp->flow, err);
    dfle_router_free(rt);
    if (st != DFLE_OK)
        return st;
    dfle_model_find_reached(m, &mp->flow, mr);
    if ((st = dfle_model_law_on_reached(m, m->S, &mp->flow, mr, mp->F, mp->E, 1, err)) != DFLE_OK)
        return st;
    for (size_t i = 0; i < m->n; i++)
        E[i] = 0.0;
    for (size_t k = 0; k < mr->n; k++) {
        const size_t i = mr->node[k];
        /* One event erodes what the rate of one flow a year erodes in a year. */
        E[i] = mp->E[i] * dfle_model_combine_factor(m, mp->flow.reach[i],
                                                    dfle_network_A(m->net)[i]) *
               dfle_model_df_scale(m, i);
    }
    return DFLE_OK;
}

const dfle_population *dfle_model_population(const dfle_model *m)
{
    return m->pop != NULL ? m->pop->pop : NULL;
}
