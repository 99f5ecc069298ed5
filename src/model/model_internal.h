/*
 * model_internal.h - what the model's solver files share (not installed).
 *
 * model.c holds the model object, its fields and the explicit stepper;
 * model_implicit.c the backward-Euler stepper; model_direct.c the direct
 * steady-state solver.  They all read and write the same state, so the
 * struct lives here rather than behind accessors.
 */
#ifndef DFLE_MODEL_INTERNAL_H
#define DFLE_MODEL_INTERNAL_H

#include "dfle/flow.h"
#include "dfle/model.h"

struct dfle_model {
    const dfle_channel *ch;
    const dfle_fluvial *fl; /* NULL: no fluvial erosion  */
    dfle_router *rt;        /* NULL: no debris flows     */
    dfle_law *law;
    double U, cfl, dt_max;
    size_t n;
    double dx;
    double time; /* total simulated years */

    /* One block of n-arrays, see model_alloc(). */
    double *z, *S, *E_f, *E_df, *dzdt, *F, *KAm;
    double *S_pert, *E_pert, *F_pert, *celerity, *z_save, *z_work;
    dfle_flow flow, flow_pert;
    /* A one-node flow for per-node evaluations (node_flow op). */
    double node_block[8];
    dfle_flow node;

    int evaluated;       /* fields match z                        */
    int flow_valid;      /* flow/F match the last routing         */
    size_t routings;     /* routings since creation               */
    size_t nonpositive;  /* nodes with S <= 0 at the last evaluation */
};

/* Bring S, E_f, E_df, dz/dt (and the flow) up to date with z. */
int dfle_mi_evaluate(dfle_model *m, dfle_error *err);
/* max over nodes 0..n-2 of |dz/dt| / U, from the last evaluation. */
double dfle_mi_rate_ratio(const dfle_model *m);
/* Rough completion estimate for progress reports. */
double dfle_mi_progress_fraction(double t, double max_time, double r0, double r, double tol);
/* Forget that fields match z (after z changed). */
void dfle_mi_touch(dfle_model *m);

/* Erosion E_f + E_df [m/yr] at node i for slope S, the rest of the
 * profile as it is.  with_df = 0 leaves out debris flows.  For a router
 * routed every step the flow at the node is re-evaluated for S (node_flow
 * op), and *goes_on says whether the flow, arriving, would go on; for
 * other routers the cached Eq. (11) factor is used. */
int dfle_mi_node_erosion(dfle_model *m, size_t i, double S, int with_df, double *E,
                         int *goes_on, dfle_error *err);

/* Solve U_eff = E(S) + c S for S on node i, where
 * E is dfle_mi_node_erosion: safeguarded Newton with bisection, started
 * from `guess` when it is > 0 (a neighbour's or the previous slope).
 * *goes_on (may be NULL) receives the flow's verdict at the root, as
 * dfle_mi_node_erosion gives it.
 * Used with c = dx/dt, U_eff = U + (z_old - z_below)/dt for a
 * backward-Euler step, and with c = 0, U_eff = U for a steady state. */
int dfle_mi_solve_node(dfle_model *m, size_t i, double U_eff, double c, int with_df,
                       double guess, double *S, int *goes_on, dfle_error *err);

/* Advance z by one step of at most dt_limit years; say how long. */
typedef int (*dfle_mi_advance_fn)(dfle_model *m, double dt_limit, double *dt_taken,
                                  void *state, dfle_error *err);
/* One forward-Euler step with the CFL time step (state unused). */
int dfle_mi_explicit_advance(dfle_model *m, double dt_limit, double *dt_taken, void *state,
                             dfle_error *err);

/* The stepping loop shared by the time-stepping methods: evaluate, test
 * for steady state, time and step limits, advance, record, report.
 * Adds to res (so a fallback run continues the tally). */
int dfle_mi_drive(dfle_model *m, const dfle_run_opts *o, dfle_mi_advance_fn advance,
                  void *state, dfle_run_result *res, dfle_error *err);

int dfle_mi_run_implicit(dfle_model *m, const dfle_run_opts *o, dfle_run_result *res,
                         dfle_error *err);
int dfle_mi_run_direct(dfle_model *m, const dfle_run_opts *o, dfle_run_result *res,
                       dfle_error *err);

#endif
