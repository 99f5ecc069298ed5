/*
 * solver_implicit.c - backward-Euler stepping of Eq. (3).
 *
 *   z_i' = z_i + dt (U - E_i(S_i')),   S_i' = (z_i' - z_r') / L_i
 *
 * Erosion at a node depends only on its own slope to its receiver r, so
 * the step is solved exactly, node by node, in stack order from base
 * level (fixed) up (Braun and Willett 2013): at node i the receiver's new
 * elevation is known and the node's own equation,
 * E(S) + (L/dt) S = U + (z_i - z_r')/dt, is one scalar root
 * (solver_node.c).  No linear system, no stability limit, and uplift
 * enters every step in full, so the steady state has no time-step bias:
 * where dz/dt = 0 the equation is exactly U = E(S).
 *
 * What is lagged by one step: where the debris flow stops (the runout
 * rule needs the whole profile above) and, for a router routed rarely,
 * its cached Eq. (11) factor.  Both are refreshed at the start of every
 * step, so a converged state is consistent; the steady-state test is the
 * explicit method's own evaluation.
 *
 * Steady-state runs grow the step geometrically (the steps then act like
 * Newton iterations on the steady state) and cut it when the residual
 * grows.  Transient runs (tol = 0) adapt the step to a local error
 * estimate by step doubling: one step of dt against two of dt/2.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <stdlib.h>

#include "solvers/solver_internal.h"

#define STEADY_DT_FIRST 100.0   /* [yr] */
#define STEADY_DT_GROWTH 4.0
#define STEADY_DT_LARGEST 1e9   /* [yr] */
#define MAX_REJECTIONS 60

typedef struct implicit_state {
    int steady;     /* 1: steady-state run, 0: transient with error control */
    double dt;      /* next step to try [yr] */
    double r_prev;  /* rate ratio before the previous step (steady runs) */
    double r_best;  /* smallest rate ratio so far (steady runs) */
    int stalled;    /* steps without halving r_best */
    int finishing;  /* 1: finishing with explicit steps */
    double rtol;
    dfle_run_result *res;
    double *z_new, *z_start, *z_full; /* n values each (one block) */
    /* Transients: explicit steps to take before trying a large implicit
     * step again, and the wait after the next failure (doubling). */
    unsigned explicit_left, explicit_wait;
} implicit_state;

/* Large steps that stop making progress for this many steps hand over
 * to explicit steps (routers routed rarely only; see steady_advance). */
#define STALL_STEPS 4

/* One backward-Euler step of dt [yr] from the current (evaluated) state. */
static int be_step(dfle_model *m, implicit_state *s, double dt, dfle_error *err)
{
    const size_t n = dfle_model_size(m);
    const size_t *stack = dfle_model_stack(m), *recv = dfle_model_receivers(m);
    const double *L = dfle_model_flow_length(m), U = dfle_model_U(m);
    double *z = dfle_model_z(m), *zn = s->z_new;
    int st;

    for (size_t k = 0; k < n; k++) {
        const size_t i = stack[k], r = recv[i];
        double S;
        if (dfle_model_is_base(m, i)) {
            zn[i] = z[i];
            continue;
        }
        st = dfle_solve_node(m, i, U + (z[i] - zn[r]) / dt, L[i] / dt,
                             dfle_model_flow_reaches(m, i), (z[i] - z[r]) / L[i], &S, NULL, err);
        if (st != DFLE_OK)
            return st;
        zn[i] = zn[r] + S * L[i];
    }
    memcpy(z, zn, n * sizeof *zn);
    dfle_model_touch(m);
    return DFLE_OK;
}

