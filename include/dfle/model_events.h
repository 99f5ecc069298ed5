/*
 * model_events.h - debris flows of a population as events in time.
 *
 * The expected-rate model (router_population.h) erodes every node at
 * the population's mean rate.  Events are the other reading: in each
 * step of dt years the number of flows is Poisson(lambda dt), each
 * flow's volume factor is drawn from the population's distribution,
 * and each one, routed with its own runout over the profile as it is,
 * erodes a depth E_df(f) * 1 yr [m] (k_df is the erosion of one event
 * with a population).  Uplift and fluvial erosion act at their rates
 * over the step (forward Euler).  Over a long run the mean erosion rate
 * is the expected rate.
 *
 * The events come from one generator (GSL's MT19937) seeded by the
 * caller and drawn in the order of time, so a run is a function of its
 * seed alone: the same on any number of workers.
 */
#ifndef DFLE_MODEL_EVENTS_H
#define DFLE_MODEL_EVENTS_H

#include <stddef.h>
#include "dfle/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* E[0..n) [m]: the erosion of one debris flow of the model's population
 * with volume factor f, and factors g_mu, g_tau on mu and tau_y (all
 * > 0), routed over the model's current profile.  DFLE_EINVAL if the
 * model's router is not a population. */
int dfle_model_event_erosion(dfle_model *m, double f, double g_mu, double g_tau, double *E,
                             dfle_error *err);

/* The population of the model's router, or NULL. */
const struct dfle_population *dfle_model_population(const dfle_model *m);

typedef struct dfle_events_opts {
    double years;       /* how long, > 0 [yr]                               */
    double dt;          /* largest step, > 0 [yr]; a step is also held below
                         * the explicit limit of the fluvial and mean
                         * debris-flow rates (cfl L / |dE/dS|)               */
    unsigned long seed; /* of the event generator                            */
    int hold;           /* 1: the profile is held (statistics of the events on
                         * it; the model's state and time do not change)     */
} dfle_events_opts;

typedef struct dfle_events_result {
    size_t events;      /* debris flows drawn                                */
    size_t steps;
    double years;       /* simulated                                         */
} dfle_events_result;

/* Run events (src/solvers/solver_events.c: the stepping loop of
 * solver.h).  sum and sum2 (n values each, may be NULL) receive, per
 * node, the sum of the events' erosion depths [m] and of their squares
 * [m^2]: sum / years is the mean rate, sqrt(sum2) / years its standard
 * error (the variance of a compound Poisson sum). */
int dfle_run_events(dfle_model *m, const dfle_events_opts *o, dfle_events_result *res,
                    double *sum, double *sum2, dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
