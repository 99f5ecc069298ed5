/*
 * landscape_run.c - runs of a landscape: transients and steady states.
 *
 * Time steps go through the solvers' stepping loop (solver.h,
 * dfle_stepping_loop): this file is a stepper on it, so that a
 * landscape and the 1D model stop on the same checks (steady, time,
 * steps, interrupt) in the same order.  The direct method is rounds,
 * not time: its own loop below, ending where the criterion holds, after
 * which the state is checked as a fixed point (landscape_steady.c) and,
 * where it is none or the rounds stall, continued by implicit steps.
 *
 * Steps are weighed against the time asked before a run starts: a step
 * whose uplift z cannot resolve is an error naming it (with dt = 1e-300
 * nothing moved, and the run reported a steady state after 6 steps); a
 * transient whose step count to `years` exceeds max_steps is refused (a
 * year at dt = 1e-12 ran a million steps and ended at 1e-6 yr without a
 * word), a steady run's only warned about (it may converge first); a
 * transient that stops short of `years` warns.
 *
 * The network (doc/landscape.md): a routing is stable when no receiver
 * changed (rcv_tol = 0); rounds and steps start with that rule and relax
 * it to rcv_tol_cycle only where the network cycles, that is when a
 * routing returns to the receivers of one of the last few, or the
 * changes stop falling for as many rounds as the grid is wide (at least
 * DIRECT_STALL).  At the old default (0.5 % of the cells allowed to
 * change, at every routing) the rounds stopped on networks that still
 * moved, with 6-41 % of the channel cells off their steady slope.
 */
#include "landscape/landscape_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Rounds (or steps) without a new fewest number of receiver changes
 * after which the network is taken to cycle, at least: a capture (a
 * basin switching outlets) changes hundreds of receivers and then needs
 * rounds in proportion to its flow paths to settle, since each round
 * moves the network about one cell further; on 300 x 300 cells draining
 * to one edge the changes stayed above their fewest for 147 rounds after
 * such a capture and then settled.  So the patience is the grid's width
 * when that is more. */
#define DIRECT_STALL 30

/* Steps to wait after a failed fixed-point check before the next, at
 * most (each failure doubles the wait). */
#define VERIFY_WAIT_MAX 64

void dfle_landscape_run_opts_default(dfle_landscape_run_opts *o)
{
    memset(o, 0, sizeof *o);
    o->method = DFLE_METHOD_AUTO;
    o->tol = 1e-3;
    o->channel_quantile = 0.99;
    o->hillslope_quantile = 0.95;
    o->stable_steps = 5;
    o->rcv_tol = 0.0;
    o->rcv_tol_cycle = 0.005;
    o->verify_steps = 3;
    o->verify_dt = 1e4;
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
    if (!(o->channel_quantile > 0 && o->channel_quantile <= 1))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: channel_quantile must be in (0, 1] "
                              "(got %g)", o->channel_quantile);
    if (!(o->hillslope_quantile > 0 && o->hillslope_quantile <= 1))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: hillslope_quantile must be in (0, "
                              "1] (got %g)", o->hillslope_quantile);
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
    if (!(o->rcv_tol_cycle >= o->rcv_tol && o->rcv_tol_cycle < 1))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: rcv_tol_cycle must be in [rcv_tol, "
                              "1) = [%g, 1) (got %g)", o->rcv_tol, o->rcv_tol_cycle);
    if (!(isfinite(o->verify_dt) && o->verify_dt > 0))
        return dfle_error_set(err, DFLE_EINVAL, "landscape: verify_dt must be > 0 yr (got %g)",
                              o->verify_dt);
    if (o->method == DFLE_METHOD_DIRECT && o->years > 0)
        return dfle_error_set(err, DFLE_EINVAL, "landscape: method 'direct' finds steady "
                              "states only; a transient (years) needs 'implicit' or 'explicit'");
    return DFLE_OK;
}