static int steady_advance(dfle_model *m, implicit_state *s, double dt_limit, double *dt_taken,
                          dfle_error *err)
{
    double r = dfle_model_rate_ratio(m), dt;
    const dfle_router *rt = dfle_model_router(m);

    /* A router routed rarely makes the steady state a fixed point of
     * routing and stepping.  Huge steps jump to the steady state of the
     * last flow, the slopes move past the re-routing threshold, the flow
     * changes at its tip, and the residual can cycle.  Small explicit
     * steps re-route at small slope increments, which damps the cycle, so
     * once large steps stop gaining the run finishes with those. */
    if (s->finishing)
        return dfle_explicit_advance(m, dt_limit, dt_taken, NULL, err);
    if (r < 0.5 * s->r_best) {
        s->r_best = r;
        s->stalled = 0;
    } else if (++s->stalled >= STALL_STEPS && rt != NULL && !dfle_router_is_local(rt)) {
        s->finishing = 1;
        snprintf(s->res->note, sizeof s->res->note,
                 "implicit: large steps stalled at max|dz/dt|/U = %.3g; finished with "
                 "explicit steps", r);
        return dfle_explicit_advance(m, dt_limit, dt_taken, NULL, err);
    }
    if (s->r_prev >= 0) {
        if (r < s->r_prev)
            s->dt = fmin(s->dt * STEADY_DT_GROWTH, STEADY_DT_LARGEST);
        else
            s->dt = fmax(s->dt / STEADY_DT_GROWTH, STEADY_DT_FIRST);
    }
    s->r_prev = r;
    dt = fmin(s->dt, dt_limit);
    *dt_taken = dt;
    return be_step(m, s, dt, err);
}

/* Explicit steps after a failed large step before the next try, at
 * most (each failure doubles the wait, a success resets it). */
#define EXPLICIT_WAIT_MAX 256u
/* Error control asking for steps this far below the explicit stability
 * limit is reacting to something that is not smooth, not to accuracy. */
#define SUB_CFL_FLOOR 1e-3

/* A safety net, not the rule: where error control wants steps far below
 * the explicit CFL step, an explicit step is taken instead (stable there
 * by construction, as accurate as the paper's method, far cheaper than
 * three backward-Euler sweeps), so no state can make the run crawl in
 * steps of 1e-11 yr.  Large implicit steps are tried again after a wait
 * that doubles with each failure. */
static int explicit_instead(dfle_model *m, implicit_state *s, double dt_limit,
                            double *dt_taken, dfle_error *err)
{
    int st = dfle_explicit_advance(m, dt_limit, dt_taken, NULL, err);
    if (st == DFLE_OK && s->explicit_left > 0)
        s->explicit_left--;
    return st;
}

/* Step doubling: accept when one step of dt and two of dt/2 agree to
 * within rtol times the larger of the step's uplift U dt and its largest
 * change in elevation; the two half steps are kept.
 *
 * All three sweeps use the flow of the step's start (the lagged runout
 * and, for a router routed rarely, the lagged Eq. 11 factor): the state
 * is not evaluated between the half steps.  Otherwise a runout that moves
 * by a node within the step makes the full step and the half steps see
 * different erosion there, a jump that does not shrink like dt^2, and
 * error control would halve the step without end (it reached 1e-11 yr).
 * The runout is refreshed at the start of the next step, as for a single
 * backward-Euler step.
 *
 * Relative to the change as well as to uplift, because a profile far
 * from equilibrium (a fluvial start meeting debris flows: tens of metres
 * in the first year) changes thousands of times faster than U, and an
 * error of rtol U dt would there mean steps of 1e-8 yr. */
