/*
 * solver_internal.h - what the solver files share (not installed).
 *
 * The layer reads: solver.c picks a method and falls back; the time-
 * stepping methods (explicit, implicit) share one stepping loop
 * (solver_stepping.c) and differ in how they advance one step; implicit
 * and direct share the scalar root solve of one node (solver_node.c).
 * Everything here calls the model (model.h) and nothing above it.
 */
#ifndef DFLE_SOLVER_INTERNAL_H
#define DFLE_SOLVER_INTERNAL_H

#include "dfle/model.h"
#include "dfle/solver.h"

/* Advance the model's z by one step of at most dt_limit years from its
 * evaluated state; say how long it was. */
typedef int (*dfle_advance_fn)(dfle_model *m, double dt_limit, double *dt_taken, void *state,
                               dfle_error *err);

/* The stepping loop of the time-stepping methods: uplift U(t), evaluate,
 * test for steady state, time and step limits, advance, record, report.
 * Adds to res (so a fallback run continues the tally). */
int dfle_stepping_run(dfle_model *m, const dfle_run_opts *o, dfle_advance_fn advance,
                      void *state, dfle_run_result *res, dfle_error *err);

/* Set the model's U from the run's U(t) callback, if any (checked > 0). */
int dfle_stepping_uplift(dfle_model *m, const dfle_run_opts *o, dfle_error *err);

/* One forward-Euler step with the CFL time step (state unused); the
 * implicit method finishes with these when large steps stall. */
int dfle_explicit_advance(dfle_model *m, double dt_limit, double *dt_taken, void *state,
                          dfle_error *err);
/* The CFL time step of the evaluated state [yr], capped at dt_max. */
int dfle_explicit_step(dfle_model *m, double *dt, dfle_error *err);

/* Solve U_eff = E(S) + c S for the slope S of node i, where E is
 * dfle_model_node_erosion: safeguarded Newton with bisection, started
 * from `guess` when it is > 0 (a neighbour's or the previous slope).
 * *goes_on (may be NULL) receives the flow's verdict at the root.
 * Used with c = L/dt, U_eff = U + (z_old - z_receiver)/dt for a
 * backward-Euler step, and with c = 0, U_eff = U for a steady state. */
int dfle_solve_node(dfle_model *m, size_t i, double U_eff, double c, double flows, double guess,
                    double *S, int *goes_on, dfle_error *err);

#endif