/* ---------------------------------------------------------------- */
/* The network: settled, cycling or stalled                          */
/* ---------------------------------------------------------------- */

typedef struct ls_watch {
    size_t fewest, fewest_at, patience;
    int relaxed;          /* judged by rcv_tol_cycle from relaxed_at */
    size_t relaxed_at;
    const char *unit;     /* of relaxed_at: "round" or "step" */
    const char *why;      /* what showed the network to cycle */
} ls_watch;

static void watch_restart(ls_watch *w)
{
    w->fewest = SIZE_MAX;
    w->fewest_at = 0;
}

static void watch_init(ls_watch *w, const dfle_landscape *ls)
{
    const size_t wide = (size_t)sqrt((double)ls->n_data);
    memset(w, 0, sizeof *w);
    w->patience = wide > DIRECT_STALL ? wide : DIRECT_STALL;
    watch_restart(w);
}

/* After routing k of a run (a round or a step): the fewest changes so
 * far; where the network cycles under rcv_tol, the rule relaxed to
 * rcv_tol_cycle (with a fresh patience).  1 when the changes have not
 * reached a new fewest for `patience` routings under the rule in force
 * (the rounds stall). */
static int watch_network(ls_watch *w, dfle_landscape *ls, const dfle_landscape_run_opts *o,
                         size_t k, const char *unit)
{
    int stalled;
    if (ls->rcv_changes < w->fewest) {
        w->fewest = ls->rcv_changes;
        w->fewest_at = k;
    }
    stalled = k - w->fewest_at >= w->patience;
    if (!w->relaxed && o->rcv_tol_cycle > ls->rcv_tol && (ls->rcv_repeat || stalled)) {
        w->relaxed = 1;
        w->relaxed_at = k;
        w->unit = unit;
        w->why = ls->rcv_repeat ? "its receivers went back to those of a routing a few before"
                                : "its receiver changes stopped falling";
        ls->rcv_tol = o->rcv_tol_cycle;
        ls->stable = (double)ls->rcv_changes <= floor(ls->rcv_tol * (double)ls->n_data);
        w->fewest = ls->rcv_changes;
        w->fewest_at = k;
        return 0;
    }
    return stalled;
}

/* ---------------------------------------------------------------- */
/* A run                                                            */
/* ---------------------------------------------------------------- */

typedef struct ls_run {
    dfle_landscape *ls;
    const dfle_landscape_run_opts *o;
    dfle_landscape_result *res;
    ls_judge judge;
    int method, transient;
    double max_time;
    dfle_landscape_status st;  /* the state as the run goes             */
    double r0;                 /* the first channel quantile (progress) */
    size_t record0;            /* records taken before the stepping loop */
    ls_watch watch;
    ls_saved saved;            /* the fixed-point check's               */
    size_t checks, verify_wait, verify_next;
    char verify_why[300];      /* the last failed check, in words       */
    int warned_steps;
} ls_run;

static void warn(const ls_run *run, const char *fmt, ...)
{
    char msg[600];
    va_list ap;
    if (run->o->warn == NULL)
        return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    run->o->warn(run->o->warn_ud, msg);
}

/* Call on_record for every record time reached at time t of the run. */
static int take_record(ls_run *run, size_t k, double t, dfle_error *err)
{
    const dfle_landscape_run_opts *o = run->o;
    if (o->on_record != NULL && o->on_record(o->on_record_ud, run->ls, k, run->ls->time) != 0)
        return dfle_error_set(err, DFLE_ECANCELED, "landscape: run stopped while recording at "
                              "t = %g yr", t);
    return DFLE_OK;
}

/* The steps a run will take weighed against the time it asks for,
 * before it starts. */
