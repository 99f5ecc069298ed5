/*
 * model_direct.c - the steady state without time stepping.
 *
 * At steady state every node above the outlet satisfies U = E_f(S) +
 * E_df(S) (Eq. 3 with dz/dt = 0), where E_df depends on the flow that
 * arrives from upstream.  So the profile can be built from the head down:
 *
 *  - a router routed every step (empirical): at each node solve
 *    U = E(S) with the flow re-evaluated for that slope (Theta clamped at
 *    0 where tau < tau_y).  When the root leaves tau < tau_y the flow
 *    stops there, exactly as the runout rule stops it, and every node
 *    below is fluvial only.  One pass, no time, no iteration;
 *  - a router routed rarely (process-based): route over the current
 *    profile, solve every node with that flow's Eq. (11) factor, rebuild
 *    the profile and route again, until no slope changes by more than
 *    direct_tol (relative).  Oscillating rounds are damped.
 *
 * Either way the result is then evaluated exactly as the explicit method
 * evaluates a state, and accepted only if it meets the same steady-state
 * test (max |dz/dt| <= tol U).  If no slope balances U somewhere (say,
 * below the runout with fluvial erosion off), or the rounds do not
 * settle, or the test fails, the run continues by implicit time stepping
 * from where it got to, and the result says so (fallback, note).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "model/model_internal.h"

#define MAX_ROUNDS 60

/* The profile from slopes S (nodes 0..n-2), outlet elevation kept. */
static void build_profile(dfle_model *m, const double *S)
{
    for (size_t i = m->n - 1; i-- > 0;)
        m->z[i] = m->z[i + 1] + S[i] * m->dx;
    dfle_mi_touch(m);
}

/* Head-down pass with a flow evaluated node by node. */
static int solve_local(dfle_model *m, double *S, dfle_error *err)
{
    int reach = m->rt != NULL;
    for (size_t i = 0; i + 1 < m->n; i++) {
        int goes_on;
        int st = dfle_mi_solve_node(m, i, m->U, 0.0, reach, i > 0 ? S[i - 1] : m->S[0], &S[i],
                                    &goes_on, err);
        if (st != DFLE_OK)
            return st;
        reach = reach && goes_on; /* once stopped, the flow stays stopped */

    }
    return DFLE_OK;
}

/* Rounds of routing and solving for a router routed rarely. */
static int solve_rounds(dfle_model *m, const dfle_run_opts *o, double *S, size_t *rounds,
                        dfle_error *err)
{
    double omega = 1.0, change_prev = INFINITY;
    for (*rounds = 1; *rounds <= MAX_ROUNDS; (*rounds)++) {
        double change = 0.0;
        int st;
        dfle_model_invalidate_flow(m); /* route over this profile */
        if ((st = dfle_mi_evaluate(m, err)) != DFLE_OK)
            return st;
        for (size_t i = 0; i + 1 < m->n; i++) {
            double s_new;
            st = dfle_mi_solve_node(m, i, m->U, 0.0, i < m->flow.runout_end, m->S[i], &s_new,
                                    NULL, err);
            if (st != DFLE_OK)
                return st;
            change = fmax(change, fabs(s_new - m->S[i]) / fmax(fabs(m->S[i]), 1e-12));
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
        for (size_t i = 0; i + 1 < m->n; i++)
            S[i] = m->S[i] + omega * (S[i] - m->S[i]);
        build_profile(m, S);
    }
    return dfle_error_set(err, DFLE_EFIT,
                          "model: routing and solving did not settle in %d rounds", MAX_ROUNDS);
}

int dfle_mi_run_direct(dfle_model *m, const dfle_run_opts *o, dfle_run_result *res,
                       dfle_error *err)
{
    const size_t routings0 = m->routings;
    double *S = m->z_work;
    dfle_error why;
    size_t rounds = 1;
    int st;

    res->method = DFLE_METHOD_DIRECT;
    if ((st = dfle_mi_evaluate(m, err)) != DFLE_OK)
        return st;
    memcpy(m->z_save, m->z, m->n * sizeof *m->z); /* to fall back from */
    if (m->rt == NULL || dfle_router_is_local(m->rt)) {
        st = solve_local(m, S, &why);
        if (st == DFLE_OK)
            build_profile(m, S);
    } else {
        st = solve_rounds(m, o, S, &rounds, &why);
    }
    res->iterations = rounds;
    if (st == DFLE_OK) {
        if ((st = dfle_mi_evaluate(m, err)) != DFLE_OK)
            return st;
        res->rate_ratio = dfle_mi_rate_ratio(m);
        if (res->rate_ratio <= o->tol) {
            res->converged = 1;
            res->reason = DFLE_STOP_STEADY;
            res->routings = m->routings - routings0;
            return DFLE_OK;
        }
        snprintf(why.msg, sizeof why.msg,
                 "the direct solution leaves max|dz/dt|/U = %.3g > tol", res->rate_ratio);
    } else if (st != DFLE_EFIT && st != DFLE_EINVAL) {
        if (err != NULL)
            *err = why;
        return st; /* NaN, memory, a failing law: not something to step around */
    } else {
        /* No slope balanced U somewhere: start stepping from where we were. */
        memcpy(m->z, m->z_save, m->n * sizeof *m->z);
        dfle_mi_touch(m);
    }
    res->fallback = 1;
    snprintf(res->note, sizeof res->note, "direct: %.110s; continued by implicit stepping",
             why.msg);
    res->routings = m->routings - routings0;
    return dfle_mi_run_implicit(m, o, res, err);
}
