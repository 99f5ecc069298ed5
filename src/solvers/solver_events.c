/*
 * solver_events.c - debris flows of a population as events in time
 * (model_events.h), stepped by the one stepping loop (solver.h).
 *
 * A step of dt: N ~ Poisson(lambda dt) flows, each with a volume factor
 * drawn from the population's distribution and routed over the profile
 * at the start of the step; then z += dt (U - E_f) - (the events'
 * depths).  The generator is drawn in the order of time only (the count
 * of a step, then two uniforms per event for its volume, and two for
 * each of mu and tau_y where they vary), so a run is fixed by its seed.
 */
#include <math.h>
#include <stdlib.h>

#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>

#include "dfle/model_events.h"
#include "dfle/router_population.h"
#include "dfle/solver.h"

typedef struct events_run {
    dfle_model *m;
    const dfle_events_opts *o;
    const dfle_population *pop;
    gsl_rng *rng;
    double *depth, *E; /* the step's event depths, one event's [m] */
    double *sum, *sum2;
    size_t events;
} events_run;

static int events_prepare(void *self, const dfle_stepping_tally *so_far, int *steady,
                          dfle_error *err)
{
    events_run *r = self;
    (void)so_far;
    *steady = 0;
    return dfle_model_is_evaluated(r->m) ? DFLE_OK : dfle_model_evaluate(r->m, err);
}

/* The explicit limit of the rates: cfl L / |dE/dS| over the nodes. */
static int explicit_limit(dfle_model *m, double *dt, dfle_error *err)
{
    const double *c, *L = dfle_model_flow_length(m);
    int st = dfle_model_celerity(m, &c, err);
    if (st != DFLE_OK)
        return st;
    for (size_t i = 0; i < dfle_model_size(m); i++)
        if (c[i] > 0)
            *dt = fmin(*dt, dfle_model_cfl(m) * L[i] / c[i]);
    return DFLE_OK;
}

static int events_advance(void *self, double dt_limit, double *dt_out, dfle_error *err)
{
    events_run *r = self;
    dfle_model *m = r->m;
    const size_t n = dfle_model_size(m);
    const dfle_population_opts *po = dfle_population_get_opts(r->pop);
    /* Mobility that does not vary draws nothing: the stream of a
     * volume-only population is the same with or without these. */
    const int vary_mu = !dfle_dist_is_point(&po->mu), vary_tau = !dfle_dist_is_point(&po->tau_y);
    double dt = fmin(r->o->dt, dt_limit);
    unsigned count;
    int st;

    if (!r->o->hold && (st = explicit_limit(m, &dt, err)) != DFLE_OK)
        return st;
    count = gsl_ran_poisson(r->rng, dfle_population_frequency(r->pop) * dt);
    for (size_t i = 0; i < n; i++)
        r->depth[i] = 0.0;
    for (unsigned e = 0; e < count; e++) {
        const double u1 = gsl_rng_uniform_pos(r->rng), u2 = gsl_rng_uniform_pos(r->rng);
        const double f = dfle_dist_draw(&po->volume, u1, u2);
        double g_mu = 1.0, g_tau = 1.0;
        if (vary_mu) {
            const double v1 = gsl_rng_uniform_pos(r->rng), v2 = gsl_rng_uniform_pos(r->rng);
            g_mu = dfle_dist_draw(&po->mu, v1, v2);
        }
        if (vary_tau) {
            const double v1 = gsl_rng_uniform_pos(r->rng), v2 = gsl_rng_uniform_pos(r->rng);
            g_tau = dfle_dist_draw(&po->tau_y, v1, v2);
        }
        if ((st = dfle_model_event_erosion(m, f, g_mu, g_tau, r->E, err)) != DFLE_OK)
            return st;
        for (size_t i = 0; i < n; i++) {
            r->depth[i] += r->E[i];
            if (r->sum != NULL)
                r->sum[i] += r->E[i];
            if (r->sum2 != NULL)
                r->sum2[i] += r->E[i] * r->E[i];
        }
    }
    r->events += count;
    if (!r->o->hold) {
        const double *E_f = dfle_model_field(m, DFLE_FIELD_E_F, err);
        double *z = dfle_model_z(m);
        const double U = dfle_model_U(m);
        if (E_f == NULL)
            return DFLE_ENUMERIC;
        for (size_t i = 0; i < n; i++)
            if (!dfle_model_is_base(m, i))
                z[i] += dt * (U - E_f[i]) - r->depth[i];
        dfle_model_touch(m);
        dfle_model_advance_time(m, dt);
    }
    *dt_out = dt;
    return DFLE_OK;
}

static const dfle_stepping_ops events_ops = {
    .iVersion = 1,
    .name = "events",
    .prepare = events_prepare,
    .advance = events_advance,
};

int dfle_run_events(dfle_model *m, const dfle_events_opts *o, dfle_events_result *res,
                    double *sum, double *sum2, dfle_error *err)
{
    const size_t n = dfle_model_size(m);
    events_run r = {.m = m, .o = o, .pop = dfle_model_population(m), .sum = sum, .sum2 = sum2};
    dfle_stepping_limits lim = {0};
    dfle_stepping_tally tally;
    int st;

    res->events = res->steps = 0;
    res->years = 0.0;
    if (r.pop == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "events: the model's router must be a population "
                              "(dfle.router.population)");
    if (!(isfinite(o->years) && o->years > 0))
        return dfle_error_set(err, DFLE_EINVAL, "events: years must be > 0 (got %g)", o->years);
    if (!(isfinite(o->dt) && o->dt > 0))
        return dfle_error_set(err, DFLE_EINVAL, "events: dt must be > 0 yr (got %g)", o->dt);
    for (size_t i = 0; i < n; i++) {
        if (sum != NULL)
            sum[i] = 0.0;
        if (sum2 != NULL)
            sum2[i] = 0.0;
    }
    r.rng = gsl_rng_alloc(gsl_rng_mt19937);
    r.depth = malloc(2 * n * sizeof *r.depth);
    if (r.rng == NULL || r.depth == NULL) {
        gsl_rng_free(r.rng);
        free(r.depth);
        return dfle_error_set(err, DFLE_ENOMEM, "events: out of memory");
    }
    r.E = r.depth + n;
    gsl_rng_set(r.rng, o->seed);
    lim.max_time = o->years;
    lim.max_steps = (size_t)-1;
    st = dfle_stepping_loop(&events_ops, &r, &lim, &tally, err);
    res->events = r.events;
    res->steps = tally.steps;
    res->years = tally.time;
    gsl_rng_free(r.rng);
    free(r.depth);
    return st;
}
