/*
 * solver_stepping.c - the loop every time-stepping method runs: a step
 * is whatever the method's advance function does; the loop around it
 * (uplift, the steady-state test, time and step limits, records,
 * progress) is the same for all, so the methods cannot drift apart in
 * what "steady" or "max_time" means.
 */
#include <assert.h>
#include <math.h>
#include <string.h>

#include "solvers/solver_internal.h"

/* Steps between progress reports. */
#define PROGRESS_EVERY 256

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

/* Copy z for every record time reached at time t of the run. */
static void take_records(dfle_model *m, const dfle_run_opts *o, double t, dfle_run_result *res)
{
    const size_t n = dfle_model_size(m);
    while (res->n_recorded < o->n_record &&
           t >= o->record_times[res->n_recorded] * (1.0 - 1e-12)) {
        memcpy(o->record_z + res->n_recorded * n, dfle_model_z(m), n * sizeof(double));
        res->n_recorded++;
    }
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

int dfle_stepping_run(dfle_model *m, const dfle_run_opts *o, dfle_advance_fn advance,
                      void *state, dfle_run_result *res, dfle_error *err)
{
    double t = 0.0, r0 = -1.0;
    size_t steps = 0, routings0 = dfle_model_routings(m);
    int st;

    res->dt_min = INFINITY;
    res->dt_max = 0.0;
    take_records(m, o, 0.0, res);
    for (;;) {
        double r, dt, limit;

        if ((st = dfle_stepping_uplift(m, o, err)) != DFLE_OK)
            return st;
        if (!dfle_model_is_evaluated(m) && (st = dfle_model_evaluate(m, err)) != DFLE_OK)
            return st;
        r = dfle_model_rate_ratio(m);
        if (r0 < 0)
            r0 = r;
        res->nonpositive_slope_nodes += dfle_model_nonpositive_slopes(m);
        if (o->tol > 0 && r <= o->tol) {
            res->reason = DFLE_STOP_STEADY;
            break;
        }
        /* Tolerate round-off in the accumulated time. */
        if (t >= o->max_time * (1.0 - 1e-12)) {
            res->reason = DFLE_STOP_TIME;
            break;
        }
        if (steps >= o->max_steps) {
            res->reason = DFLE_STOP_STEPS;
            break;
        }
        if (o->interrupt != NULL && *o->interrupt) {
            res->reason = DFLE_STOP_INTERRUPTED;
            break;
        }
        /* Land exactly on the end of the run and on every record time. */
        limit = o->max_time - t;
        if (res->n_recorded < o->n_record && o->record_times[res->n_recorded] - t < limit)
            limit = o->record_times[res->n_recorded] - t;
        if ((st = advance(m, limit, &dt, state, err)) != DFLE_OK)
            return st;
        assert(dt > 0 && dt <= limit);
        t += dt;
        dfle_model_advance_time(m, dt);
        steps++;
        if (dt < res->dt_min)
            res->dt_min = dt;
        if (dt > res->dt_max)
            res->dt_max = dt;
        take_records(m, o, t, res);
        if (o->progress != NULL && steps % PROGRESS_EVERY == 0) {
            dfle_run_status s = {
                .time = t, .max_time = o->max_time, .steps = steps, .dt = dt,
                .rate_ratio = r, .tol = o->tol,
                .fraction = progress_fraction(t, o->max_time, r0, r, o->tol),
            };
            if (o->progress(o->progress_ud, &s) != 0)
                return dfle_error_set(err, DFLE_ECANCELED,
                                      "model: run stopped by the progress callback at t = %g yr", t);
        }
    }
    res->converged = res->reason == DFLE_STOP_STEADY;
    res->time += t;
    res->steps += steps;
    res->routings += dfle_model_routings(m) - routings0;
    res->rate_ratio = dfle_model_rate_ratio(m);
    if (res->dt_min > res->dt_max)
        res->dt_min = 0.0;
    return DFLE_OK;
}
