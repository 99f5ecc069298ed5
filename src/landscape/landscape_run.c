/*
 * landscape_run.c - runs of a landscape: transients and steady states.
 *
 * What steady means for a landscape (doc/landscape.md).  On a 1D channel
 * the run stops when max |dz/dt| <= tol U.  In 2D the drainage network
 * itself moves: divides migrate, a hillslope cell on a divide flips
 * between receivers, and every flip moves its area from one flow path to
 * another, so the channel cells below it keep |dz/dt| of a few percent
 * of U long after the rest is still (fastscapelib's 250^2 landscape with
 * n = 2.33 has max |dz/dt|/U of about 3 after 1.6e7 yr while the mean is
 * 1.3e-2).  So a landscape is steady when
 *   - at least a fraction `quantile` (0.95) of its non-base data cells
 *     has |dz/dt| <= tol U (tol = 1e-3), and
 *   - the network is stable: at most a fraction rcv_tol (0.005) of the
 *     cells changed receiver at each of the last `stable_steps` (5)
 *     routings.
 * Both are reported as the run goes (q_ratio, frac_above, rcv_changes,
 * stable); a run that reaches max_time or max_steps without meeting them
 * ends with converged = 0 and a note saying which part failed and by how
 * much.
 *
 * Methods: IMPLICIT, backward Euler with a fixed step (landscape_step.c);
 * EXPLICIT, forward Euler with the CFL step (the reference); DIRECT, the
 * steady state of a fixed network node by node (landscape_direct.c),
 * re-routed and judged by the same criterion after every round; when the
 * rounds stop approaching a fixed network the run goes on by implicit
 * steps from the last round's surface, and says so.
 */
#include "landscape/landscape_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The direct rounds give up when they have not reached a new fewest
 * number of receiver changes for this many rounds, or for as many
 * rounds as the grid is wide (the square root of its data cells), if
 * that is more (run_direct says why). */
#define DIRECT_STALL 30