static int weigh_steps(ls_run *run, dfle_error *err)
{
    const dfle_landscape_run_opts *o = run->o;
    const double tol = run->transient ? 0.0 : o->tol;
    int s;
    if (run->method != DFLE_METHOD_EXPLICIT &&
        (s = ls_check_step(run->ls, fmin(o->dt, run->max_time), tol, "dt", err)) != DFLE_OK)
        return s;
    if (!run->transient && o->verify_steps > 0 &&
        (s = ls_check_step(run->ls, o->verify_dt, o->tol, "verify_dt", err)) != DFLE_OK)
        return s;
    if (run->method == DFLE_METHOD_IMPLICIT) {
        const double need = ceil(run->max_time / o->dt * (1.0 - 1e-12)) + (double)o->n_record;
        if (run->transient && need > (double)o->max_steps)
            return dfle_error_set(err, DFLE_EINVAL, "landscape: years = %g yr in steps of dt = "
                                  "%g yr takes %.3g steps, more than max_steps = %zu: give a "
                                  "larger dt, or a larger max_steps", o->years, o->dt, need,
                                  o->max_steps);
        if (!run->transient && need > (double)o->max_steps)
            warn(run, "max_time = %g yr in steps of dt = %g yr takes %.3g steps: unless it is "
                 "steady first, the run stops at max_steps = %zu, at t = %g yr", o->max_time,
                 o->dt, need, o->max_steps, (double)o->max_steps * o->dt);
    }
    return DFLE_OK;
}

/* Check the state that met the criterion as a fixed point; *passed. */
static int check_fixed_point(ls_run *run, int *passed, dfle_error *err)
{
    const dfle_landscape_run_opts *o = run->o;
    dfle_landscape_result *res = run->res;
    dfle_landscape_status worst;
    size_t taken;
    int s = ls_verify(run->ls, &run->judge, o->verify_steps, o->verify_dt, &run->saved, passed,
                      &taken, &worst, err);
    if (s != DFLE_OK)
        return s;
    run->checks++;
    res->verify_steps = taken;
    res->verified = *passed && taken > 0;
    res->verify = worst;
    if (!*passed)
        snprintf(run->verify_why, sizeof run->verify_why, "after %zu implicit step%s of %g yr "
                 "from it, %.3g%% of the channel cells (%zu) had |dz/dt| > tol U (allowed "
                 "%.3g%%; the max %.3g), the hillslopes %.3g%%, the volume balance %.3g", taken,
                 taken == 1 ? "" : "s", o->verify_dt, 100 * worst.channel_frac_above,
                 worst.channel_above, 100 * (1 - o->channel_quantile), worst.channel_max_ratio,
                 100 * worst.hillslope_frac_above, worst.volume_balance);
    return DFLE_OK;
}

/* How the fixed-point check went, for the note. */
static void checked_words(const ls_run *run, char *buf, size_t cap)
{
    const dfle_landscape_run_opts *o = run->o;
    const dfle_landscape_result *res = run->res;
    if (o->verify_steps == 0 || res->verify_steps == 0)
        snprintf(buf, cap, "not checked as a fixed point (verify_steps = 0)");
    else
        snprintf(buf, cap, "a fixed point: %zu implicit steps of %g yr from it keep the "
                 "criterion (at most %.3g%% of the channel cells above tol U)",
                 res->verify_steps, o->verify_dt, 100 * res->verify.channel_frac_above);
}

/* The network's rule, for the note. */
static void network_words(const ls_run *run, char *buf, size_t cap)
{
    if (run->watch.relaxed)
        snprintf(buf, cap, "; the network cycles (%s), so from %s %zu on a routing was stable "
                 "with at most %g of the cells changing receiver (rcv_tol_cycle)",
                 run->watch.why, run->watch.unit, run->watch.relaxed_at, run->o->rcv_tol_cycle);
    else
        buf[0] = '\0';
}

