/*
 * router_population.c - a population of debris flows behind one router
 * handle (router_population.h).
 *
 * The members are ordinary empirical routers, one per quadrature node,
 * with M0 times the node's factor: every rule of the characteristic flow
 * (volume-area scaling, Rickenmann's relations, the runout where
 * tau < tau_y) holds for each member as it is, and a zero-width
 * population runs the very code of the characteristic flow.  The model
 * evaluates the law per member (the law is not linear in the flow's
 * properties, so no single "mean flow" stands for the population); the
 * route op here only gives the summary a script reads.
 */
#include "dfle/router_population.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/router_empirical.h"

#define MAX_ORDER 64

struct dfle_population {
    dfle_population_opts opts;
    double M0;            /* the base router's M0 [m^(3-2 gamma)]            */
    double *table;        /* owned copies of a table's values, then weights */
    size_t q;
    dfle_router **member; /* q routers                                      */
    double *f, *w, *rate; /* factor, weight, rate lambda w [1/yr]           */
    double *block;        /* scratch flow of the route op (n nodes)         */
    size_t block_n;
};

void dfle_population_opts_default(dfle_population_opts *o)
{
    memset(o, 0, sizeof *o);
    o->volume.kind = DFLE_DIST_LOGNORMAL;
    o->volume.sigma = 0.0;
    o->volume.median = 1.0;
    o->frequency = 1.0;
    o->order = 8;
}

static void population_destroy(void *state)
{
    dfle_population *p = state;
    if (p == NULL)
        return;
    for (size_t j = 0; p->member != NULL && j < p->q; j++)
        dfle_router_free(p->member[j]);
    free(p->member);
    free(p->f);
    free(p->table);
    free(p->block);
    free(p);
}

static const dfle_population *population_of(const void *state) { return state; }

void dfle_population_accumulate(const dfle_population *p, size_t j, const dfle_flow *mf,
                                dfle_flow *sum)
{
    const double r = p->rate[j];
    /* Rate-weighted sums of the members going on, their weight kept in
     * `integral` until the last member turns the sums into means. */
    for (size_t i = 0; i < mf->n; i++) {
        if (!(mf->reach[i] > 0))
            continue;
        sum->reach[i] += r * mf->reach[i];
        sum->integral[i] += r;
        sum->M[i] += r * mf->M[i], sum->Q[i] += r * mf->Q[i], sum->h[i] += r * mf->h[i];
        sum->v[i] += r * mf->v[i], sum->t_p[i] += r * mf->t_p[i];
        sum->tau[i] += r * mf->tau[i], sum->Theta[i] += r * mf->Theta[i];
    }
    if (mf->runout_end > sum->runout_end)
        sum->runout_end = mf->runout_end;
    if (j + 1 < p->q)
        return;
    for (size_t i = 0; i < mf->n; i++) {
        const double W = sum->integral[i];
        if (W > 0) {
            sum->M[i] /= W, sum->Q[i] /= W, sum->h[i] /= W, sum->v[i] /= W;
            sum->t_p[i] /= W, sum->tau[i] /= W, sum->Theta[i] /= W;
        }
        sum->integral[i] = 0.0;
    }
    sum->time_resolved = 0;
}

/* The summary: every member routed over S in turn. */
static int population_route(void *state, const dfle_network *net, const double *S,
                            dfle_flow *flow, dfle_error *err)
{
    dfle_population *p = state;
    const size_t n = dfle_network_size(net);
    dfle_flow mf;
    int st;

    if (flow->n != n)
        return dfle_error_set(err, DFLE_EINVAL,
                              "router.population: flow has %zu nodes, network %zu", flow->n, n);
    if (p->block_n != n) {
        free(p->block);
        p->block_n = 0;
        p->block = calloc(DFLE_FLOW_ARRAYS * n + 1, sizeof *p->block);
        if (p->block == NULL)
            return dfle_error_set(err, DFLE_ENOMEM, "router.population: out of memory");
        p->block_n = n;
    }
    dfle_flow_bind(&mf, p->block, n);
    dfle_flow_clear(flow);
    memset(flow->integral, 0, n * sizeof *flow->integral);
    for (size_t j = 0; j < p->q; j++) {
        if ((st = dfle_router_route(p->member[j], net, S, &mf, err)) != DFLE_OK)
            return st;
        dfle_population_accumulate(p, j, &mf, flow);
    }
    return DFLE_OK;
}

static size_t population_params(const void *state, dfle_param *out, size_t cap)
{
    const dfle_population *p = state;
    const dfle_dist *d = &p->opts.volume;
    /* The members' parameters at f = 1 (M0 as given), then the
     * population's own. */
    dfle_param all[32];
    size_t n = dfle_router_params(p->member[0], all, 16);
    if (n > 16)
        n = 16;
    for (size_t k = 0; k < n; k++)
        if (strcmp(all[k].name, "M0") == 0)
            all[k].value = p->M0; /* the members' M0 is f_j times this */
    all[n++] = (dfle_param){"frequency", p->opts.frequency, "1/yr", 0};
    all[n++] = (dfle_param){"order", (double)p->q, "", 0};
    switch (d->kind) {
    case DFLE_DIST_LOGNORMAL:
        all[n++] = (dfle_param){"sigma", d->sigma, "", 0};
        all[n++] = (dfle_param){"median", d->median, "", 0};
        break;
    case DFLE_DIST_POWER_LAW:
        all[n++] = (dfle_param){"b", d->b, "", 0};
        all[n++] = (dfle_param){"f_min", d->f_min, "", 0};
        all[n++] = (dfle_param){"f_max", d->f_max, "", 0};
        break;
    case DFLE_DIST_UNIFORM:
        all[n++] = (dfle_param){"f_min", d->f_min, "", 0};
        all[n++] = (dfle_param){"f_max", d->f_max, "", 0};
        break;
    default:
        break;
    }
    return dfle_param_copy(all, n, out, cap);
}

