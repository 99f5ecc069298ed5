/*
 * direct.c - the direct steady state of Fig. 9 (empirical router, power
 * law alpha = 6, beta = 1, Table G1 fluvial law with k_e = 5e-14, dx =
 * 5 m, A_max = 8 km^2: 402 nodes to solve) on its two node-solve paths:
 * Newton steps with dE/d ln S from the router's and the law's derivative
 * ops, and the path of a law without them (bracket, a difference step,
 * secant steps: the path every node took before the ops existed, and the
 * one laws written in Lua take).  Printed: CPU time per steady state
 * (best and median of batches, the paths timed alternately so that the
 * machine's load weighs on both alike) beside the target, the ratio,
 * one-node erosions per node on each path, and how far apart the two
 * answers are.
 *
 *   build/bench/direct [batches]     (default 20, of 20 steady states)
 *
 * Figures only: nothing here asserts on time.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/channel.h"
#include "dfle/fluvial.h"
#include "dfle/law.h"
#include "dfle/law_power.h"
#include "dfle/model.h"
#include "dfle/router_empirical.h"
#include "dfle/solver.h"

#include "bench.h"

#define BATCH 20 /* steady states per timing: each takes ~0.1-0.3 ms */

typedef struct setup {
    dfle_channel *ch;
    dfle_fluvial *fl;
    dfle_router *rt;
    dfle_law *law[2];   /* [0] the power law, [1] it without rate_dlnS */
    dfle_law_ops plain; /* the ops of law[1] */
    dfle_model *m[2];
    double *z0;         /* the starting profile (Eq. 26) */
} setup;

static void teardown(setup *s)
{
    for (int p = 0; p < 2; p++)
        dfle_model_free(s->m[p]);
    dfle_law_free(s->law[1]); /* borrows law[0]'s state: free it first */
    dfle_law_free(s->law[0]);
    dfle_router_free(s->rt);
    dfle_fluvial_free(s->fl);
    dfle_channel_free(s->ch);
    free(s->z0);
}

static int make(setup *s, dfle_error *err)
{
    dfle_channel_opts co;
    dfle_stochastic_threshold_opts so;
    dfle_empirical_opts eo;
    dfle_power_law_opts lo;
    dfle_model_opts mo;
    int st;

    memset(s, 0, sizeof *s);
    dfle_channel_opts_default(&co);
    co.dx = 5.0, co.A_max = 8e6;
    dfle_stochastic_threshold_opts_default(&so);
    so.k_e = 5e-14;
    dfle_empirical_opts_default(&eo); /* M0 = 3000, gamma = 0.5, mu = 500, tau_y = 300 */
    dfle_power_law_opts_default(&lo);
    lo.k_df = 1e-4, lo.alpha = 6, lo.beta = 1;
    if ((st = dfle_channel_new(&co, &s->ch, err)) != DFLE_OK ||
        (st = dfle_fluvial_new_stochastic_threshold(&so, &s->fl, err)) != DFLE_OK ||
        (st = dfle_router_new_empirical(&eo, &s->rt, err)) != DFLE_OK ||
        (st = dfle_law_new_power(&lo, &s->law[0], err)) != DFLE_OK)
        return st;
    /* The same law over the same state, without its derivative op (and
     * without destroy: the state stays law[0]'s). */
    s->plain = *dfle_law_get_ops(s->law[0]);
    s->plain.rate_dlnS = NULL;
    s->plain.destroy = NULL;
    if ((st = dfle_law_new(&s->plain, dfle_law_state(s->law[0]), &s->law[1], err)) != DFLE_OK)
        return st;
    dfle_model_opts_default(&mo);
    mo.channel = s->ch, mo.fluvial = s->fl, mo.router = s->rt, mo.U = 5e-4;
    for (int p = 0; p < 2; p++) {
        mo.law = s->law[p];
        if ((st = dfle_model_new(&mo, &s->m[p], err)) != DFLE_OK)
            return st;
    }
    s->z0 = malloc(dfle_model_size(s->m[0]) * sizeof *s->z0);
    if (s->z0 == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "out of memory");
    memcpy(s->z0, dfle_model_z(s->m[0]), dfle_model_size(s->m[0]) * sizeof *s->z0);
    return DFLE_OK;
}

/* BATCH direct steady states of path p from the starting profile: CPU
 * seconds per steady state, and one-node erosions per solved node. */
static int batch(setup *s, int p, double *t, double *per_node, dfle_error *err)
{
    dfle_model *m = s->m[p];
    const size_t n = dfle_model_size(m);
    dfle_run_opts ro;
    dfle_run_result res;
    size_t ev0 = dfle_model_node_evaluations(m);
    double t0 = cpu_seconds();
    int st;

    dfle_run_opts_default(&ro);
    ro.method = DFLE_METHOD_DIRECT;
    for (int k = 0; k < BATCH; k++) {
        if ((st = dfle_model_set_z(m, s->z0, n, err)) != DFLE_OK ||
            (st = dfle_solver_run(m, &ro, &res, err)) != DFLE_OK)
            return st;
        if (!res.converged || res.fallback)
            return dfle_error_set(err, DFLE_ESTATE, "path %d: no direct steady state", p);
    }
    *t = (cpu_seconds() - t0) / BATCH;
    /* Every node but the outlet is solved once per steady state. */
    *per_node = (double)(dfle_model_node_evaluations(m) - ev0) / (double)(BATCH * (n - 1));
    return DFLE_OK;
}

int main(int argc, char **argv)
{
    const int reps = argc > 1 && atoi(argv[1]) > 0 ? atoi(argv[1]) : 20;
    setup s;
    double *t = NULL, per_node[2] = {0, 0}, dS = 0.0;
    dfle_error err;
    int st;

    if ((st = make(&s, &err)) == DFLE_OK &&
        (t = malloc(2 * (size_t)reps * sizeof *t)) == NULL)
        st = dfle_error_set(&err, DFLE_ENOMEM, "out of memory");
    for (int r = 0; r < reps && st == DFLE_OK; r++)
        for (int p = 0; p < 2 && st == DFLE_OK; p++)
            st = batch(&s, p, &t[p * reps + r], &per_node[p], &err);
    if (st == DFLE_OK) {
        const double *S0 = dfle_model_field(s.m[0], DFLE_FIELD_S, &err);
        const double *S1 = dfle_model_field(s.m[1], DFLE_FIELD_S, &err);
        for (size_t i = 0; S0 != NULL && S1 != NULL && i < dfle_model_size(s.m[0]); i++)
            dS = fmax(dS, fabs(S0[i] - S1[i]) / S1[i]);
        for (int p = 0; p < 2; p++)
            qsort(t + p * reps, (size_t)reps, sizeof *t, by_value);
        printf("direct steady state (Fig. 9), Newton with dE/d ln S: %.0f us CPU (best of %d "
               "batches of %d; median %.0f), target <= 150 us; difference-and-secant path (a "
               "law without rate_dlnS) %.0f us (median %.0f), %.2fx; one-node erosions per "
               "node %.2f against %.2f; slopes of the two paths within %.1e\n",
               1e6 * t[0], reps, BATCH, 1e6 * t[reps / 2], 1e6 * t[reps],
               1e6 * t[reps + reps / 2], t[reps] / t[0], per_node[0], per_node[1], dS);
    }
    free(t);
    teardown(&s);
    if (st != DFLE_OK) {
        fprintf(stderr, "direct bench: %s\n", err.msg);
        return 1;
    }
    return 0;
}