/* Rounds of the direct method until the criterion holds.  DFLE_EFIT
 * (with why) when a cell has no steady slope (*stalled = 0: nothing to
 * go on from) or when the rounds stop approaching a fixed network
 * (*stalled = 1: the surface is the last round's, close to steady but
 * for the cells whose receivers still flip).  Each round moves the
 * network only near where the last one changed it (a channel head
 * extends by a cell, a divide shifts), so the rounds needed grow with
 * the grid: 30-50 on 100 x 100 cells from noise, 100-300 on 300 x 300
 * with rcv_tol = 0 (doc/landscape.md has the table). */
static int run_direct(ls_run *run, int *stalled, dfle_error *err)
{
    dfle_landscape *ls = run->ls;
    const dfle_landscape_run_opts *o = run->o;
    dfle_landscape_status *st = &run->st;
    size_t rounds = 0;
    int s;

    *stalled = 0;
    ls->stable = 0;
    ls->df_omega = 0.0; /* undamped rounds first (landscape_direct.c) */
    ls->routed = 0; /* count from a routing of this state */
    for (;;) {
        if ((s = ls_route(ls, err)) != DFLE_OK)
            return s;
        if (rounds > 0) {
            const int give_up = watch_network(&run->watch, ls, o, rounds, "round");
            st->steps = rounds;
            st->rcv_changes = ls->rcv_changes;
            st->stable = ls->stable;
            /* The rates (a routing of the debris flows, the model's
             * evaluation) decide only once the network is stable. */
            if (ls->stable >= o->stable_steps) {
                if ((s = ls_evaluate_rates(ls, &run->judge, st, err)) != DFLE_OK)
                    return s;
                st->steps = rounds;
                if (ls_rates_met(&run->judge, st))
                    return DFLE_OK;
            }
            if (o->on_step != NULL && o->on_step(o->on_step_ud, ls, st) != 0)
                return dfle_error_set(err, DFLE_ECANCELED, "landscape: run stopped by its step "
                                      "callback");
            if (rounds >= o->max_steps || give_up) {
                const char *why = rounds >= o->max_steps ? "reached max_steps"
                                                         : "stopped approaching a fixed network";
                char words[400];
                *stalled = 1;
                if (ls->stable >= o->stable_steps) { /* the network held; the rates did not */
                    ls_explain(&run->judge, st, 0, ls->rcv_tol, words, sizeof words);
                    return dfle_error_set(err, DFLE_EFIT, "the direct rounds %s after %zu "
                                          "rounds with a stable network but %s", why, rounds,
                                          words + strlen("not steady: "));
                }
                if (ls->o.hillslope == DFLE_HILLSLOPE_THRESHOLD && !ls->o.cap_channels) {
                    /* The likely cause, named (doc/landscape.md, "Channels
                     * steeper than S_c"): such heads have no steady network. */
                    const uint32_t *rcv = dfle_drainage_receivers(ls->dr);
                    const unsigned char *dir = dfle_drainage_dir(ls->dr);
                    const double *A = dfle_drainage_area(ls->dr);
                    size_t steep = 0;
                    for (size_t c = 0; c < ls->n; c++)
                        steep += rcv[c] != c && A[c] >= ls->o.A0 &&
                                 ls->z[c] - ls->z[rcv[c]] >
                                     ls->o.S_c * (1.0 + 1e-9) * ls->len[dir[c]];
                    if (steep > 0)
                        return dfle_error_set(err, DFLE_EFIT, "the direct rounds %s after %zu "
                                              "rounds (%zu cells changed receiver in the last, "
                                              "%zu allowed; %zu channel cells are steeper than "
                                              "S_c, cap_channels = false)", why, rounds,
                                              ls->rcv_changes,
                                              (size_t)floor(ls->rcv_tol * (double)ls->n_data),
                                              steep);
                }
                return dfle_error_set(err, DFLE_EFIT, "the direct rounds %s after %zu rounds "
                                      "(%zu cells changed receiver in the last, %zu allowed; "
                                      "the fewest, %zu, in round %zu)", why, rounds,
                                      ls->rcv_changes,
                                      (size_t)floor(ls->rcv_tol * (double)ls->n_data),
                                      run->watch.fewest, run->watch.fewest_at);
            }
        }
        if (o->interrupt != NULL && *o->interrupt)
            return DFLE_OK;
        if ((s = ls_direct_round(ls, err)) != DFLE_OK)
            return s;
        rounds++;
    }
}

