/*
 * model_implicit.c - backward-Euler stepping of Eq. (3).
 *
 *   z_i' = z_i + dt (U - E_i(S_i')),   S_i' = (z_i' - z_{i+1}') / dx
 *
 * Erosion at a node depends only on its own (downstream) slope, so the
 * step is solved exactly, node by node, from the outlet (fixed) up: at
 * node i the new elevation below is known and the node's own equation,
 * E(S) + (dx/dt) S = U + (z_i - z_{i+1}')/dt, is one scalar root
 * (model_node.c).  No linear system, no stability limit, and uplift
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

#include "model/model_internal.h"

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
} implicit_state;

/* Large steps that stop making progress for this many steps hand over
 * to explicit steps (routers routed rarely only; see steady_advance). */
#define STALL_STEPS 4

/* One backward-Euler step of dt [yr] from the current (evaluated) state. */
static int be_step(dfle_model *m, double dt, dfle_error *err)
{
    const size_t n = m->n;
    const size_t reach = m->rt != NULL ? m->flow.runout_end : 0;
    double *zn = m->z_work;
    int st;

    zn[n - 1] = m->z[n - 1];
    for (size_t i = n - 1; i-- > 0;) {
        double S;
        st = dfle_mi_solve_node(m, i, m->U + (m->z[i] - zn[i + 1]) / dt, m->dx / dt,
                                i < reach, (m->z[i] - m->z[i + 1]) / m->dx, &S, NULL, err);
        if (st != DFLE_OK)
            return st;
        zn[i] = zn[i + 1] + S * m->dx;
    }
    memcpy(m->z, zn, n * sizeof *zn);
    dfle_mi_touch(m);
    return DFLE_OK;
}

static int steady_advance(dfle_model *m, implicit_state *s, double dt_limit, double *dt_taken,
                          dfle_error *err)
{
    double r = dfle_mi_rate_ratio(m), dt;

    /* A router routed rarely makes the steady state a fixed point of
     * routing and stepping.  Huge steps jump to the steady state of the
     * last flow, the slopes move past the re-routing threshold, the flow
     * changes at its tip, and the residual can cycle.  Small explicit
     * steps re-route at small slope increments, which damps the cycle, so
     * once large steps stop gaining the run finishes with those. */
    if (s->finishing)
        return dfle_mi_explicit_advance(m, dt_limit, dt_taken, NULL, err);
    if (r < 0.5 * s->r_best) {
        s->r_best = r;
        s->stalled = 0;
    } else if (++s->stalled >= STALL_STEPS && m->rt != NULL && !dfle_router_is_local(m->rt)) {
        s->finishing = 1;
        snprintf(s->res->note, sizeof s->res->note,
                 "implicit: large steps stalled at max|dz/dt|/U = %.3g; finished with "
                 "explicit steps", r);
        return dfle_mi_explicit_advance(m, dt_limit, dt_taken, NULL, err);
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
    return be_step(m, dt, err);
}

/* Step doubling: accept when one step of dt and two of dt/2 agree to
 * within rtol U dt (the local error against the uplift of the step);
 * the two half steps are kept. */
static int transient_advance(dfle_model *m, implicit_state *s, double dt_limit,
                             double *dt_taken, dfle_error *err)
{
    const size_t n = m->n;
    double *z_start = m->z_save, *z_full = m->S_pert;
    int st;

    memcpy(z_start, m->z, n * sizeof *z_start);
    for (int tries = 0; tries < MAX_REJECTIONS; tries++) {
        double dt = fmin(s->dt, dt_limit), diff = 0.0, zmax = 0.0, scale, q;
        if ((st = be_step(m, dt, err)) != DFLE_OK)
            return st;
        memcpy(z_full, m->z, n * sizeof *z_full);
        memcpy(m->z, z_start, n * sizeof *z_start);
        dfle_mi_touch(m);
        if ((st = dfle_mi_evaluate(m, err)) != DFLE_OK || (st = be_step(m, 0.5 * dt, err)) != DFLE_OK ||
            (st = dfle_mi_evaluate(m, err)) != DFLE_OK || (st = be_step(m, 0.5 * dt, err)) != DFLE_OK)
            return st;
        for (size_t i = 0; i < n; i++) {
            diff = fmax(diff, fabs(m->z[i] - z_full[i]));
            zmax = fmax(zmax, fabs(m->z[i]));
        }
        /* Error per step against uplift per step: summed over a run, the
         * error stays below rtol times the uplift of the run. */
        scale = s->rtol * m->U * dt + 1e-12 * (zmax + 1.0);
        q = diff > 0 ? 0.9 * sqrt(scale / diff) : 4.0;
        if (diff <= scale) {
            s->dt = dt * fmin(4.0, fmax(0.2, q));
            *dt_taken = dt;
            return DFLE_OK;
        }
        /* Rejected: back to the start, smaller step. */
        memcpy(m->z, z_start, n * sizeof *z_start);
        dfle_mi_touch(m);
        if ((st = dfle_mi_evaluate(m, err)) != DFLE_OK)
            return st;
        s->dt = dt * fmax(0.2, q);
    }
    return dfle_error_set(err, DFLE_ENUMERIC,
                          "model: implicit step rejected %d times at t = %g yr (step %g yr)",
                          MAX_REJECTIONS, m->time, s->dt);
}

static int implicit_advance(dfle_model *m, double dt_limit, double *dt_taken, void *state,
                            dfle_error *err)
{
    implicit_state *s = state;
    return s->steady ? steady_advance(m, s, dt_limit, dt_taken, err)
                     : transient_advance(m, s, dt_limit, dt_taken, err);
}

int dfle_mi_run_implicit(dfle_model *m, const dfle_run_opts *o, dfle_run_result *res,
                         dfle_error *err)
{
    implicit_state s = {
        .steady = o->tol > 0,
        .dt = o->tol > 0 ? STEADY_DT_FIRST : fmin(m->dt_max, o->max_time),
        .r_prev = -1.0,
        .r_best = INFINITY,
        .rtol = o->rtol,
        .res = res,
    };
    res->method = DFLE_METHOD_IMPLICIT;
    return dfle_mi_drive(m, o, implicit_advance, &s, res, err);
}