static const dfle_router_ops population_ops = {
    .version = DFLE_ROUTER_OPS_VERSION,
    .name = "population",
    .route = population_route,
    .needs_reroute = NULL, /* members are routed every step, like the empirical router */
    .params = population_params,
    .destroy = population_destroy,
    .population = population_of,
};

int dfle_router_new_population(const dfle_router *base, const dfle_population_opts *o,
                               dfle_router **out, dfle_error *err)
{
    const dfle_empirical_opts *eo = base != NULL ? dfle_router_empirical_opts(base) : NULL;
    dfle_population *p;
    size_t cap;
    int st;

    *out = NULL;
    if (eo == NULL)
        return dfle_error_set(err, DFLE_EINVAL,
                              "router.population: router must be an empirical router (got %s)",
                              base != NULL ? dfle_router_name(base) : "none");
    if (!(isfinite(o->frequency) && o->frequency > 0))
        return dfle_error_set(err, DFLE_EINVAL,
                              "router.population: frequency must be > 0 events/yr (got %g)",
                              o->frequency);
    if (o->volume.kind != DFLE_DIST_TABLE && (o->order < 1 || o->order > MAX_ORDER))
        return dfle_error_set(err, DFLE_EINVAL,
                              "router.population: order must be a whole number in [1, %d] (got %zu)",
                              MAX_ORDER, o->order);
    if ((st = dfle_dist_check(&o->volume, err)) != DFLE_OK)
        return st;
    p = calloc(1, sizeof *p);
    if (p == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "router.population: out of memory");
    p->opts = *o;
    p->M0 = eo->M0;
    cap = o->volume.kind == DFLE_DIST_TABLE ? o->volume.n : o->order;
    if (o->volume.kind == DFLE_DIST_TABLE) {
        p->table = malloc(2 * cap * sizeof *p->table);
        if (p->table == NULL) {
            free(p);
            return dfle_error_set(err, DFLE_ENOMEM, "router.population: out of memory");
        }
        memcpy(p->table, o->volume.values, cap * sizeof *p->table);
        memcpy(p->table + cap, o->volume.weights, cap * sizeof *p->table);
        p->opts.volume.values = p->table;
        p->opts.volume.weights = p->table + cap;
    }
    p->f = malloc(3 * cap * sizeof *p->f);
    p->member = calloc(cap, sizeof *p->member);
    if (p->f == NULL || p->member == NULL) {
        population_destroy(p);
        return dfle_error_set(err, DFLE_ENOMEM, "router.population: out of memory");
    }
    p->w = p->f + cap;
    p->rate = p->w + cap;
    if ((st = dfle_dist_quadrature(&p->opts.volume, o->order, p->f, p->w, &p->q, err)) != DFLE_OK) {
        population_destroy(p);
        return st;
    }
    for (size_t j = 0; j < p->q; j++) {
        dfle_empirical_opts mo = *eo;
        mo.M0 = eo->M0 * p->f[j];
        p->rate[j] = o->frequency * p->w[j];
        if ((st = dfle_router_new_empirical(&mo, &p->member[j], err)) != DFLE_OK) {
            p->q = j; /* only those made */
            population_destroy(p);
            return st;
        }
    }
    return dfle_router_new(&population_ops, p, out, err);
}

const dfle_population *dfle_router_get_population(const dfle_router *rt)
{
    const dfle_router_ops *ops;
    if (rt == NULL)
        return NULL;
    ops = dfle_router_get_ops(rt);
    if (ops->version < 2 || ops->population == NULL)
        return NULL;
    return ops->population(dfle_router_state(rt));
}

int dfle_population_new_flow(const dfle_population *p, double f, dfle_router **out,
                             dfle_error *err)
{
    dfle_empirical_opts mo = *dfle_router_empirical_opts(p->member[0]);
    *out = NULL;
    if (!(isfinite(f) && f > 0))
        return dfle_error_set(err, DFLE_EINVAL, "router.population: a flow's volume factor must "
                              "be > 0 (got %g)", f);
    mo.M0 = p->M0 * f;
    return dfle_router_new_empirical(&mo, out, err);
}

size_t dfle_population_size(const dfle_population *p) { return p->q; }
dfle_router *dfle_population_member(const dfle_population *p, size_t j) { return p->member[j]; }
double dfle_population_rate(const dfle_population *p, size_t j) { return p->rate[j]; }
double dfle_population_factor(const dfle_population *p, size_t j) { return p->f[j]; }
double dfle_population_frequency(const dfle_population *p) { return p->opts.frequency; }
const dfle_population_opts *dfle_population_get_opts(const dfle_population *p)
{
    return &p->opts;
}