static int transient_advance(dfle_model *m, implicit_state *s, double dt_limit,
                             double *dt_taken, dfle_error *err)
{
    const size_t n = dfle_model_size(m);
    double *z = dfle_model_z(m), *z_start = s->z_start, *z_full = s->z_full, dt_cfl;
    int st;

    if (s->explicit_left > 0)
        return explicit_instead(m, s, dt_limit, dt_taken, err);
    if ((st = dfle_explicit_step(m, &dt_cfl, err)) != DFLE_OK)
        return st;
    memcpy(z_start, z, n * sizeof *z_start);
    for (int tries = 0; tries < MAX_REJECTIONS; tries++) {
        double dt = fmin(s->dt, dt_limit), diff = 0.0, zmax = 0.0, change = 0.0, scale, q;
        if (dt < SUB_CFL_FLOOR * dt_cfl && dt < dt_limit) {
            /* Error control asks for less than an explicit step. */
            s->explicit_wait = s->explicit_wait ? 2 * s->explicit_wait : 1;
            if (s->explicit_wait > EXPLICIT_WAIT_MAX)
                s->explicit_wait = EXPLICIT_WAIT_MAX;
            s->explicit_left = s->explicit_wait;
            s->dt = dt_cfl; /* what the next try starts from */
            if (!dfle_model_is_evaluated(m) && (st = dfle_model_evaluate(m, err)) != DFLE_OK)
                return st; /* z is back at the start after a rejection */
            return explicit_instead(m, s, dt_limit, dt_taken, err);
        }
        if ((st = be_step(m, s, dt, err)) != DFLE_OK)
            return st;
        memcpy(z_full, z, n * sizeof *z_full);
        memcpy(z, z_start, n * sizeof *z_start);
        if ((st = be_step(m, s, 0.5 * dt, err)) != DFLE_OK ||
            (st = be_step(m, s, 0.5 * dt, err)) != DFLE_OK)
            return st;
        for (size_t i = 0; i < n; i++) {
            diff = fmax(diff, fabs(z[i] - z_full[i]));
            change = fmax(change, fabs(z[i] - z_start[i]));
            zmax = fmax(zmax, fabs(z[i]));
        }
        /* Summed over a run, the error stays below rtol times the larger
         * of its uplift and its change. */
        scale = s->rtol * fmax(dfle_model_U(m) * dt, change) + 1e-12 * (zmax + 1.0);
        q = diff > 0 ? 0.9 * sqrt(scale / diff) : 4.0;
        if (diff <= scale) {
            s->dt = dt * fmin(4.0, fmax(0.2, q));
            s->explicit_wait = 0;
            *dt_taken = dt;
            return DFLE_OK;
        }
        /* Rejected: back to the start (whose flow is still the model's:
         * nothing was evaluated), smaller step. */
        memcpy(z, z_start, n * sizeof *z_start);
        dfle_model_touch(m);
        s->dt = dt * fmax(0.2, q);
    }
    return dfle_error_set(err, DFLE_ENUMERIC,
                          "model: implicit step rejected %d times at t = %g yr (step %g yr)",
                          MAX_REJECTIONS, dfle_model_time(m), s->dt);
}

static int implicit_advance(dfle_model *m, double dt_limit, double *dt_taken, void *state,
                            dfle_error *err)
{
    implicit_state *s = state;
    return s->steady ? steady_advance(m, s, dt_limit, dt_taken, err)
                     : transient_advance(m, s, dt_limit, dt_taken, err);
}

static int implicit_run(dfle_model *m, const dfle_run_opts *o, dfle_run_result *res,
                        dfle_error *err)
{
    const size_t n = dfle_model_size(m);
    implicit_state s = {
        .steady = o->tol > 0,
        .dt = o->tol > 0 ? STEADY_DT_FIRST : fmin(dfle_model_dt_max(m), o->max_time),
        .r_prev = -1.0,
        .r_best = INFINITY,
        .rtol = o->rtol,
        .res = res,
    };
    double *block = malloc(3 * n * sizeof *block);
    int st;

    if (block == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "model: out of memory for %zu nodes", n);
    s.z_new = block;
    s.z_start = block + n;
    s.z_full = block + 2 * n;
    res->method = DFLE_METHOD_IMPLICIT;
    st = dfle_stepping_run(m, o, implicit_advance, &s, res, err);
    free(block);
    return st;
}

const dfle_solver_ops dfle_solver_implicit = {
    .version = DFLE_SOLVER_OPS_VERSION,
    .name = "implicit",
    .run = implicit_run,
};
