/*
 * landscape_run.c - runs of a landscape: transients and steady states.
 *
 * What steady means for a landscape (doc/landscape.md).  On a 1D channel
 * the run stops when max |dz/dt| <= tol U.  In 2D the drainage network
 * itself moves: divides migrate, a cell on a divide flips between two
 * receivers, and a few cells keep |dz/dt| of order U long after the
 * rest is still (fastscapelib's 250^2 landscape with n = 2.33 has max
 * |dz/dt|/U of about 3 after 1.6e7 yr while the mean is 1.3e-2).  So a
 * landscape is steady when
 *   - at least a fraction `quantile` (0.99) of its non-base data cells
 *     has |dz/dt| <= tol U (tol = 1e-3), and
 *   - no cell has changed its receiver for `stable_steps` (5) routings
 *     in a row (the network has stopped changing).
 * Both are reported as the run goes (q_ratio, frac_above, rcv_changes,
 * stable); a run that reaches max_time or max_steps without meeting them
 * ends with converged = 0 and a note saying which part failed and by how
 * much.
 *
 * Methods: IMPLICIT, backward Euler with a fixed step (landscape_step.c);
 * EXPLICIT, forward Euler with the CFL step (the reference); DIRECT, the
 * steady state of a fixed network node by node (slopes from the heads
 * down, elevations from base level up), re-routed until the network
 * stops changing, then judged by the same criterion on the evaluated
 * rates; when rounds do not settle (a network that cycles) the run goes
 * on by implicit steps and says so.
 */
#include "landscape/landscape_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DIRECT_ROUNDS 60

void dfle_landscape_run_opts_default(dfle_landscape_run_opts *o)
{
    memset(o, 0, sizeof *o);
    o->method = DFLE_METHOD_AUTO;
    o->tol = 1e-3;
    o->quantile = 0.99;
    o->stable_steps = 5;
    o->rcv_tol = 0.005;
    o->max_time = 1e7;
    o->max_steps = 1000000;
    o->dt = 1000.0;
    o->cfl = 0.5;
    o->progress_every = 16;
}

static int check_run_opts(const dfle_landscape_run_opts *o, dfle_error *err)
{
    if (!(isfinite(o->years) && o->years >= 0))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: years must be >= 0 (got %g)",
                              o->years);
    if (!(isfinite(o->tol) && o->tol > 0))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: tol must be > 0 (got %g)", o->tol);
    if (!(o->quantile > 0 && o->quantile <= 1))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: quantile must be in (0, 1] (got "
                              "%g)", o->quantile);
    if (!(isfinite(o->max_time) && o->max_time > 0))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: max_time must be > 0 yr (got %g)",
                              o->max_time);
    if (!(isfinite(o->dt) && o->dt > 0))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: dt must be > 0 yr (got %g)", o->dt);
    if (!(o->cfl > 0 && o->cfl <= 1))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: cfl must be in (0, 1] (got %g)",
                              o->cfl);
    if (o->max_steps == 0)
        return dfle_error_set(err, DFLE_EINVAL, "landscape: max_steps must be >= 1");
    if (o->method != DFLE_METHOD_AUTO && o->method != DFLE_METHOD_IMPLICIT &&
        o->method != DFLE_METHOD_EXPLICIT && o->method != DFLE_METHOD_DIRECT)
        return dfle_error_set(err, DFLE_EINVAL, "landscape: method %d is not one of explicit, "
                              "implicit, direct, auto", o->method);
    if (!(o->rcv_tol >= 0 && o->rcv_tol < 1))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: rcv_tol must be in [0, 1) (got %g)",
                              o->rcv_tol);
    if (o->method == DFLE_METHOD_DIRECT && o->years > 0)
        return dfle_error_set(err, DFLE_EINVAL, "landscape: method 'direct' finds steady "
                              "states only; a transient (years) needs 'implicit' or 'explicit'");
    return DFLE_OK;
}

/* Call on_record for every record time reached at time t of the run. */
static int take_records(dfle_landscape *ls, const dfle_landscape_run_opts *o, double t,
                        dfle_landscape_result *res, dfle_error *err)
{
    while (res->n_recorded < o->n_record &&
           t >= o->record_times[res->n_recorded] * (1.0 - 1e-12)) {
        if (o->on_record != NULL &&
            o->on_record(o->on_record_ud, ls, res->n_recorded, ls->time) != 0)
            return dfle_error_set(err, DFLE_ECANCELED, "landscape: run stopped while recording "
                                  "at t = %g yr", t);
        res->n_recorded++;
    }
    return DFLE_OK;
}

static int steady_met(const dfle_landscape_run_opts *o, const dfle_landscape_status *st)
{
    return st->frac_above <= 1.0 - o->quantile + 1e-12 && st->stable >= o->stable_steps;
}