/* ---------------------------------------------------------------- */
/* The stepper on the solvers' loop                                  */
/* ---------------------------------------------------------------- */

static double fraction(const ls_run *run, double t)
{
    double f = t / run->max_time;
    const double r0 = run->r0, r = run->st.channel_q_ratio, tol = run->o->tol;
    if (!run->transient && r0 > tol && r > 0) {
        double fc = log(r0 / r) / log(r0 / tol);
        f = fc > f ? fc : f;
    }
    return f < 0 ? 0 : f > 1 ? 1 : f;
}

/* Judge the last step (a steady run) and bring the fields to the
 * time of the next. */
static int step_prepare(void *self, const dfle_stepping_tally *so_far, int *steady,
                        dfle_error *err)
{
    ls_run *run = self;
    dfle_landscape *ls = run->ls;
    const dfle_landscape_run_opts *o = run->o;
    int s;
    if (so_far->steps > 0 && !run->transient) {
        (void)watch_network(&run->watch, ls, o, so_far->steps, "step");
        run->st.stable = ls->stable;
        if (ls_rates_met(&run->judge, &run->st) && ls->stable >= o->stable_steps) {
            if (run->verify_wait > 0) {
                run->verify_wait--;
            } else {
                int passed;
                if ((s = check_fixed_point(run, &passed, err)) != DFLE_OK)
                    return s;
                *steady = passed;
                if (!passed) { /* step on; check again later, less often */
                    run->verify_next = run->verify_next ? 2 * run->verify_next : 1;
                    if (run->verify_next > VERIFY_WAIT_MAX)
                        run->verify_next = VERIFY_WAIT_MAX;
                    run->verify_wait = run->verify_next;
                }
            }
        }
        if (*steady)
            return DFLE_OK;
    }
    return ls_update_fields(ls, 0, err);
}

static int step_advance(void *self, double dt_limit, double *dt, dfle_error *err)
{
    ls_run *run = self;
    dfle_landscape *ls = run->ls;
    const dfle_landscape_run_opts *o = run->o;
    const double want = fmin(o->dt, dt_limit);
    int s;
    if (run->method == DFLE_METHOD_EXPLICIT) {
        if ((s = ls_explicit_step(ls, want, o->cfl, &run->judge, dt, &run->st, err)) != DFLE_OK)
            return s;
        /* The CFL step can be what no elevation resolves. */
        if (*dt < dt_limit &&
            (s = ls_check_step(ls, *dt, run->transient ? 0.0 : o->tol, "the explicit (CFL) step",
                               err)) != DFLE_OK)
            return s;
    } else {
        /* Elevations grow as the run goes, and resolve less: checked at
         * every step but those that land on a record or the end. */
        if (want == o->dt &&
            (s = ls_check_step(ls, want, run->transient ? 0.0 : o->tol, "dt", err)) != DFLE_OK)
            return s;
        if ((s = ls_implicit_step(ls, want, &run->judge, &run->st, err)) != DFLE_OK)
            return s;
        *dt = want;
    }
    ls->time += *dt;
    return DFLE_OK;
}

static int step_record(void *self, size_t k, double t, dfle_error *err)
{
    ls_run *run = self;
    return take_record(run, run->record0 + k, t, err);
}

