/*
 * solver_direct.c - the steady state without time stepping.
 *
 * At steady state every node above base level satisfies U = E_f(S) +
 * E_df(S) (Eq. 3 with dz/dt = 0), where E_df depends on the flow that
 * arrives from upstream.  So the slopes can be found from the heads down
 * (reverse stack order: every node after its donors) and the profile
 * built from base level up (stack order):
 *
 *  - a router routed every step (empirical): at each node solve
 *    U = E(S) with the flow re-evaluated for that slope (Theta clamped at
 *    0 where tau < tau_y).  When the root leaves tau < tau_y the flow
 *    stops there, exactly as the runout rule stops it, and no node below
 *    is reached by it.  One pass, no time, no iteration;
 *  - a router routed rarely (process-based): route over the current
 *    profile, solve every node with that flow's Eq. (11) factor, rebuild
 *    the profile and route again, until no slope changes by more than
 *    direct_tol (relative).  Oscillating rounds are damped.
 *
 * Either way the result is then evaluated exactly as the explicit method
 * evaluates a state, and accepted only if it meets the same steady-state
 * test (max |dz/dt| <= tol U).  If no slope balances U somewhere (say,
 * below the runout with fluvial erosion off), or the rounds do not
 * settle, or the test fails, the run returns DFLE_EFIT with the reason,
 * the state left where time stepping should continue from; the
 * dispatcher (solver.c) then continues by implicit stepping.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "solvers/solver_internal.h"

#define MAX_ROUNDS 60

typedef struct direct_work {
    double *S;       /* the slopes being solved for              */
    double *guess;   /* a starting slope per node                */
    double *z_save;  /* the state to fall back from              */
    double *reach;   /* debris flows arriving at the node      */
} direct_work;

/* The profile from slopes S (non-base nodes), base levels kept. */
static void build_profile(dfle_model *m, const double *S)
{
    const size_t n = dfle_model_size(m);
    const size_t *stack = dfle_model_stack(m), *recv = dfle_model_receivers(m);
    const double *L = dfle_model_flow_length(m);
    double *z = dfle_model_z(m);
    for (size_t k = 0; k < n; k++) {
        const size_t i = stack[k];
        if (!dfle_model_is_base(m, i))
            z[i] = z[recv[i]] + S[i] * L[i];
    }
    dfle_model_touch(m);
}

/* Heads-down pass with a flow evaluated node by node.  A debris flow
 * starts at every source of the network and goes on below a node only
 * if it goes on at that node; where flows meet they add up. */
static int solve_local(dfle_model *m, direct_work *w, dfle_error *err)
{
    const size_t n = dfle_model_size(m);
    const size_t *stack = dfle_model_stack(m), *recv = dfle_model_receivers(m);
    const double *L = dfle_model_flow_length(m), *z = dfle_model_z(m);
    const unsigned char *source = dfle_network_sources(dfle_model_network(m));
    const int has_flow = dfle_model_router(m) != NULL;

    /* The profile as it is gives the heads their first guess (the root
     * does not depend on it); every other node starts from the slope
     * solved just above it.  Nothing here needs the profile's flow, so
     * it is not routed. */
    for (size_t i = 0; i < n; i++) {
        w->guess[i] = (z[i] - z[recv[i]]) / L[i];
        w->reach[i] = has_flow && source[i];
    }
    for (size_t k = n; k-- > 0;) {
        const size_t i = stack[k];
        int goes_on;
        int st;
        if (dfle_model_is_base(m, i))
            continue;
        st = dfle_solve_node(m, i, dfle_model_U(m), 0.0, w->reach[i], w->guess[i], &w->S[i],
                             &goes_on, err);
        if (st != DFLE_OK)
            return st;
        /* Once stopped, a flow stays stopped. */
        if (goes_on && w->reach[i] > 0)
            w->reach[recv[i]] += w->reach[i];
        w->guess[recv[i]] = w->S[i];
    }
    build_profile(m, w->S);
    return DFLE_OK;
}

