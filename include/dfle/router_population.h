/*
 * router_population.h - debris flows as a population: a distribution of
 * event volumes with a frequency, in place of one characteristic flow.
 *
 * The paper routes one characteristic flow again and again (Sect. 2.3);
 * a catchment sees many small flows and few large ones.  A population
 * router holds the volume distribution as a factor f on the member
 * router's M0 (so M = f M0 (1e-6 A)^gamma: the volume-area scaling of
 * each head stays as it is, the spread sits on top), and a frequency
 * lambda [events/yr].  The erosion it stands for is the expectation
 *
 *   E_df = lambda sum_j w_j E_df(flow with f_j)
 *
 * over q quadrature flows (f_j, w_j, sum w_j = 1), each routed with its
 * own runout.  The flows' mobility may vary too: factors on the member
 * router's viscosity mu and yield strength tau_y, each with its own
 * distribution (independent of the volume and of each other), make the
 * quadrature the tensor product of the three (q_V q_mu q_tau flows;
 * a zero-width distribution adds no nodes).  With a population, k_df is the erosion of one event
 * (k_df's m/yr times 1 yr/event) and lambda brings the frequency back:
 * lambda = 1 and a zero-width distribution give the characteristic flow
 * exactly.
 *
 * The quadrature follows the distribution:
 *  - log-normal, ln f ~ N(ln median, sigma^2): Gauss-Hermite in ln f;
 *  - truncated power law, p(f) ~ f^(-b) on [f_min, f_max]: Gauss-
 *    Legendre in ln f, the weights carrying f^(1-b);
 *  - uniform on [f_min, f_max]: Gauss-Legendre in f;
 *  - a table of factors and weights (a measured inventory): as given.
 *
 * The model (model.h) sees a population through the router's population
 * op (router.h) and evaluates the law for every member; the router's own
 * route op gives the population's summary (reach: the expected number of
 * flows a year going on at each node).
 */
#ifndef DFLE_ROUTER_POPULATION_H
#define DFLE_ROUTER_POPULATION_H

#include <stddef.h>
#include "dfle/router.h"

#ifdef __cplusplus
extern "C" {
#endif

enum dfle_dist_kind {
    DFLE_DIST_LOGNORMAL = 0, /* sigma, median                       */
    DFLE_DIST_POWER_LAW = 1, /* b, f_min, f_max                     */
    DFLE_DIST_UNIFORM = 2,   /* f_min, f_max                        */
    DFLE_DIST_TABLE = 3      /* n values and weights, as given       */
};

/* A distribution of the volume factor f [-] (M = f M0 (1e-6 A)^gamma). */
typedef struct dfle_dist {
    int kind;          /* enum dfle_dist_kind                               */
    double sigma;      /* log-normal: standard deviation of ln f, >= 0      */
    double median;     /* log-normal: median of f, > 0 (1)                   */
    double b;          /* power law: p(f) ~ f^(-b), any finite b             */
    double f_min;      /* power law and uniform: lower cut-off, > 0          */
    double f_max;      /* upper cut-off, >= f_min                            */
    size_t n;          /* table: number of entries                           */
    const double *values;  /* table: factors, > 0 (copied)                   */
    const double *weights; /* table: relative weights, >= 0, not all 0 (copied) */
} dfle_dist;

/* Check d (messages name the parameter); 0 or DFLE_EINVAL. */
int dfle_dist_check(const dfle_dist *d, dfle_error *err);

/* The quadrature of order q (q >= 1; a table gives its own n nodes and
 * ignores q): writes *n_out factors f[] and weights w[] (sum 1), both
 * with room for max(q, table n) values, in increasing f.  A distribution
 * of zero width (sigma = 0, f_min = f_max) gives one node of weight 1. */
int dfle_dist_quadrature(const dfle_dist *d, size_t q, double *f, double *w, size_t *n_out,
                         dfle_error *err);

/* E[f^k] in closed form (log-normal, power law, uniform: analytic;
 * table: the weighted sum). */
double dfle_dist_moment(const dfle_dist *d, double k);

/* Draw one factor from d with u uniform in (0, 1) (inverse CDF; a
 * log-normal takes a second uniform u2 for Box-Muller). */
double dfle_dist_draw(const dfle_dist *d, double u, double u2);

/* 1 if d has zero width (one value): sigma = 0, f_min = f_max, or a
 * table of one value. */
int dfle_dist_is_point(const dfle_dist *d);

typedef struct dfle_population_opts {
    dfle_dist volume;  /* the volume factor's distribution                */
    double frequency;  /* lambda: debris flows per year, > 0 (1)           */
    size_t order;      /* quadrature order q, 1..64 (8); tables use theirs */
    dfle_dist mu;      /* factor on the router's viscosity mu (zero width: fixed) */
    dfle_dist tau_y;   /* factor on its yield strength tau_y (zero width)  */
    size_t mobility_order; /* quadrature order of mu and tau_y, 1..64 (8)  */
} dfle_population_opts;

/* Most flows a population may have (the product of the three orders). */
#define DFLE_POPULATION_MAX_FLOWS 4096

void dfle_population_opts_default(dfle_population_opts *o);

/* A population of flows of the member router `base` (an empirical or a
 * process-based router; not taken over: the population makes its own
 * members from base's parameters, M0 times each factor). */
int dfle_router_new_population(const dfle_router *base, const dfle_population_opts *o,
                               dfle_router **out, dfle_error *err);

typedef struct dfle_population dfle_population;

/* The population of router rt, or NULL for any other router. */
const dfle_population *dfle_router_get_population(const dfle_router *rt);

size_t dfle_population_size(const dfle_population *p);
/* Member j's router (j < size) and its rate lambda w_j [events/yr]. */
dfle_router *dfle_population_member(const dfle_population *p, size_t j);
double dfle_population_rate(const dfle_population *p, size_t j);
double dfle_population_factor(const dfle_population *p, size_t j);
/* Member j's factors on mu and tau_y (1 where these do not vary). */
double dfle_population_mu_factor(const dfle_population *p, size_t j);
double dfle_population_tau_y_factor(const dfle_population *p, size_t j);
double dfle_population_frequency(const dfle_population *p);
const dfle_population_opts *dfle_population_get_opts(const dfle_population *p);

/* A router for one flow of the population with factors f on the volume,
 * g_mu on mu and g_tau on tau_y (all > 0): the base router with M0 f,
 * mu g_mu and tau_y g_tau.  The caller frees it. */
int dfle_population_new_flow(const dfle_population *p, double f, double g_mu, double g_tau,
                             dfle_router **out, dfle_error *err);

/* Fold member j's routed flow `mf` into the population's summary `sum`
 * (cleared by the caller for j = 0): reach gains rate_j * mf->reach, the
 * other fields become rate-weighted means over the members going on;
 * runout_end is the largest.  Call for j = 0 .. size-1 in turn. */
void dfle_population_accumulate(const dfle_population *p, size_t j, const dfle_flow *mf,
                                dfle_flow *sum);

#ifdef __cplusplus
}
#endif
#endif