void dfle_landscape_run_opts_default(dfle_landscape_run_opts *o)
{
    memset(o, 0, sizeof *o);
    o->method = DFLE_METHOD_AUTO;
    o->tol = 1e-3;
    o->quantile = 0.95;
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

/* Channel cells of the current routing steeper than S_c. */
static size_t steeper_channels(dfle_landscape *ls)
{
    const uint32_t *rcv = dfle_drainage_receivers(ls->dr);
    const unsigned char *dir = dfle_drainage_dir(ls->dr);
    const double *A = dfle_drainage_area(ls->dr);
    size_t k = 0;
    for (size_t c = 0; c < ls->n; c++)
        if (rcv[c] != c && A[c] >= ls->o.A0 &&
            ls->z[c] - ls->z[rcv[c]] > ls->o.S_c * (1.0 + 1e-9) * ls->len[dir[c]])
            k++;
    return k;
}

/* Rounds of the direct method until the criterion holds.  DFLE_EFIT
 * (with why) when a cell has no steady slope (*stalled = 0: nothing to
 * go on from) or when the rounds stop approaching a fixed network
 * (*stalled = 1: the surface is the last round's, close to steady
 * but for the cells whose receivers still flip).
 *
 * Each round moves the network only near where the last one changed it
 * (a channel head extends by a cell, a divide shifts), so the rounds
 * needed grow with the size of the grid: about 30 on 100 x 100 cells
 * from noise, 50-70 on 200 x 200.  The rounds stop when the criterion
 * holds (the last rcv_tol-stable routings count towards stable_steps);
 * they give up when the fewest changes so far came `patience` rounds
 * ago (a network that cycles between near-equal routings), or after
 * max_steps rounds.  The patience is DIRECT_STALL rounds or as many as
 * the grid is wide: a capture (a basin switching outlets) changes
 * hundreds of receivers and then needs rounds in proportion to the
 * length of its flow paths to settle, since each round moves the
 * network about one cell further; on 300 x 300 cells draining to one
 * edge the changes stayed above their fewest for 147 rounds after
 * such a capture and then fell below rcv_tol. */
static int run_direct(dfle_landscape *ls, const dfle_landscape_run_opts *o,
                      dfle_landscape_result *res, dfle_landscape_status *st, int *stalled,
                      dfle_error *err)
{
    size_t rounds = 0, fewest = SIZE_MAX, fewest_at = 0;
    const size_t wide = (size_t)sqrt((double)ls->n_data);
    const size_t patience = wide > DIRECT_STALL ? wide : DIRECT_STALL;
    int s;

    *stalled = 0;
    res->method = DFLE_METHOD_DIRECT;
    ls->stable = 0;
    ls->routed = 0; /* count from a routing of this state */
    for (;;) {
        if ((s = ls_route(ls, err)) != DFLE_OK)
            return s;
        if (rounds > 0) {
            st->steps = rounds;
            /* The rates (a routing of the debris flows, the model's
             * evaluation) decide only once the network is stable. */
            if (ls->stable >= o->stable_steps) {
                if ((s = ls_evaluate_rates(ls, o->tol, o->quantile, st, err)) != DFLE_OK)
                    return s;
                if (steady_met(o, st))
                    return DFLE_OK;
            }
            st->rcv_changes = ls->rcv_changes;
            st->stable = ls->stable;
            if (ls->rcv_changes < fewest) {
                fewest = ls->rcv_changes;
                fewest_at = rounds;
            }
            if (o->on_step != NULL && o->on_step(o->on_step_ud, ls, st) != 0)
                return dfle_error_set(err, DFLE_ECANCELED, "landscape: run stopped by its step "
                                      "callback");
        }
        if (rounds >= o->max_steps || (rounds > 0 && rounds - fewest_at >= patience)) {
            const char *why = rounds >= o->max_steps ? "reached max_steps"
                                                     : "stopped approaching a fixed network";
            *stalled = 1;
            if (ls->stable >= o->stable_steps) /* the network held; the rates did not */
                return dfle_error_set(err, DFLE_EFIT, "the direct rounds %s after %zu rounds: "
                                      "the network is stable but %.3g%% of the cells have "
                                      "|dz/dt| > tol U (allowed %.3g%%; cells below divides "
                                      "that flip)", why, rounds, 100 * st->frac_above,
                                      100 * (1 - o->quantile));
            if (ls->o.hillslope == DFLE_HILLSLOPE_THRESHOLD && !ls->o.cap_channels) {
                /* The likely cause, named (doc/landscape.md, "Channels
                 * steeper than S_c"): such heads have no steady network. */
                size_t steep = steeper_channels(ls);
                if (steep > 0)
                    return dfle_error_set(err, DFLE_EFIT, "the direct rounds %s after %zu "
                                          "rounds (%zu cells changed receiver in the last, %zu "
                                          "allowed; %zu channel cells are steeper than S_c, "
                                          "cap_channels = false)", why, rounds,
                                          ls->rcv_changes,
                                          (size_t)floor(ls->rcv_tol * (double)ls->n_data), steep);
            }
            return dfle_error_set(err, DFLE_EFIT, "the direct rounds %s after %zu rounds (%zu "
                                  "cells changed receiver in the last, %zu allowed; the "
                                  "fewest, %zu, in round %zu)", why, rounds, ls->rcv_changes,
                                  (size_t)floor(ls->rcv_tol * (double)ls->n_data), fewest,
                                  fewest_at);
        }
        if (o->interrupt != NULL && *o->interrupt)
            return DFLE_OK;
        if ((s = ls_direct_round(ls, err)) != DFLE_OK)
            return s;
        rounds++;
    }
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
        int stalled = 0;
        double *z_save = malloc(ls->n * sizeof *z_save);
        if (z_save == NULL)
            return dfle_error_set(err, DFLE_ENOMEM, "landscape: out of memory");
        memcpy(z_save, ls->z, ls->n * sizeof *z_save);
        s = run_direct(ls, o, res, &st, &stalled, &why);
        if (s == DFLE_OK) {
            free(z_save);
            res->last = st;
            res->routings = ls->routings - routings0;
            res->dt_min = res->dt_max = 0;
            if (o->interrupt != NULL && *o->interrupt) {
                res->reason = DFLE_STOP_INTERRUPTED;
                snprintf(res->note, sizeof res->note, "interrupted during the direct rounds");
            } else {
                res->converged = 1;
                res->reason = DFLE_STOP_STEADY;
                snprintf(res->note, sizeof res->note, "steady: the network settled after %zu "
                         "direct rounds", st.steps);
            }
            return DFLE_OK;
        }
        if (s != DFLE_EFIT) {
            free(z_save);
            if (err != NULL)
                *err = why;
            return s;
        }
        /* Rounds that stalled leave a surface close to steady but for the
         * cells whose receivers flip: implicit steps settle those, as
         * time does.  A cell with no steady slope leaves nothing to go on
         * from: step from where the run began. */
        if (!stalled)
            dfle_landscape_set_z(ls, z_save, NULL);
        free(z_save);
        res->fallback = 1;
        res->direct_rounds = st.steps;
        snprintf(res->note, sizeof res->note, "direct: %.200s; continued by implicit steps from "
                 "%s", why.msg, stalled ? "the last round's surface" : "the start");
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
        char why[300];
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
        char why[300];
        size_t used = strlen(res->note);
        explain(o, &st, why, sizeof why);
        snprintf(res->note + used, sizeof res->note - used, "; %s", why);
    }
    return DFLE_OK;
}