static int step_after(void *self, const dfle_stepping_tally *so_far, double dt, dfle_error *err)
{
    ls_run *run = self;
    const dfle_landscape_run_opts *o = run->o;
    dfle_landscape_status *st = &run->st;
    const size_t every = o->progress_every ? o->progress_every : 16;
    if (run->r0 < 0)
        run->r0 = st->channel_q_ratio;
    st->time = so_far->time;
    st->steps = so_far->steps;
    st->max_time = run->max_time;
    st->fraction = fraction(run, so_far->time);
    if (run->transient && run->method == DFLE_METHOD_EXPLICIT && !run->warned_steps) {
        /* Known only now: the CFL step of the start. */
        const double need = (double)so_far->steps + (run->max_time - so_far->time) / dt;
        run->warned_steps = 1;
        if (need > (double)o->max_steps)
            warn(run, "years = %g yr at the explicit (CFL) step of the start, dt = %g yr, takes "
                 "about %.3g steps, more than max_steps = %zu: the run will stop short unless "
                 "the step grows", o->years, dt, need, o->max_steps);
    }
    if (o->on_step != NULL && o->on_step(o->on_step_ud, run->ls, st) != 0)
        return dfle_error_set(err, DFLE_ECANCELED, "landscape: run stopped by its step callback "
                              "at t = %g yr", so_far->time);
    if (o->progress != NULL && so_far->steps % every == 0 && o->progress(o->progress_ud, st) != 0)
        return dfle_error_set(err, DFLE_ECANCELED, "landscape: run stopped by the progress "
                              "callback at t = %g yr", so_far->time);
    return DFLE_OK;
}

static const dfle_stepping_ops landscape_stepping = {
    .iVersion = 1,
    .name = "landscape",
    .prepare = step_prepare,
    .advance = step_advance,
    .record = step_record,
    .after_step = step_after,
};

/* ---------------------------------------------------------------- */
/* The run                                                          */
/* ---------------------------------------------------------------- */

/* Append ("; " and) text to the note. */
static void note_add(dfle_landscape_result *res, const char *text)
{
    size_t used = strlen(res->note);
    snprintf(res->note + used, sizeof res->note - used, "%s%s", used > 0 ? "; " : "", text);
}

/* How much of `text` to quote in at most `max` characters: all of it, or
 * its clauses ("; "-separated) that fit whole, so that a note never ends
 * in the middle of a word. */
static int whole_clauses(const char *text, int max)
{
    int n = (int)strlen(text), cut = 0;
    if (n <= max)
        return n;
    for (int k = 0; k + 1 < max; k++)
        if (text[k] == ';' && text[k + 1] == ' ')
            cut = k;
    return cut > 0 ? cut : max;
}

/* The direct method: rounds, the fixed-point check; *done when the
 * run ended there, else it goes on by implicit steps (fallback). */
