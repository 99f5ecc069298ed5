/*
 * solver.h - reaching a state of the model (model.h): time stepping of
 * Eq. (3) and steady states.
 *
 * The solvers sit above the model and use only its public API: the model
 * evaluates rates for a state, a solver decides how the state moves.
 * Three methods reach the same steady state (doc/solvers.md):
 *  - EXPLICIT: forward Euler with the CFL step, as in the paper (the
 *    reference).  Erosion depends on the slope to the receiver, so a
 *    perturbation travels upstream like a kinematic wave with speed
 *    c = dE/dS [m/yr]; the step is dt = cfl * min_i L_i / c_i, capped at
 *    dt_max and at the time left in the run;
 *  - IMPLICIT: backward Euler in stack order, one scalar Newton solve per
 *    node; unconditionally stable;
 *  - DIRECT: steady state without time, node by node.
 * Steady state (explicit and configurable): the run stops when
 *   max over non-base nodes of |dz/dt| <= tol * U.
 */
#ifndef DFLE_SOLVER_H
#define DFLE_SOLVER_H

#include <signal.h>
#include <stddef.h>
#include "dfle/error.h"
#include "dfle/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Progress hook: called every few hundred steps with the state of the
 * run; return nonzero to stop it (the run then fails with
 * DFLE_ECANCELED). */
typedef struct dfle_run_status {
    double time;       /* years simulated in this run          */
    double max_time;   /* limit of this run [yr]               */
    size_t steps;      /* steps taken in this run              */
    double dt;         /* last time step [yr]                  */
    double rate_ratio; /* max |dz/dt| / U                      */
    double tol;        /* steady-state target for rate_ratio   */
    double fraction;   /* rough completion estimate in [0, 1]  */
    const char *ratio_name; /* what rate_ratio is, for a display
                             * (NULL: "max|dz/dt|/U")           */
} dfle_run_status;
typedef int (*dfle_progress_fn)(void *ud, const dfle_run_status *st);

/* How to reach the answer (all reach the same steady state):
 *  - EXPLICIT: forward Euler with the CFL step, as in the paper (the
 *    reference);
 *  - IMPLICIT: backward Euler swept from the outlet up, one scalar
 *    Newton solve per node; unconditionally stable.  For steady states
 *    the step grows geometrically; for transients (tol = 0) it is
 *    adapted to the error estimate `rtol` by step doubling;
 *  - DIRECT: steady state only.  Empirical router: solve U = E_f + E_df
 *    node by node from the head down, stopping the flow where it would
 *    stop.  Process-based router: alternate routing and solving until no
 *    slope changes by more than direct_tol (relative).  If no consistent
 *    solution is found, the run falls back to IMPLICIT stepping and says
 *    so in the result;
 *  - AUTO: DIRECT for steady states, EXPLICIT otherwise. */
enum dfle_method {
    DFLE_METHOD_EXPLICIT = 0,
    DFLE_METHOD_IMPLICIT = 1,
    DFLE_METHOD_DIRECT = 2,
    DFLE_METHOD_AUTO = 3
};
const char *dfle_method_name(int method); /* "explicit", ... */
int dfle_method_lookup(const char *name); /* or -1 */

typedef struct dfle_run_opts {
    double max_time;  /* simulated years allowed for this run, > 0        */
    double tol;       /* steady when max|dz/dt| <= tol*U; 0 = never stop  */
    size_t max_steps; /* hard cap on steps (guards against a hang)        */
    int method;       /* enum dfle_method                    (EXPLICIT)   */
    double rtol;      /* IMPLICIT transients: local error per step at
                       * most rtol U dt [m], so a run's error stays
                       * below rtol times its uplift        (1e-3)      */
    double direct_tol; /* DIRECT, routed rarely: stop when no slope
                        * changes by more than this, relative (2e-3).
                        * A routed flow's erosion sum answers slope
                        * changes in small steps (cells crossing the Phi
                        * threshold), so rounds settle to ~1e-3, no less */
    /* Optional: record z at these times [yr since the start of the run,
     * increasing, <= max_time] into record_z (n_record x n values).
     * The steps land on each time exactly. */
    size_t n_record;
    const double *record_times;
    double *record_z;
    dfle_progress_fn progress; /* optional */
    void *progress_ud;
    /* Optional, time-varying uplift U(t) (doc/laws.md): set *U [m/yr] for
     * model time t [yr, dfle_model_time] and return 0, or a negative
     * status with err set (the run stops with it).  Called before every
     * landscape step, and once before a direct solve; the model's U
     * becomes the value returned.  The steady-state test compares |dz/dt|
     * with tol times the current U. */
    int (*uplift)(void *ud, double t, double *U, dfle_error *err);
    void *uplift_ud;
    /* Optional: a flag a signal handler sets (SIGINT).  When it is
     * nonzero the run stops before its next step, keeping the state it
     * reached, with reason DFLE_STOP_INTERRUPTED (not an error). */
    const volatile sig_atomic_t *interrupt;
} dfle_run_opts;

