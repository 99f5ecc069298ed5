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
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/router_empirical.h"

#define MAX_ORDER 64

struct dfle_population {
    dfle_population_opts opts;
    double M0, mu, tau_y; /* the base router's [m^(3-2 gamma)], [Pa s], [Pa] */
    double *table[3];     /* owned copies of tables' values, then weights   */
    size_t q;
    dfle_router **member; /* q routers                                      */
    double *f, *g, *h;    /* factors on M0, mu, tau_y                       */
    double *w, *rate;     /* weight, rate lambda w [1/yr]                   */
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
    o->mu = o->tau_y = o->volume; /* zero width: fixed */
    o->mobility_order = 8;
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
    for (int k = 0; k < 3; k++)
        free(p->table[k]);
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

/* A distribution's parameters into all[n..]; `of` names a mobility
 * distribution ("mu": mu_sigma, ...), NULL the volume's (sigma, ...). */
static size_t dist_params(const dfle_dist *d, const char *of, dfle_param *all, size_t n)
{
    /* Names outlive the call (dfle_param holds the pointer). */
    static const char *const names[3][6] = {
        {"sigma", "median", "b", "f_min", "f_max", "table"},
        {"mu_sigma", "mu_median", "mu_b", "mu_f_min", "mu_f_max", "mu_table"},
        {"tau_y_sigma", "tau_y_median", "tau_y_b", "tau_y_f_min", "tau_y_f_max", "tau_y_table"}};
    const char *const *nm = names[of == NULL ? 0 : strcmp(of, "mu") == 0 ? 1 : 2];
    switch (d->kind) {
    case DFLE_DIST_LOGNORMAL:
        all[n++] = (dfle_param){nm[0], d->sigma, "", 0};
        all[n++] = (dfle_param){nm[1], d->median, "", 0};
        break;
    case DFLE_DIST_POWER_LAW:
        all[n++] = (dfle_param){nm[2], d->b, "", 0};
        all[n++] = (dfle_param){nm[3], d->f_min, "", 0};
        all[n++] = (dfle_param){nm[4], d->f_max, "", 0};
        break;
    case DFLE_DIST_UNIFORM:
        all[n++] = (dfle_param){nm[3], d->f_min, "", 0};
        all[n++] = (dfle_param){nm[4], d->f_max, "", 0};
        break;
    default:
        if (of != NULL)
            all[n++] = (dfle_param){nm[5], (double)d->n, "", 0}; /* a table: its entries */
        break;
    }
    return n;
}

static size_t population_params(const void *state, dfle_param *out, size_t cap)
{
    const dfle_population *p = state;
    const dfle_dist *d = &p->opts.volume;
    /* The members' parameters at f = 1 (M0 as given), then the
     * population's own. */
    dfle_param all[48];
    size_t n = dfle_router_params(p->member[0], all, 16);
    if (n > 16)
        n = 16;
    for (size_t k = 0; k < n; k++) {
        /* The members' values are these times their factors. */
        if (strcmp(all[k].name, "M0") == 0)
            all[k].value = p->M0;
        else if (strcmp(all[k].name, "mu") == 0)
            all[k].value = p->mu;
        else if (strcmp(all[k].name, "tau_y") == 0)
            all[k].value = p->tau_y;
    }
    all[n++] = (dfle_param){"frequency", p->opts.frequency, "1/yr", 0};
    all[n++] = (dfle_param){"order", (double)p->q, "", 0};
    n = dist_params(d, NULL, all, n);
    if (!dfle_dist_is_point(&p->opts.mu))
        n = dist_params(&p->opts.mu, "mu", all, n);
    if (!dfle_dist_is_point(&p->opts.tau_y))
        n = dist_params(&p->opts.tau_y, "tau_y", all, n);
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

/* A copy of d's table owned by *own (d then points at it). */
static int own_table(dfle_dist *d, double **own)
{
    if (d->kind != DFLE_DIST_TABLE || d->n == 0)
        return DFLE_OK;
    *own = malloc(2 * d->n * sizeof **own);
    if (*own == NULL)
        return DFLE_ENOMEM;
    memcpy(*own, d->values, d->n * sizeof **own);
    memcpy(*own + d->n, d->weights, d->n * sizeof **own);
    d->values = *own;
    d->weights = *own + d->n;
    return DFLE_OK;
}

/* d checked, its messages naming `what` ("mu": "population: mu: ..."). */
static int check_named(const dfle_dist *d, const char *what, dfle_error *err)
{
    dfle_error e;
    int st = dfle_dist_check(d, &e);
    if (st != DFLE_OK) {
        const char *msg = strncmp(e.msg, "population: ", 12) == 0 ? e.msg + 12 : e.msg;
        return dfle_error_set(err, st, "population: %s: %s", what, msg);
    }
    return DFLE_OK;
}

static size_t nodes_cap(const dfle_dist *d, size_t order)
{
    return d->kind == DFLE_DIST_TABLE ? d->n : dfle_dist_is_point(d) ? 1 : order;
}

int dfle_router_new_population(const dfle_router *base, const dfle_population_opts *o,
                               dfle_router **out, dfle_error *err)
{
    const dfle_empirical_opts *eo = base != NULL ? dfle_router_empirical_opts(base) : NULL;
    const dfle_dist *dist[3];
    dfle_population *p;
    size_t cap[3], n[3] = {0, 0, 0}, total;
    double *x[3] = {NULL, NULL, NULL};
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
    if ((!dfle_dist_is_point(&o->mu) || !dfle_dist_is_point(&o->tau_y)) &&
        (o->mobility_order < 1 || o->mobility_order > MAX_ORDER))
        return dfle_error_set(err, DFLE_EINVAL, "router.population: mobility_order must be a "
                              "whole number in [1, %d] (got %zu)", MAX_ORDER, o->mobility_order);
    if ((st = dfle_dist_check(&o->volume, err)) != DFLE_OK)
        return st;
    if ((st = check_named(&o->mu, "mu", err)) != DFLE_OK ||
        (st = check_named(&o->tau_y, "tau_y", err)) != DFLE_OK)
        return st;
    p = calloc(1, sizeof *p);
    if (p == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "router.population: out of memory");
    p->opts = *o;
    p->M0 = eo->M0, p->mu = eo->mu, p->tau_y = eo->tau_y;
    dist[0] = &p->opts.volume, dist[1] = &p->opts.mu, dist[2] = &p->opts.tau_y;
    for (int k = 0; k < 3; k++)
        if (own_table((dfle_dist *)dist[k], &p->table[k]) != DFLE_OK) {
            population_destroy(p);
            return dfle_error_set(err, DFLE_ENOMEM, "router.population: out of memory");
        }
    cap[0] = nodes_cap(dist[0], o->order);
    cap[1] = nodes_cap(dist[1], o->mobility_order);
    cap[2] = nodes_cap(dist[2], o->mobility_order);
    total = cap[0] * cap[1] * cap[2];
    if (total > DFLE_POPULATION_MAX_FLOWS) {
        population_destroy(p);
        return dfle_error_set(err, DFLE_EINVAL, "router.population: %zu x %zu x %zu flows (volume "
                              "x mu x tau_y) is more than %d: lower order or mobility_order",
                              cap[0], cap[1], cap[2], DFLE_POPULATION_MAX_FLOWS);
    }
    p->f = malloc((5 * total + 2 * (cap[0] + cap[1] + cap[2])) * sizeof *p->f);
    p->member = calloc(total, sizeof *p->member);
    if (p->f == NULL || p->member == NULL) {
        population_destroy(p);
        return dfle_error_set(err, DFLE_ENOMEM, "router.population: out of memory");
    }
    p->g = p->f + total, p->h = p->g + total, p->w = p->h + total, p->rate = p->w + total;
    x[0] = p->rate + total, x[1] = x[0] + 2 * cap[0], x[2] = x[1] + 2 * cap[1];
    {
        const size_t order[3] = {o->order, dfle_dist_is_point(dist[1]) ? 1 : o->mobility_order,
                                 dfle_dist_is_point(dist[2]) ? 1 : o->mobility_order};
        for (int k = 0; k < 3; k++)
            if ((st = dfle_dist_quadrature(dist[k], order[k], x[k], x[k] + cap[k], &n[k], err)) !=
                DFLE_OK) {
                population_destroy(p);
                return st;
            }
    }
    /* The tensor product, volume outermost: a population whose mobility
     * does not vary has the members of a volume-only one, in its order. */
    p->q = 0;
    for (size_t a = 0; a < n[0]; a++)
        for (size_t b = 0; b < n[1]; b++)
            for (size_t c = 0; c < n[2]; c++) {
                const size_t j = p->q;
                dfle_empirical_opts mo = *eo;
                p->f[j] = x[0][a], p->g[j] = x[1][b], p->h[j] = x[2][c];
                p->w[j] = x[0][cap[0] + a] * x[1][cap[1] + b] * x[2][cap[2] + c];
                p->rate[j] = o->frequency * p->w[j];
                mo.M0 = eo->M0 * p->f[j];
                mo.mu = eo->mu * p->g[j];
                mo.tau_y = eo->tau_y * p->h[j];
                if ((st = dfle_router_new_empirical(&mo, &p->member[j], err)) != DFLE_OK) {
                    population_destroy(p); /* the members made so far: q of them */
                    return st;
                }
                p->q++;
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

int dfle_population_new_flow(const dfle_population *p, double f, double g_mu, double g_tau,
                             dfle_router **out, dfle_error *err)
{
    dfle_empirical_opts mo = *dfle_router_empirical_opts(p->member[0]);
    *out = NULL;
    if (!(isfinite(f) && f > 0 && isfinite(g_mu) && g_mu > 0 && isfinite(g_tau) && g_tau > 0))
        return dfle_error_set(err, DFLE_EINVAL, "router.population: a flow's factors must be "
                              "> 0 (got volume %g, mu %g, tau_y %g)", f, g_mu, g_tau);
    mo.M0 = p->M0 * f;
    mo.mu = p->mu * g_mu;
    mo.tau_y = p->tau_y * g_tau;
    return dfle_router_new_empirical(&mo, out, err);
}

size_t dfle_population_size(const dfle_population *p) { return p->q; }
dfle_router *dfle_population_member(const dfle_population *p, size_t j) { return p->member[j]; }
double dfle_population_rate(const dfle_population *p, size_t j) { return p->rate[j]; }
double dfle_population_factor(const dfle_population *p, size_t j) { return p->f[j]; }
double dfle_population_mu_factor(const dfle_population *p, size_t j) { return p->g[j]; }
double dfle_population_tau_y_factor(const dfle_population *p, size_t j) { return p->h[j]; }
double dfle_population_frequency(const dfle_population *p) { return p->opts.frequency; }
const dfle_population_opts *dfle_population_get_opts(const dfle_population *p)
{
    return &p->opts;
}