static int direct_then(ls_run *run, int *done, dfle_error *err)
{
    dfle_landscape *ls = run->ls;
    dfle_landscape_result *res = run->res;
    const dfle_landscape_run_opts *o = run->o;
    dfle_error why;
    int stalled = 0, passed = 0, s;
    char words[400], net[300];
    double *z_save = malloc(ls->n * sizeof *z_save);

    *done = 0;
    if (z_save == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "landscape: out of memory");
    memcpy(z_save, ls->z, ls->n * sizeof *z_save);
    s = run_direct(run, &stalled, &why);
    if (s == DFLE_OK && o->interrupt != NULL && *o->interrupt) {
        free(z_save);
        res->reason = DFLE_STOP_INTERRUPTED;
        snprintf(res->note, sizeof res->note, "interrupted during the direct rounds");
        *done = 1;
        return DFLE_OK;
    }
    if (s == DFLE_OK && (s = check_fixed_point(run, &passed, err)) != DFLE_OK) {
        free(z_save);
        return s;
    }
    network_words(run, net, sizeof net);
    if (s == DFLE_OK && passed) {
        free(z_save);
        checked_words(run, words, sizeof words);
        res->converged = 1;
        res->reason = DFLE_STOP_STEADY;
        char held[120];
        if (ls->rcv_tol > 0)
            snprintf(held, sizeof held, "at most %g of the cells changed receiver at each of the "
                     "last %zu routings", ls->rcv_tol, o->stable_steps);
        else
            snprintf(held, sizeof held, "no receiver changed in the last %zu routings",
                     o->stable_steps);
        snprintf(res->note, sizeof res->note, "steady: the network settled after %zu direct "
                 "rounds (%.120s); %.300s%.200s", run->st.steps, held, words, net);
        *done = 1;
        return DFLE_OK;
    }
    if (s == DFLE_OK) {
        /* Steady by its rates, not a fixed point: time settles it. */
        free(z_save);
        snprintf(res->note, sizeof res->note, "direct: the state of round %zu meets the "
                 "criterion but is no fixed point (%s); continued by implicit steps from it",
                 run->st.steps, run->verify_why);
    } else if (s != DFLE_EFIT) {
        free(z_save);
        if (err != NULL)
            *err = why;
        return s;
    } else {
        /* Rounds that stalled leave a surface close to steady but for
         * the cells whose receivers flip: implicit steps settle those,
         * as time does.  A cell with no steady slope leaves nothing to
         * go on from: step from where the run began. */
        if (!stalled)
            dfle_landscape_set_z(ls, z_save, NULL);
        free(z_save);
        snprintf(res->note, sizeof res->note, "direct: %.*s; continued by implicit steps from "
                 "%s", whole_clauses(why.msg, 300), why.msg,
                 stalled ? "the last round's surface" : "the start");
    }
    res->fallback = 1;
    res->direct_rounds = run->st.steps;
    run->verify_why[0] = '\0';
    return DFLE_OK;
}

/* The note and warnings of a run that went through the stepping loop. */
static void finish_stepping(ls_run *run, const dfle_stepping_tally *tally)
{
    dfle_landscape *ls = run->ls;
    dfle_landscape_result *res = run->res;
    const dfle_landscape_run_opts *o = run->o;
    char words[700], net[300];

    network_words(run, net, sizeof net);
    if (res->converged) {
        char checked[300];
        checked_words(run, checked, sizeof checked);
        snprintf(words, sizeof words, "steady after %zu steps; %s%s", tally->steps, checked,
                 net);
    } else if (run->transient && res->reason == DFLE_STOP_TIME) {
        snprintf(words, sizeof words, "ran %g yr in %zu steps", tally->time, tally->steps);
    } else if (res->reason == DFLE_STOP_INTERRUPTED) {
        snprintf(words, sizeof words, "interrupted at t = %g yr after %zu steps", tally->time,
                 tally->steps);
    } else if (run->transient) {
        snprintf(words, sizeof words, "stopped at t = %g yr of the %g yr asked: max_steps = %zu "
                 "reached (steps of %g to %g yr)", tally->time, o->years, o->max_steps,
                 tally->dt_min, tally->dt_max);
        warn(run, "%s", words);
    } else if (run->verify_why[0] != '\0' && ls_rates_met(&run->judge, &run->st) &&
               run->st.stable >= o->stable_steps) {
        /* What failed is the check, not the criterion. */
        snprintf(words, sizeof words, "not steady: no fixed point: the state meets the "
                 "criterion (%.3g%% of the channel cells above tol U, volume balance %.3g), "
                 "but %.300s%.200s", 100 * run->st.channel_frac_above,
                 run->st.volume_balance, run->verify_why, net);
    } else {
        size_t used;
        ls_explain(&run->judge, &run->st, o->stable_steps, ls->rcv_tol, words, sizeof words);
        used = strlen(words);
        if (run->verify_why[0] != '\0' && used < sizeof words)
            snprintf(words + used, sizeof words - used, "; the last fixed-point check failed: "
                     "%s", run->verify_why);
        used = strlen(words);
        if (used < sizeof words)
            snprintf(words + used, sizeof words - used, "%s", net);
    }
    note_add(res, words);
}