/* Why a steady run has not stopped, in words. */
static void explain(const dfle_landscape_run_opts *o, const dfle_landscape_status *st,
                    char *buf, size_t cap)
{
    int ok_rates = st->frac_above <= 1.0 - o->quantile + 1e-12;
    int ok_net = st->stable >= o->stable_steps;
    snprintf(buf, cap, "not steady: %.3g%% of the cells have |dz/dt| > tol U (allowed %.3g%%; "
             "the %g quantile of |dz/dt|/U is %.3g, the mean %.3g, the max %.3g)%s; %s",
             100 * st->frac_above, 100 * (1 - o->quantile), o->quantile, st->q_ratio,
             st->mean_ratio, st->max_ratio, ok_rates ? " - met" : "",
             ok_net ? "the network is stable"
                    : st->rcv_changes > 0 ? "receivers still change (divides migrate)"
                                          : "the network has not been stable long enough");
}

static double fraction(const dfle_landscape_run_opts *o, double t, double max_time, double r0,
                       double r)
{
    double f = t / max_time;
    if (o->years <= 0 && r0 > o->tol && r > 0) {
        double fc = log(r0 / r) / log(r0 / o->tol);
        f = fc > f ? fc : f;
    }
    return f < 0 ? 0 : f > 1 ? 1 : f;
}

/* Rounds of the direct method; DFLE_EFIT (with why) when they do not
 * settle or a cell has no steady slope, the state then as it was. */
static int run_direct(dfle_landscape *ls, const dfle_landscape_run_opts *o,
                      dfle_landscape_result *res, dfle_landscape_status *st, dfle_error *err)
{
    size_t rounds = 0, limit = o->max_steps < DIRECT_ROUNDS ? o->max_steps : DIRECT_ROUNDS;
    int s;

    res->method = DFLE_METHOD_DIRECT;
    ls->stable = 0;
    ls->routed = 0; /* count from a routing of this state */
    for (;;) {
        if ((s = ls_route(ls, err)) != DFLE_OK)
            return s;
        /* Settled when this round's surface routes as the last did (but
         * for the few divide cells rcv_tol allows). */
        if (rounds > 0 && ls->stable > 0)
            break;
        if (rounds >= limit)
            return dfle_error_set(err, DFLE_EFIT, "direct: the network still changed after "
                                  "%zu rounds (%zu cells changed receiver in the last)", rounds,
                                  ls->rcv_changes);
        if (o->interrupt != NULL && *o->interrupt)
            return DFLE_OK;
        if ((s = ls_direct_round(ls, err)) != DFLE_OK)
            return s;
        rounds++;
        if (o->on_step != NULL) {
            st->steps = rounds;
            if (o->on_step(o->on_step_ud, ls, st) != 0)
                return dfle_error_set(err, DFLE_ECANCELED, "landscape: run stopped by its "
                                      "step callback");
        }
    }
    /* One more round on this routing, kept: the steady state of the
     * network that its own surface routes to, but for the few divide
     * cells rcv_tol allows (a flipped divide cell moves the areas of two
     * whole flow paths, so the state is judged on the network it was
     * solved on, not on a re-routing that may flip them back). */
    if ((s = ls_direct_round(ls, err)) != DFLE_OK)
        return s;
    ls->routed = 1;
    st->steps = rounds + 1;
    ls->stable = o->stable_steps;
    return DFLE_OK;
}