/* tol = 1e-3, max_time = 2e7 yr, max_steps = 1e7 (about ten minutes on
 * the default 403-node grid: long enough for any sane run, short enough
 * that a run with a vanishing time step ends with reason "steps"). */
void dfle_run_opts_default(dfle_run_opts *o);

/* Check the options as dfle_solver_run does, for a run to steady state
 * (`steady`: tol > 0) or any run: DFLE_EINVAL with a message naming the
 * option and its value ("max_time must be > 0 yr (got 0)") without a
 * prefix, for the caller to add its own (a binding its function's name;
 * dfle_solver_run says "model: "). */
int dfle_run_opts_check(const dfle_run_opts *o, int steady, dfle_error *err);

enum dfle_stop_reason {
    DFLE_STOP_STEADY = 0, /* the steady-state criterion was met     */
    DFLE_STOP_TIME = 1,   /* max_time was reached                   */
    DFLE_STOP_STEPS = 2,  /* max_steps was reached                  */
    DFLE_STOP_INTERRUPTED = 3 /* the interrupt flag was raised      */
};
const char *dfle_stop_reason_name(int reason); /* "steady", "time", "steps", "interrupted" */

typedef struct dfle_run_result {
    int converged;     /* 1 when reason == DFLE_STOP_STEADY            */
    int reason;        /* enum dfle_stop_reason                        */
    double time;       /* years simulated in this run                  */
    size_t steps;      /* time steps taken                             */
    size_t routings;   /* debris flows routed                          */
    double rate_ratio; /* final max |dz/dt| / U                        */
    double dt_min, dt_max; /* smallest and largest step taken [yr]     */
    size_t nonpositive_slope_nodes; /* node-steps with S <= 0 (no erosion there) */
    int method;        /* the method that produced the result        */
    int fallback;      /* 1: DIRECT found no consistent solution and
                        * the run continued with IMPLICIT stepping    */
    size_t iterations; /* DIRECT: routing-and-solving rounds          */
    size_t n_recorded; /* record times reached                        */
    char note[160];    /* why a fallback happened, else empty         */
} dfle_run_result;

/* A solver: one static const table per method, in a file of its own.
 * run() starts from the model's current state and adds to `res` (so a
 * fallback run continues the tally); it may assume `opts` was checked. */
#define DFLE_SOLVER_OPS_VERSION 1

typedef struct dfle_solver_ops {
    int version;      /* DFLE_SOLVER_OPS_VERSION */
    const char *name; /* "explicit", "implicit", "direct" */
    int (*run)(dfle_model *m, const dfle_run_opts *opts, dfle_run_result *res,
               dfle_error *err);
} dfle_solver_ops;

extern const dfle_solver_ops dfle_solver_explicit; /* solver_explicit.c */
extern const dfle_solver_ops dfle_solver_implicit; /* solver_implicit.c */
extern const dfle_solver_ops dfle_solver_direct;   /* solver_direct.c   */

/* Check opts, pick the method (AUTO: DIRECT for steady states, else
 * EXPLICIT) and run it until steady state, max_time or max_steps; when
 * DIRECT finds no consistent solution, continue with IMPLICIT stepping
 * and say so in res.  A NaN or Inf anywhere fails with DFLE_ENUMERIC
 * naming the node, field and time. */