/* Rounds of routing and solving for a router routed rarely. */
static int solve_rounds(dfle_model *m, const dfle_run_opts *o, direct_work *w, size_t *rounds,
                        dfle_error *err)
{
    const size_t n = dfle_model_size(m);
    double *S = w->S, omega = 1.0, change_prev = INFINITY;
    for (*rounds = 1; *rounds <= MAX_ROUNDS; (*rounds)++) {
        const double *Sm;
        double change = 0.0;
        int st;
        /* Route over this profile (the first round's was routed by the
         * caller). */
        if (*rounds > 1) {
            dfle_model_invalidate_flow(m);
            if ((st = dfle_model_evaluate(m, err)) != DFLE_OK)
                return st;
        }
        Sm = dfle_model_field(m, DFLE_FIELD_S, err);
        for (size_t i = 0; i < n; i++) {
            double s_new;
            if (dfle_model_is_base(m, i))
                continue;
            st = dfle_solve_node(m, i, dfle_model_U(m), 0.0, dfle_model_flow_reaches(m, i), Sm[i],
                                 &s_new, NULL, err);
            if (st != DFLE_OK)
                return st;
            change = fmax(change, fabs(s_new - Sm[i]) / fmax(fabs(Sm[i]), 1e-12));
            S[i] = s_new;
        }
        if (change <= o->direct_tol) {
            /* Settled: keep the slopes that solve U = E with this flow. */
            build_profile(m, S);
            return DFLE_OK;
        }
        /* A round that moved the slopes more than the last one is
         * overshooting: damp the update. */
        if (change > change_prev && omega > 0.125)
            omega *= 0.5;
        change_prev = change;
        for (size_t i = 0; i < n; i++)
            if (!dfle_model_is_base(m, i))
                S[i] = Sm[i] + omega * (S[i] - Sm[i]);
        build_profile(m, S);
    }
    return dfle_error_set(err, DFLE_EFIT,
                          "model: routing and solving did not settle in %d rounds", MAX_ROUNDS);
}

static int direct_solve(dfle_model *m, const dfle_run_opts *o, direct_work *w,
                        dfle_run_result *res, dfle_error *err)
{
    const size_t n = dfle_model_size(m), routings0 = dfle_model_routings(m);
    const dfle_router *rt = dfle_model_router(m);
    dfle_error why;
    size_t rounds = 1;
    int st;

    res->method = DFLE_METHOD_DIRECT;
    memcpy(w->z_save, dfle_model_z(m), n * sizeof *w->z_save); /* to fall back from */
    if (rt == NULL || dfle_router_is_local(rt)) {
        /* The local pass needs only the head slopes of the starting
         * state, not its flow: nothing is routed before it. */
        st = solve_local(m, w, &why);
    } else {
        /* The first round's routing, over the starting profile; an error
         * here (a law the router cannot use) is the run's, not a reason
         * to fall back. */
        dfle_model_invalidate_flow(m);
        if ((st = dfle_model_evaluate(m, err)) != DFLE_OK)
            return st;
        st = solve_rounds(m, o, w, &rounds, &why);
    }
    res->iterations = rounds;
    if (st == DFLE_OK) {
        if ((st = dfle_model_evaluate(m, err)) != DFLE_OK)
            return st;
        res->rate_ratio = dfle_model_rate_ratio(m);
        res->routings = dfle_model_routings(m) - routings0;
        if (res->rate_ratio <= o->tol) {
            res->converged = 1;
            res->reason = DFLE_STOP_STEADY;
            return DFLE_OK;
        }
        /* Close, not there: time stepping continues from here. */
        return dfle_error_set(err, DFLE_EFIT,
                              "the direct solution leaves max|dz/dt|/U = %.3g > tol",
                              res->rate_ratio);
    }
    if (st != DFLE_EFIT && st != DFLE_EINVAL) {
        if (err != NULL)
            *err = why;
        return st; /* NaN, memory, a failing law: not something to step around */
    }
    /* No slope balanced U somewhere: time stepping starts from where we were. */
    memcpy(dfle_model_z(m), w->z_save, n * sizeof *w->z_save);
    dfle_model_touch(m);
    res->routings = dfle_model_routings(m) - routings0;
    if (err != NULL)
        *err = why;
    return err != NULL ? (err->code = DFLE_EFIT) : DFLE_EFIT;
}

static int direct_run(dfle_model *m, const dfle_run_opts *o, dfle_run_result *res,
                      dfle_error *err)
{
    const size_t n = dfle_model_size(m);
    direct_work w;
    void *block = malloc(4 * n * sizeof(double));
    int st;

    if (block == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "model: out of memory for %zu nodes", n);
    w.S = block;
    w.guess = w.S + n;
    w.z_save = w.guess + n;
    w.reach = w.z_save + n;
    st = direct_solve(m, o, &w, res, err);
    free(block);
    return st;
}

const dfle_solver_ops dfle_solver_direct = {
    .version = DFLE_SOLVER_OPS_VERSION,
    .name = "direct",
    .run = direct_run,
};
