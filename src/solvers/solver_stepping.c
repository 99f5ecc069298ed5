/*
 * solver_stepping.c - the one loop every time-stepping run goes through
 * (solver.h, dfle_stepping_loop), and the 1D model's stepper on it.
 *
 * A step is whatever a stepper's advance does; the loop around it (the
 * steady-state test, time and step limits, the interrupt, landing on
 * record times and on the end) is the same for all, so the 1D methods
 * and a landscape cannot drift apart in what "steady", "max_time" or an
 * interrupt means.
 */
#include <assert.h>
#include <math.h>
#include <string.h>

#include "solvers/solver_internal.h"

/* Steps between progress reports of a 1D run. */
#define PROGRESS_EVERY 256

/* Take every record time reached at time t. */
static int take_records(const dfle_stepping_ops *ops, void *self,
                        const dfle_stepping_limits *lim, double t, dfle_stepping_tally *tally,
                        dfle_error *err)
{
    int st;
    while (tally->n_recorded < lim->n_record &&
           t >= lim->record_times[tally->n_recorded] * (1.0 - 1e-12)) {
        if (ops->record != NULL &&
            (st = ops->record(self, tally->n_recorded, t, err)) != DFLE_OK)
            return st;
        tally->n_recorded++;
    }
    return DFLE_OK;
}

int dfle_stepping_loop(const dfle_stepping_ops *ops, void *self,
                       const dfle_stepping_limits *lim, dfle_stepping_tally *tally,
                       dfle_error *err)
{
    int st;

    memset(tally, 0, sizeof *tally);
    tally->reason = -1;
    tally->dt_min = INFINITY;
    if ((st = take_records(ops, self, lim, 0.0, tally, err)) != DFLE_OK)
        return st;
    for (;;) {
        double dt = 0.0, limit;
        int steady = 0;

        if ((st = ops->prepare(self, tally, &steady, err)) != DFLE_OK)
            return st;
        if (steady) {
            tally->reason = DFLE_STOP_STEADY;
            break;
        }
        /* Tolerate round-off in the accumulated time. */
        if (tally->time >= lim->max_time * (1.0 - 1e-12)) {
            tally->reason = DFLE_STOP_TIME;
            break;
        }
        if (tally->steps >= lim->max_steps) {
            tally->reason = DFLE_STOP_STEPS;
            break;
        }
        if (lim->interrupt != NULL && *lim->interrupt) {
            tally->reason = DFLE_STOP_INTERRUPTED;
            break;
        }
        /* Land exactly on the end of the run and on every record time. */
        limit = lim->max_time - tally->time;
        if (tally->n_recorded < lim->n_record &&
            lim->record_times[tally->n_recorded] - tally->time < limit)
            limit = lim->record_times[tally->n_recorded] - tally->time;
        if ((st = ops->advance(self, limit, &dt, err)) != DFLE_OK)
            return st;
        assert(dt > 0 && dt <= limit);
        tally->time += dt;
        tally->steps++;
        tally->dt_min = fmin(tally->dt_min, dt);
        tally->dt_max = fmax(tally->dt_max, dt);
        if ((st = take_records(ops, self, lim, tally->time, tally, err)) != DFLE_OK)
            return st;
        if (ops->after_step != NULL && (st = ops->after_step(self, tally, dt, err)) != DFLE_OK)
            return st;
    }
    if (tally->dt_min > tally->dt_max)
        tally->dt_min = 0.0;
    return DFLE_OK;
}

/* ---------------------------------------------------------------- */
/* The 1D model's stepper                                           */
/* ---------------------------------------------------------------- */

/* Rough completion estimate: the larger of the time used and how far the
 * rate ratio has fallen (on a log scale) from its start towards tol. */
static double progress_fraction(double t, double max_time, double r0, double r, double tol)
{
    double f = t / max_time;
    if (tol > 0 && r0 > tol && r > 0) {
        double fc = log(r0 / r) / log(r0 / tol);
        if (fc > f)
            f = fc;
    }
    return f < 0 ? 0 : f > 1 ? 1 : f;
}

/* Time-varying uplift U(t) (doc/laws.md): the run's uplift callback,
 * if any, sets U for the coming step, so forcing can change within a run
 * instead of only between runs (m:set_U). */