int dfle_solver_run(dfle_model *m, const dfle_run_opts *opts, dfle_run_result *res,
                    dfle_error *err);

/* The scalar root solve the implicit and direct solvers make at every
 * node, for a caller that sweeps a network itself (a landscape), on the
 * path the solvers take (doc/solvers.md: Newton steps with dE/d ln S
 * where a router routed every step and the law give it, values alone
 * otherwise): the slope S of node i with
 *   U_eff = E(S) + c S,   E = dfle_model_node_erosion(m, i, S, flows),
 * c = L/dt and U_eff = U + (z_old - z_receiver_new)/dt for a backward-
 * Euler step, c = 0 and U_eff = U for a steady state.  Started from
 * `guess` when it is > 0; *goes_on (may be NULL) receives whether the
 * flow goes on at the root.  DFLE_EFIT when no slope balances U_eff. */
int dfle_solver_node_slope(dfle_model *m, size_t i, double U_eff, double c, double flows,
                           double guess, double *S, int *goes_on, dfle_error *err);

/* --- The stepping loop ------------------------------------------------
 *
 * Every time-stepping run in dfle goes through this one loop, so that
 * "steady", "max_time", "max_steps" and an interrupt mean the same
 * everywhere: the 1D methods above (explicit, implicit) and a
 * landscape's implicit and explicit steps (landscape.h).  A stepper says
 * how its state is judged and how it moves; the loop owns the time, the
 * step count, the stop checks in one order, and where steps land:
 *
 *   records at t = 0
 *   loop: prepare (bring the state up to date, judge it)
 *         stop if steady, t >= max_time, steps >= max_steps, interrupted
 *         advance by at most the time to the next record or max_time
 *         count the step, take the records it reached, after_step
 *
 * A stepper is a static const ops table and a state pointer (GSL's
 * {type, state}); callbacks return DFLE_OK or a negative status with err
 * set, which ends the loop with that status. */
typedef struct dfle_stepping_tally {
    int reason;          /* enum dfle_stop_reason, once the loop ended   */
    double time;         /* years stepped in this loop                   */
    size_t steps;        /* steps taken in this loop                     */
    double dt_min, dt_max; /* smallest and largest step [yr] (0 if none) */
    size_t n_recorded;   /* record times reached                        */
} dfle_stepping_tally;

typedef struct dfle_stepper_ops {
    int iVersion;        /* 1 */
    const char *name;    /* for messages: "explicit", "landscape", ... */
    /* Before every stop check: bring the state up to date for time t of
     * the loop (forcing, rates) and set *steady = 1 when it meets the
     * stepper's steady-state criterion (the loop then stops with
     * DFLE_STOP_STEADY; leave it 0 for transients). */
    int (*prepare)(void *self, const dfle_stepping_tally *so_far, int *steady, dfle_error *err);
    /* One step of at most dt_limit [yr] (> 0): *dt receives its length,
     * 0 < *dt <= dt_limit. */
    int (*advance)(void *self, double dt_limit, double *dt, dfle_error *err);
    /* Optional: record time k (record_times[k]) was reached at time t. */
    int (*record)(void *self, size_t k, double t, dfle_error *err);
    /* Optional: after every step (the tally already counts it). */
    int (*after_step)(void *self, const dfle_stepping_tally *so_far, double dt, dfle_error *err);
} dfle_stepping_ops;

typedef struct dfle_stepping_limits {
    double max_time;     /* > 0 [yr]                                     */
    size_t max_steps;    /* > 0                                          */
    const volatile sig_atomic_t *interrupt; /* may be NULL               */
    size_t n_record;     /* record times [yr since the loop began],      */
    const double *record_times; /* increasing, within [0, max_time]      */
} dfle_stepping_limits;

/* Run the loop (see above) from a fresh tally.  Reaching max_time,
 * max_steps or the interrupt is not an error: tally->reason says which
 * stop it was. */
int dfle_stepping_loop(const dfle_stepping_ops *ops, void *self,
                       const dfle_stepping_limits *lim, dfle_stepping_tally *tally,
                       dfle_error *err);


#ifdef __cplusplus
}
#endif
#endif