int dfle_landscape_run(dfle_landscape *ls, const dfle_landscape_run_opts *o,
                       dfle_landscape_result *res, dfle_error *err)
{
    ls_run run;
    dfle_stepping_tally tally;
    dfle_stepping_limits lim;
    const size_t routings0 = ls->routings;
    int s;

    memset(res, 0, sizeof *res);
    memset(&run, 0, sizeof run);
    if ((s = check_run_opts(o, err)) != DFLE_OK)
        return s;
    run.ls = ls;
    run.o = o;
    run.res = res;
    run.judge = (ls_judge){o->tol, o->channel_quantile, o->hillslope_quantile};
    run.transient = o->years > 0;
    run.max_time = run.transient ? o->years : o->max_time;
    run.method = o->method != DFLE_METHOD_AUTO ? o->method
                 : run.transient                ? DFLE_METHOD_IMPLICIT
                                                : DFLE_METHOD_DIRECT;
    run.r0 = -1.0;
    run.st.max_time = run.max_time;
    watch_init(&run.watch, ls);
    ls->rcv_tol = o->rcv_tol;
    ls->rcv_hashes = 0;
    res->method = run.method;
    for (size_t k = 0; k < o->n_record; k++)
        if (!(o->record_times[k] >= 0 && o->record_times[k] <= run.max_time &&
              (k == 0 || o->record_times[k] > o->record_times[k - 1])))
            return dfle_error_set(err, DFLE_EINVAL, "landscape: record times must increase "
                                  "within [0, %g yr] (time %zu is %g)", run.max_time, k + 1,
                                  o->record_times[k]);
    if ((s = weigh_steps(&run, err)) != DFLE_OK)
        return s;
    if ((s = ls_update_fields(ls, 0, err)) != DFLE_OK)
        return s;
    if (o->on_step != NULL && o->on_step(o->on_step_ud, ls, &run.st) != 0)
        return dfle_error_set(err, DFLE_ECANCELED, "landscape: run stopped by its step callback");
    while (run.record0 < o->n_record && o->record_times[run.record0] <= 0) {
        if ((s = take_record(&run, run.record0, 0.0, err)) != DFLE_OK)
            return s;
        run.record0++;
    }

    if (run.method == DFLE_METHOD_DIRECT) {
        int done;
        s = direct_then(&run, &done, err);
        if (s != DFLE_OK || done) {
            ls_saved_free(&run.saved);
            res->last = run.st;
            res->routings = ls->routings - routings0;
            res->n_recorded = run.record0;
            res->rcv_tol = ls->rcv_tol;
            if (s == DFLE_OK && res->converged && run.st.channel_cells == 0)
                warn(&run, "the steady state has no channel cell: A0 = %g m^2 is more than any "
                     "cell drains", ls->o.A0);
            return s;
        }
        run.method = res->method = DFLE_METHOD_IMPLICIT;
        watch_restart(&run.watch);
    }

    lim.max_time = run.max_time;
    lim.max_steps = o->max_steps;
    lim.interrupt = o->interrupt;
    lim.n_record = o->n_record - run.record0;
    lim.record_times = o->record_times + run.record0;
    s = dfle_stepping_loop(&landscape_stepping, &run, &lim, &tally, err);
    ls_saved_free(&run.saved);
    res->n_recorded = run.record0 + tally.n_recorded;
    if (s != DFLE_OK)
        return s;
    res->reason = tally.reason;
    res->converged = tally.reason == DFLE_STOP_STEADY;
    res->dt_min = tally.dt_min;
    res->dt_max = tally.dt_max;
    res->last = run.st;
    res->routings = ls->routings - routings0;
    res->rcv_tol = ls->rcv_tol;
    finish_stepping(&run, &tally);
    if (res->converged && run.st.channel_cells == 0)
        warn(&run, "the steady state has no channel cell: A0 = %g m^2 is more than any cell "
             "drains", ls->o.A0);
    return DFLE_OK;
}