int dfle_stepping_uplift(dfle_model *m, const dfle_run_opts *o, dfle_error *err)
{
    double U = dfle_model_U(m);
    const double t = dfle_model_time(m);
    int st;
    if (o->uplift == NULL)
        return DFLE_OK;
    if ((st = o->uplift(o->uplift_ud, t, &U, err)) != DFLE_OK)
        return st;
    if (!(isfinite(U) && U > 0))
        return dfle_error_set(err, DFLE_EINVAL, "model: U(t) must be > 0 m/yr (got %g at t = %g yr)",
                              U, t);
    return dfle_model_set_U(m, U, err);
}

typedef struct model_stepper {
    dfle_model *m;
    const dfle_run_opts *o;
    dfle_advance_fn advance;
    void *state;
    dfle_run_result *res;
    double r, r0; /* max |dz/dt|/U now, and at the start */
} model_stepper;

static int model_prepare(void *self, const dfle_stepping_tally *so_far, int *steady,
                         dfle_error *err)
{
    model_stepper *s = self;
    int st;
    (void)so_far;
    if ((st = dfle_stepping_uplift(s->m, s->o, err)) != DFLE_OK)
        return st;
    if (!dfle_model_is_evaluated(s->m) && (st = dfle_model_evaluate(s->m, err)) != DFLE_OK)
        return st;
    s->r = dfle_model_rate_ratio(s->m);
    if (s->r0 < 0)
        s->r0 = s->r;
    s->res->nonpositive_slope_nodes += dfle_model_nonpositive_slopes(s->m);
    *steady = s->o->tol > 0 && s->r <= s->o->tol;
    return DFLE_OK;
}

static int model_advance(void *self, double dt_limit, double *dt, dfle_error *err)
{
    model_stepper *s = self;
    int st = s->advance(s->m, dt_limit, dt, s->state, err);
    if (st == DFLE_OK)
        dfle_model_advance_time(s->m, *dt);
    return st;
}

/* Copy z for a record time reached. */
static int model_record(void *self, size_t k, double t, dfle_error *err)
{
    model_stepper *s = self;
    const size_t n = dfle_model_size(s->m);
    (void)t;
    (void)err;
    memcpy(s->o->record_z + k * n, dfle_model_z(s->m), n * sizeof(double));
    return DFLE_OK;
}

static int model_after_step(void *self, const dfle_stepping_tally *so_far, double dt,
                            dfle_error *err)
{
    model_stepper *s = self;
    const dfle_run_opts *o = s->o;
    if (o->progress != NULL && so_far->steps % PROGRESS_EVERY == 0) {
        dfle_run_status rs = {
            .time = so_far->time, .max_time = o->max_time, .steps = so_far->steps, .dt = dt,
            .rate_ratio = s->r, .tol = o->tol,
            .fraction = progress_fraction(so_far->time, o->max_time, s->r0, s->r, o->tol),
        };
        if (o->progress(o->progress_ud, &rs) != 0)
            return dfle_error_set(err, DFLE_ECANCELED,
                                  "model: run stopped by the progress callback at t = %g yr",
                                  so_far->time);
    }
    return DFLE_OK;
}

static const dfle_stepping_ops model_stepping = {
    .iVersion = 1,
    .name = "model",
    .prepare = model_prepare,
    .advance = model_advance,
    .record = model_record,
    .after_step = model_after_step,
};

int dfle_stepping_run(dfle_model *m, const dfle_run_opts *o, dfle_advance_fn advance,
                      void *state, dfle_run_result *res, dfle_error *err)
{
    model_stepper s = {m, o, advance, state, res, 0.0, -1.0};
    const dfle_stepping_limits lim = {o->max_time, o->max_steps, o->interrupt, o->n_record,
                                      o->record_times};
    const size_t routings0 = dfle_model_routings(m);
    dfle_stepping_tally tally;
    int st = dfle_stepping_loop(&model_stepping, &s, &lim, &tally, err);

    res->n_recorded = tally.n_recorded;
    if (st != DFLE_OK)
        return st;
    /* Adds to res (a fallback run continues the tally); the step sizes
     * are this loop's. */
    res->reason = tally.reason;
    res->converged = res->reason == DFLE_STOP_STEADY;
    res->time += tally.time;
    res->steps += tally.steps;
    res->routings += dfle_model_routings(m) - routings0;
    res->rate_ratio = dfle_model_rate_ratio(m);
    res->dt_min = tally.dt_min;
    res->dt_max = tally.dt_max;
    return DFLE_OK;
}
