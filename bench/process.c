/*
 * process.c - the process-based router (router_process.h) with the Fig. 6
 * defaults on the default channel (dx = 5 m, A_max = 8 km^2, 20 ghost
 * cells): CPU time of one routing of the default flow, over the Fig. 6
 * steady-state profile (where the flow stops about node 154 of 423
 * cells) and over the initial Eq. (26) profile; of a whole direct steady
 * state; and how a routing's time grows with the domain (8 and 100 km^2:
 * the same flow on a grid 4.5 times longer).  Each figure is printed
 * beside its target (issue 15) and beside the same run on the
 * full-domain path (flow1d's full_domain = 1: every cell every step, the
 * results bit for bit the same), timed alternately in this one run so
 * that the machine's load weighs on both alike.
 *
 *   build/bench/process [repetitions]     (default 20; best and median)
 *
 * Figures only: nothing here asserts on time.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "dfle/channel.h"
#include "dfle/fluvial.h"
#include "dfle/law.h"
#include "dfle/law_power.h"
#include "dfle/model.h"
#include "dfle/network.h"
#include "dfle/router_process.h"
#include "dfle/solver.h"

#include "bench.h"

/* One model of Fig. 6 (the README's defaults) on a channel to A_max. */
typedef struct setup {
    dfle_channel *ch;
    dfle_fluvial *fl;
    dfle_router *rt[2]; /* [0] the wet window, [1] the full domain */
    dfle_law *law;
    dfle_model *m;      /* routes with rt[0] */
} setup;

static void teardown(setup *s)
{
    dfle_model_free(s->m);
    dfle_law_free(s->law);
    dfle_router_free(s->rt[0]);
    dfle_router_free(s->rt[1]);
    dfle_fluvial_free(s->fl);
    dfle_channel_free(s->ch);
}

static int make(setup *s, double A_max, int full_domain_model, dfle_error *err)
{
    dfle_channel_opts co;
    dfle_stochastic_threshold_opts so;
    dfle_process_opts po;
    dfle_power_law_opts lo;
    dfle_model_opts mo;
    int st;

    memset(s, 0, sizeof *s);
    dfle_channel_opts_default(&co);
    co.dx = 5.0;
    co.A_max = A_max;
    dfle_stochastic_threshold_opts_default(&so);
    so.k_e = 5e-14;
    dfle_process_opts_default(&po); /* M0 = 200, eta = 60, mu2 = 0.62, D = 5e-6 */
    dfle_power_law_opts_default(&lo);
    lo.k_df = 1e-4, lo.alpha = 6, lo.beta = 1;
    if ((st = dfle_channel_new(&co, &s->ch, err)) != DFLE_OK ||
        (st = dfle_fluvial_new_stochastic_threshold(&so, &s->fl, err)) != DFLE_OK ||
        (st = dfle_router_new_process(&po, &s->rt[0], err)) != DFLE_OK ||
        (st = dfle_law_new_power(&lo, &s->law, err)) != DFLE_OK)
        return st;
    po.flow.full_domain = 1;
    if ((st = dfle_router_new_process(&po, &s->rt[1], err)) != DFLE_OK)
        return st;
    dfle_model_opts_default(&mo);
    mo.channel = s->ch, mo.fluvial = s->fl, mo.law = s->law, mo.U = 5e-4;
    mo.router = s->rt[full_domain_model ? 1 : 0];
    return dfle_model_new(&mo, &s->m, err);
}

/* One profile to route: the model's slopes, a flow record per path. */
typedef struct timing {
    setup *s;
    const double *S;
    dfle_flow flow[2];
    double *t;                 /* reps x 2 CPU times [s] */
    double best[2], median[2]; /* [0] window, [1] full domain [s] */
    size_t cells, steps, cell_steps, runout_end;
} timing;

