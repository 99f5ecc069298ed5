/*
 * model.h - the channel-profile model, Eq. (3):  dz/dt = U - E_f - E_df.
 *
 * The model owns the elevations z [m] and the diagnostic fields that go
 * with them; it borrows the channel, fluvial law, router and erosion law,
 * which must outlive it.  Time is in years, rates in m/yr.
 *
 * Stepping is explicit forward Euler, as in the paper.  The step is set
 * by a CFL condition on the upwind slope: erosion that depends on the
 * downstream slope moves a slope perturbation upstream at the speed
 * c_i = |dE_i/dS_i| [m/yr], so dt = cfl * dx / max_i c_i, capped at
 * dt_max and at the time left in the run.
 *
 * Steady state (explicit and configurable): the run stops when
 *   max over nodes 0..n-2 of |dz/dt| <= tol * U.
 */
#ifndef DFLE_MODEL_H
#define DFLE_MODEL_H

#include <stddef.h>
#include "dfle/channel.h"
#include "dfle/error.h"
#include "dfle/fluvial.h"
#include "dfle/law.h"
#include "dfle/router.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_model dfle_model;

typedef struct dfle_model_opts {
    const dfle_channel *channel; /* required                               */
    const dfle_fluvial *fluvial; /* NULL: no fluvial erosion               */
    dfle_router *router;         /* NULL: no debris flows                  */
    dfle_law *law;               /* required when router is set            */
    double U;                    /* rock uplift rate [m/yr], > 0  (5e-4)   */
    double cfl;                  /* Courant number in (0, 1]      (0.5)    */
    double dt_max;               /* largest time step [yr], > 0   (1000)   */
} dfle_model_opts;

void dfle_model_opts_default(dfle_model_opts *o);

int dfle_model_new(const dfle_model_opts *opts, dfle_model **out,
                   dfle_error *err);
void dfle_model_free(dfle_model *m);

/* Fields of the current state, one value per node. */
enum dfle_field {
    DFLE_FIELD_X,     /* distance from the head [m]             */
    DFLE_FIELD_A,     /* drainage area [m^2]                    */
    DFLE_FIELD_W,     /* channel width [m]                      */
    DFLE_FIELD_Z,     /* elevation above the outlet [m]         */
    DFLE_FIELD_S,     /* slope (z_i - z_i+1)/dx [-]             */
    DFLE_FIELD_E_F,   /* fluvial erosion [m/yr]                 */
    DFLE_FIELD_E_DF,  /* debris-flow erosion [m/yr]             */
    DFLE_FIELD_DZDT,  /* dz/dt [m/yr]                           */
    DFLE_FIELD_M,     /* debris-flow volume [m^3]               */
    DFLE_FIELD_Q,     /* peak discharge [m^3/s]                 */
    DFLE_FIELD_H,     /* flow depth [m]                         */
    DFLE_FIELD_V,     /* flow velocity [m/s]                    */
    DFLE_FIELD_T_P,   /* passage time [s]                       */
    DFLE_FIELD_TAU,   /* basal shear stress [Pa]                */
    DFLE_FIELD_THETA, /* threshold factor [-]                   */
    DFLE_FIELD_COUNT
};

/* Field by name ("x", "A", "S", "E_df", "tau", ...), or -1. */
int dfle_field_lookup(const char *name);
const char *dfle_field_name(int field);
const char *dfle_field_unit(int field);

/* The field's n values for the current z (re-evaluated if z changed). */
const double *dfle_model_field(dfle_model *m, int field, dfle_error *err);
size_t dfle_model_size(const dfle_model *m);

/* Eq. (26): integrate the fluvial steady-state slope up from the outlet
 * (z = 0).  Uses `fl`, else the model's fluvial law, else the Table G1
 * stochastic-threshold law. */
int dfle_model_init_fluvial_steady(dfle_model *m, const dfle_fluvial *fl,
                                   dfle_error *err);
/* Forget the routed flow: the next evaluation routes again.  Needed when
 * the model's router was used directly (its memory of the last routing
 * no longer matches the model's cached flow). */
void dfle_model_invalidate_flow(dfle_model *m);

/* Set elevations [m] (n values; the outlet value is the base level). */
int dfle_model_set_z(dfle_model *m, const double *z, size_t n,
                     dfle_error *err);

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
} dfle_run_opts;

/* tol = 1e-3, max_time = 2e7 yr, max_steps = 1e7 (about ten minutes on
 * the default 403-node grid: long enough for any sane run, short enough
 * that a run with a vanishing time step ends with reason "steps"). */
void dfle_run_opts_default(dfle_run_opts *o);

enum dfle_stop_reason {
    DFLE_STOP_STEADY = 0, /* the steady-state criterion was met     */
    DFLE_STOP_TIME = 1,   /* max_time was reached                   */
    DFLE_STOP_STEPS = 2   /* max_steps was reached                  */
};
const char *dfle_stop_reason_name(int reason); /* "steady", "time", "steps" */

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

/* Step Eq. (3) until steady state, max_time or max_steps.  A NaN or Inf
 * anywhere fails with DFLE_ENUMERIC naming the node, field and time. */
int dfle_model_run(dfle_model *m, const dfle_run_opts *opts,
                   dfle_run_result *res, dfle_error *err);

double dfle_model_time(const dfle_model *m); /* total simulated years */
double dfle_model_U(const dfle_model *m);
int dfle_model_set_U(dfle_model *m, double U, dfle_error *err);
const dfle_channel *dfle_model_channel(const dfle_model *m);
const dfle_fluvial *dfle_model_fluvial(const dfle_model *m);
dfle_router *dfle_model_router(const dfle_model *m);
dfle_law *dfle_model_law(const dfle_model *m);

/* CSV of every field, header row with units. */
int dfle_model_write_csv(dfle_model *m, const char *path, dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