int dfle_landscape_run(dfle_landscape *ls, const dfle_landscape_run_opts *o,
                       dfle_landscape_result *res, dfle_error *err)
{
    dfle_landscape_status st;
    const int transient = o->years > 0;
    const double max_time = transient ? o->years : o->max_time;
    size_t steps = 0, routings0 = ls->routings;
    double t = 0.0, r0 = -1.0;
    int method = o->method, s;

    memset(res, 0, sizeof *res);
    memset(&st, 0, sizeof st);
    if ((s = check_run_opts(o, err)) != DFLE_OK)
        return s;
    ls->rcv_tol = o->rcv_tol;
    if (method == DFLE_METHOD_AUTO)
        method = transient ? DFLE_METHOD_IMPLICIT : DFLE_METHOD_DIRECT;
    res->method = method;
    res->dt_min = INFINITY;
    st.max_time = max_time;
    if ((s = ls_update_fields(ls, 0, err)) != DFLE_OK)
        return s;
    if (o->on_step != NULL && o->on_step(o->on_step_ud, ls, &st) != 0)
        return dfle_error_set(err, DFLE_ECANCELED, "landscape: run stopped by its step callback");
    for (size_t k = 0; k < o->n_record; k++)
        if (!(o->record_times[k] >= 0 && o->record_times[k] <= max_time &&
              (k == 0 || o->record_times[k] > o->record_times[k - 1])))
            return dfle_error_set(err, DFLE_EINVAL, "landscape: record times must increase "
                                  "within [0, %g yr] (time %zu is %g)", max_time, k + 1,
                                  o->record_times[k]);
    if ((s = take_records(ls, o, 0.0, res, err)) != DFLE_OK)
        return s;

    if (method == DFLE_METHOD_DIRECT) {
        dfle_error why;
        double *z_save = malloc(ls->n * sizeof *z_save);
        if (z_save == NULL)
            return dfle_error_set(err, DFLE_ENOMEM, "landscape: out of memory");
        memcpy(z_save, ls->z, ls->n * sizeof *z_save);
        s = run_direct(ls, o, res, &st, &why);
        if (s == DFLE_OK && !(o->interrupt != NULL && *o->interrupt)) {
            s = ls_evaluate_rates(ls, o->tol, o->quantile, &st, err);
            if (s == DFLE_OK && steady_met(o, &st)) {
                free(z_save);
                res->converged = 1;
                res->reason = DFLE_STOP_STEADY;
                res->last = st;
                res->routings = ls->routings - routings0;
                res->dt_min = res->dt_max = 0;
                snprintf(res->note, sizeof res->note, "steady: the network settled after %zu "
                         "direct rounds", st.steps);
                return DFLE_OK;
            }
            if (s != DFLE_OK) {
                free(z_save);
                return s;
            }
            explain(o, &st, why.msg, sizeof why.msg);
            s = DFLE_EFIT;
        } else if (s == DFLE_OK) {
            free(z_save);
            res->reason = DFLE_STOP_INTERRUPTED;
            res->last = st;
            snprintf(res->note, sizeof res->note, "interrupted during the direct rounds");
            return DFLE_OK;
        }
        if (s != DFLE_EFIT) {
            free(z_save);
            if (err != NULL)
                *err = why;
            return s;
        }
        /* No consistent steady state of a fixed network: step instead,
         * from where the run began. */
        dfle_landscape_set_z(ls, z_save, NULL);
        free(z_save);
        res->fallback = 1;
        snprintf(res->note, sizeof res->note, "direct: %.200s; continued by implicit steps",
                 why.msg);
        method = DFLE_METHOD_IMPLICIT;
        res->method = method;
        steps = 0;
    }

    for (;;) {
        double dt;
        if (steps > 0 && !transient && steady_met(o, &st)) {
            res->converged = 1;
            res->reason = DFLE_STOP_STEADY;
            break;
        }
        if (t >= max_time * (1.0 - 1e-12)) {
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
        if ((s = ls_update_fields(ls, 0, err)) != DFLE_OK)
            return s;
        dt = fmin(o->dt, max_time - t);
        if (res->n_recorded < o->n_record && o->record_times[res->n_recorded] - t < dt)
            dt = o->record_times[res->n_recorded] - t;
        if (method == DFLE_METHOD_EXPLICIT)
            s = ls_explicit_step(ls, dt, o->cfl, o->tol, o->quantile, &dt, &st, err);
        else
            s = ls_implicit_step(ls, dt, o->tol, o->quantile, &st, err);
        if (s != DFLE_OK)
            return s;
        t += dt;
        ls->time += dt;
        steps++;
        res->dt_min = fmin(res->dt_min, dt);
        res->dt_max = fmax(res->dt_max, dt);
        if (r0 < 0)
            r0 = st.q_ratio;
        st.time = t;
        st.steps = steps;
        st.fraction = fraction(o, t, max_time, r0, st.q_ratio);
        if (o->on_step != NULL && o->on_step(o->on_step_ud, ls, &st) != 0)
            return dfle_error_set(err, DFLE_ECANCELED, "landscape: run stopped by its step "
                                  "callback at t = %g yr", t);
        if ((s = take_records(ls, o, t, res, err)) != DFLE_OK)
            return s;
        if (o->progress != NULL && steps % (o->progress_every ? o->progress_every : 16) == 0 &&
            o->progress(o->progress_ud, &st) != 0)
            return dfle_error_set(err, DFLE_ECANCELED, "landscape: run stopped by the progress "
                                  "callback at t = %g yr", t);
    }
    res->last = st;
    res->routings = ls->routings - routings0;
    if (res->dt_min > res->dt_max)
        res->dt_min = 0;
    if (res->note[0] == '\0' || res->converged) {
        char why[200];
        if (res->converged)
            snprintf(why, sizeof why, "steady after %zu steps", steps);
        else if (transient && res->reason == DFLE_STOP_TIME)
            snprintf(why, sizeof why, "ran %g yr in %zu steps", t, steps);
        else if (res->reason == DFLE_STOP_INTERRUPTED)
            snprintf(why, sizeof why, "interrupted at t = %g yr after %zu steps", t, steps);
        else
            explain(o, &st, why, sizeof why);
        if (res->note[0] != '\0') {
            size_t used = strlen(res->note);
            snprintf(res->note + used, sizeof res->note - used, "; %s", why);
        } else {
            snprintf(res->note, sizeof res->note, "%s", why);
        }
    } else {
        char why[200];
        size_t used = strlen(res->note);
        explain(o, &st, why, sizeof why);
        snprintf(res->note + used, sizeof res->note - used, "; %s", why);
    }
    return DFLE_OK;
}