static int timing_init(timing *tm, setup *s, int reps, dfle_error *err)
{
    const size_t n = dfle_model_size(s->m);
    memset(tm, 0, sizeof *tm);
    tm->s = s;
    if ((tm->S = dfle_model_field(s->m, DFLE_FIELD_S, err)) == NULL)
        return err->code;
    if ((tm->t = malloc(2 * (size_t)reps * sizeof *tm->t)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "out of memory");
    for (int p = 0; p < 2; p++) {
        int st = dfle_flow_init(&tm->flow[p], n, err);
        if (st != DFLE_OK)
            return st;
        tm->flow[p].integrand = dfle_law_get_ops(s->law)->integrand;
        tm->flow[p].integrand_state = dfle_law_state(s->law);
    }
    tm->cells = n + (size_t)dfle_router_process_opts(s->rt[0])->n_ghost;
    return DFLE_OK;
}

/* Round r: one routing on each path. */
static int timing_round(timing *tm, int reps, int r, dfle_error *err)
{
    for (int p = 0; p < 2; p++) {
        double t0 = cpu_seconds();
        int st = dfle_router_route(tm->s->rt[p], dfle_model_network(tm->s->m), tm->S,
                                   &tm->flow[p], err);
        tm->t[p * reps + r] = cpu_seconds() - t0;
        if (st != DFLE_OK)
            return st;
    }
    return DFLE_OK;
}

/* Best and median of each path; both paths must give the same flow. */
static int timing_finish(timing *tm, int reps, dfle_error *err)
{
    const dfle_process_report *rep = dfle_router_process_report(tm->s->rt[0]);
    for (size_t i = 0; i < tm->flow[0].n; i++)
        if (tm->flow[0].integral[i] != tm->flow[1].integral[i] ||
            tm->flow[0].h[i] != tm->flow[1].h[i])
            return dfle_error_set(err, DFLE_ESTATE, "the two paths differ at node %zu", i + 1);
    for (int p = 0; p < 2; p++) {
        qsort(tm->t + p * reps, (size_t)reps, sizeof *tm->t, by_value);
        tm->best[p] = tm->t[p * reps];
        tm->median[p] = tm->t[p * reps + reps / 2];
    }
    tm->steps = rep->steps;
    tm->cell_steps = rep->cell_steps;
    tm->runout_end = tm->flow[0].runout_end;
    return DFLE_OK;
}

static void timing_free(timing *tm)
{
    for (int p = 0; p < 2; p++)
        dfle_flow_release(&tm->flow[p]);
    free(tm->t);
}

static void print_routing(const char *what, const timing *tm, int reps, double target_ms)
{
    printf("process router, one routing over the %s: %.2f ms CPU (best of %d; median %.2f)", what,
           1e3 * tm->best[0], reps, 1e3 * tm->median[0]);
    if (target_ms > 0)
        printf(", target <= %g ms", target_ms);
    printf("; full-domain path %.2f ms (median %.2f), %.2fx; %zu cells x %zu steps, wet window "
           "%.0f cells on average, flow reaches node %zu\n",
           1e3 * tm->best[1], 1e3 * tm->median[1], tm->best[1] / tm->best[0], tm->cells,
           tm->steps, (double)tm->cell_steps / (double)tm->steps, tm->runout_end);
}

/* A whole direct steady state from the initial profile (a fresh model
 * each time), on each path alternately. */
static int time_steady_state(int reps, dfle_error *err)
{
    double *t = malloc(2 * (size_t)reps * sizeof *t);
    size_t routings = 0;
    int st = DFLE_OK;

    if (t == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "out of memory");
    for (int r = 0; r < reps && st == DFLE_OK; r++)
        for (int p = 0; p < 2 && st == DFLE_OK; p++) {
            setup s;
            dfle_run_opts ro;
            dfle_run_result res;
            double t0;
            if ((st = make(&s, 8e6, p, err)) == DFLE_OK) {
                dfle_run_opts_default(&ro);
                ro.method = DFLE_METHOD_DIRECT;
                t0 = cpu_seconds();
                st = dfle_solver_run(s.m, &ro, &res, err);
                t[p * reps + r] = cpu_seconds() - t0;
                routings = res.routings;
                if (st == DFLE_OK && !res.converged)
                    st = dfle_error_set(err, DFLE_ESTATE, "no steady state");
            }
            teardown(&s);
        }
    if (st == DFLE_OK) {
        for (int p = 0; p < 2; p++)
            qsort(t + p * reps, (size_t)reps, sizeof *t, by_value);
        printf("process router, direct steady state (Fig. 6): %.1f ms CPU (best of %d; median "
               "%.1f), target <= 20 ms; full-domain path %.1f ms (median %.1f), %.2fx; %zu "
               "routings\n",
               1e3 * t[0], reps, 1e3 * t[reps / 2], 1e3 * t[reps], 1e3 * t[reps + reps / 2],
               t[reps] / t[0], routings);
    }
    free(t);
    return st;
}

int main(int argc, char **argv)
{
    const int reps = argc > 1 && atoi(argv[1]) > 0 ? atoi(argv[1]) : 20;
    setup s[3];
    timing tm[3]; /* the steady profile; the initial one on 8 and on 100 km^2 */
    dfle_run_opts ro;
    dfle_run_result res;
    dfle_error err;
    int st = DFLE_OK, made = 0;

    /* The Fig. 6 steady state's profile (the default run's flow), and the
     * initial (Eq. 26) profile on 8 and 100 km^2: the same slopes where
     * they overlap, so the same flow over a grid 4.4 times longer. */
    dfle_run_opts_default(&ro);
    ro.method = DFLE_METHOD_DIRECT;
    for (int c = 0; c < 3 && st == DFLE_OK; c++, made++)
        if ((st = make(&s[c], c < 2 ? 8e6 : 1e8, 0, &err)) == DFLE_OK &&
            (c > 0 || (st = dfle_solver_run(s[c].m, &ro, &res, &err)) == DFLE_OK))
            st = timing_init(&tm[c], &s[c], reps, &err);
    /* Rounds of every case on both paths: the load weighs on all alike. */
    for (int r = 0; r < reps && st == DFLE_OK; r++)
        for (int c = 0; c < 3 && st == DFLE_OK; c++)
            st = timing_round(&tm[c], reps, r, &err);
    for (int c = 0; c < 3 && st == DFLE_OK; c++)
        st = timing_finish(&tm[c], reps, &err);
    if (st == DFLE_OK) {
        const double wet = (double)tm[2].cell_steps / (double)tm[1].cell_steps;
        print_routing("Fig. 6 steady-state profile (the default flow)", &tm[0], reps, 3.0);
        print_routing("initial profile", &tm[1], reps, 0);
        print_routing("initial profile on 100 km^2", &tm[2], reps, 0);
        printf("process router, growth from 8 to 100 km^2 (%zu to %zu cells, the same flow): time "
               "x%.2f against wet length x%.2f (target: no faster than the wet length); "
               "full-domain path x%.2f\n",
               tm[1].cells, tm[2].cells, tm[2].best[0] / tm[1].best[0], wet,
               tm[2].best[1] / tm[1].best[1]);
        st = time_steady_state(reps < 5 ? reps : 5, &err);
    }
    for (int c = 0; c < made; c++) {
        timing_free(&tm[c]);
        teardown(&s[c]);
    }
    if (st != DFLE_OK) {
        fprintf(stderr, "process bench: %s\n", err.msg);
        return 1;
    }
    return 0;
}
