/*
 * model.h - the channel-profile model, Eq. (3):  dz/dt = U - E_f - E_df.
 *
 * The model holds the state (elevations z [m], model time [yr], the
 * routed debris flow) and evaluates the rates; it does not step.  Time
 * stepping and steady-state solving are the solvers' (solver.h), which
 * sit above the model and use only what this header declares, so a new
 * solver needs nothing private.  It borrows the channel, fluvial law,
 * router and erosion law, which must outlive it.  Rates are in m/yr.
 *
 * The model is solved on a drainage network (network.h): each node
 * drains to one receiver over a flow length L [m], base-level nodes (the
 * outlet) are their own receivers and are held fixed, and the stack lists
 * every node after its receiver (Braun and Willett 2013).  The slope of
 * node i is
 *   S_i = (z_i - z_receiver(i)) / L_i
 * (the paper's downstream difference; a base-level node repeats the slope
 * of its largest donor).  A 1D channel is the network in which node i
 * drains to i + 1 over dx; nothing in the model or the solvers assumes
 * i + 1.  A landscape changes the network's shape as its surface evolves;
 * the model follows at its next evaluation.
 *
 * Debris flows start at every source of the network and join where they
 * meet.  How the flows of several sources combine at a node is a choice
 * (dfle_df_combine): the 1D rule (a node any flow reaches erodes at the
 * frequency a single flow stands for, with properties from its own A and
 * S), frequency growing with the number of flows, or a function of it.
 */
#ifndef DFLE_MODEL_H
#define DFLE_MODEL_H

#include <stddef.h>
#include "dfle/channel.h"
#include "dfle/error.h"
#include "dfle/fluvial.h"
#include "dfle/law.h"
#include "dfle/network.h"
#include "dfle/param.h"
#include "dfle/record.h"
#include "dfle/router.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_model dfle_model;

/* How the debris flows from several sources combine at a node where
 * they meet: E_df is multiplied by a factor of the number c of flows that
 * go on there (1 on a channel, whatever the rule). */
enum dfle_df_combine {
    DFLE_DF_ANY = 0,   /* factor 1: reached is reached (the 1D rule)    */
    DFLE_DF_COUNT = 1, /* factor c: each flow erodes, frequencies add   */
    DFLE_DF_CUSTOM = 2 /* factor frequency(ud, c, A)                    */
};

typedef struct dfle_model_opts {
    const dfle_channel *channel; /* the domain: a channel, or ...          */
    const dfle_network *network; /* ... a network (exactly one of the two) */
    const dfle_fluvial *fluvial; /* NULL: no fluvial erosion               */
    dfle_router *router;         /* NULL: no debris flows                  */
    dfle_law *law;               /* required when router is set            */
    double U;                    /* rock uplift rate [m/yr], > 0  (5e-4)   */
    double cfl;                  /* Courant number in (0, 1]      (0.5)    */
    double dt_max;               /* largest time step [yr], > 0   (1000)   */
    int df_combine;              /* enum dfle_df_combine           (ANY)   */
    /* DFLE_DF_CUSTOM: the factor for c flows at a node of area A [m^2];
     * must be finite and >= 0. */
    double (*df_frequency)(void *ud, double count, double A);
    void *df_frequency_ud;
} dfle_model_opts;

void dfle_model_opts_default(dfle_model_opts *o);

int dfle_model_new(const dfle_model_opts *opts, dfle_model **out,
                   dfle_error *err);
void dfle_model_free(dfle_model *m);

/* Fields of the current state, one value per node. */
enum dfle_field {
    DFLE_FIELD_X,     /* distance from the head [m] (a network: its x, or NaN) */
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
/* The slopes [-] of the current z into S (n values), exactly as an
 * evaluation computes them (a base level repeats its largest donor's),
 * without routing or evaluating anything else: for a caller that routes
 * a router itself over the profile. */
void dfle_model_slopes(dfle_model *m, double *S);
/* Forget the routed flow: the next evaluation routes again.  Needed when
 * the model's router was used directly (its memory of the last routing
 * no longer matches the model's cached flow). */
void dfle_model_invalidate_flow(dfle_model *m);

/* Erodibility in space: per-node multipliers of the fluvial K (K_scale)
 * and of the debris-flow erosion E_df (df_scale), n values each, finite
 * and >= 0, or NULL for 1 everywhere.  The model reads the arrays where
 * they are (no copy): they must stay valid until the model is freed or
 * this is called again, which it must be after their values change.
 * On a network with a channel mask (network.h) hillslope nodes have no
 * fluvial or debris-flow erosion whatever the scales say. */
int dfle_model_set_erodibility(dfle_model *m, const double *K_scale, const double *df_scale,
                               dfle_error *err);

/* Set elevations [m] (n values; the outlet value is the base level). */
int dfle_model_set_z(dfle_model *m, const double *z, size_t n,
                     dfle_error *err);

double dfle_model_time(const dfle_model *m); /* total simulated years */
double dfle_model_U(const dfle_model *m);
int dfle_model_set_U(dfle_model *m, double U, dfle_error *err);
const dfle_channel *dfle_model_channel(const dfle_model *m); /* NULL on a network */
const dfle_network *dfle_model_network(const dfle_model *m);
const dfle_fluvial *dfle_model_fluvial(const dfle_model *m);
dfle_router *dfle_model_router(const dfle_model *m);
dfle_law *dfle_model_law(const dfle_model *m);

double dfle_model_cfl(const dfle_model *m);    /* explicit Courant number  */
double dfle_model_dt_max(const dfle_model *m); /* largest time step [yr]   */

/* The model's own parameters (param.h): U (the current uplift rate,
 * m/yr), cfl and dt_max [yr], up to cap of them; returns how many there
 * are.  Its components list theirs (dfle_channel_params,
 * dfle_fluvial_params, dfle_router_params, dfle_law_params). */
size_t dfle_model_params(const dfle_model *m, dfle_param *out, size_t cap);

/* --- For solvers (solver.h): topology, state, rates. ---------------- */

/* Receiver of every node (a base-level node is its own), flow length to
 * it [m], and the stack: all n nodes, each after its receiver. */
const size_t *dfle_model_receivers(const dfle_model *m);
const double *dfle_model_flow_length(const dfle_model *m);
const size_t *dfle_model_stack(const dfle_model *m);
/* 1 if node i is held at base level. */
int dfle_model_is_base(const dfle_model *m, size_t i);
/* 1 if every flow length is the same (a 1D channel). */
int dfle_model_uniform_flow_length(const dfle_model *m);

/* The elevations [m] for a solver to change in place; call
 * dfle_model_touch afterwards (the fields are then stale). */
double *dfle_model_z(dfle_model *m);
void dfle_model_touch(dfle_model *m);
/* Add dt [yr] to the model time. */
void dfle_model_advance_time(dfle_model *m, double dt);

/* Bring S, E_f, E_df and dz/dt up to date with z: route the debris flow
 * if it is stale (a local router every time, another when it asks, from
 * the slopes of this model's last routing), then check every value a
 * step produces; a NaN or Inf fails with DFLE_ENUMERIC naming the node,
 * field and time.  dfle_model_is_evaluated says whether that is needed. */
int dfle_model_evaluate(dfle_model *m, dfle_error *err);
/* The slopes and the debris flow alone, for a caller that solves each
 * node itself (a landscape's implicit step reads S and the flows' reach,
 * then asks dfle_solver_node_slope per node).  With a local router,
 * without a population, that is one routing: E_f, the law's E_df and
 * dz/dt are not computed and the model is left unevaluated, so a field
 * asked for later is evaluated in full.  Otherwise this is
 * dfle_model_evaluate.  *S and *reach (n each) stay valid until z or the
 * network changes. */
int dfle_model_route(dfle_model *m, const double **S, const double **reach, dfle_error *err);
/* Bytes the model holds now: its fields and flows, the arrays made on
 * first use (the celerity's perturbed copies, the gathered views of a
 * law on scattered nodes) and a population's (not the network's). */
size_t dfle_model_memory(const dfle_model *m);
int dfle_model_is_evaluated(const dfle_model *m);
/* From the last evaluation: max over non-base nodes of |dz/dt| / U
 * (DBL_MAX when that overflows, for a U near the smallest double), the
 * number of those with S <= 0, and routings since creation. */
double dfle_model_rate_ratio(const dfle_model *m);
size_t dfle_model_nonpositive_slopes(const dfle_model *m);
size_t dfle_model_routings(const dfle_model *m);
/* The number of debris flows of the last routing that go on at node i
 * (0: none; E_df is nonzero only where this is). */
double dfle_model_flow_reaches(const dfle_model *m, size_t i);

/* Kinematic-wave speed |dE/dS| [m/yr per unit slope] of every node for
 * the evaluated state (0 on base nodes): exact for the fluvial power
 * law, a one-sided difference for the debris-flow part (which works for
 * any router and law without asking them for derivatives).  *c points
 * at n values owned by the model. */
int dfle_model_celerity(dfle_model *m, const double **c, dfle_error *err);

/* Erosion E_f + E_df [m/yr] at node i for slope S, the rest of the
 * profile as it is, with `flows` debris flows arriving (0 leaves them
 * out; the combine rule weighs them).  For a router routed every step
 * the flow at the node is re-evaluated for S (its node_flow op), and
 * *goes_on says whether the flow, arriving, would go on; for other
 * routers the cached Eq. (11) factor is used. */
int dfle_model_node_erosion(dfle_model *m, size_t i, double S, double flows, double *E,
                            int *goes_on, dfle_error *err);
/* The same E, and *dE = dE/d ln S [m/yr] (S dE/dS), when every part can
 * give it: the fluvial law always, the erosion law through its rate_dlnS
 * op and, for a router routed every step, the router through its
 * node_flow_dlnS op (routed rarely, the flow is held: only S moves).
 * dfle_model_node_dlnS says whether they can now (a law written in Lua
 * can only while its compiled programs can be differentiated: law.h);
 * when they cannot, *dE is NaN and E is what dfle_model_node_erosion
 * gives.  lnS is ln S, kept by the caller (Newton steps move it): the
 * powers of S then cost an exp each instead of a pow or a cbrt, the
 * bulk of a node solve.  Results agree with dfle_model_node_erosion's
 * to rounding. */
int dfle_model_node_erosion_dlnS(dfle_model *m, size_t i, double S, double lnS, double flows,
                                 double *E, double *dE, int *goes_on, dfle_error *err);
int dfle_model_node_dlnS(const dfle_model *m);
/* One-node erosions evaluated (either function above) since creation:
 * what a node solve costs, counted by the model (laws must not count). */
size_t dfle_model_node_evaluations(const dfle_model *m);

/* What the model is, into a record (record.h): a section per component
 * ("channel" with its kind, params and n, x_outlet [m], A_head and
 * A_outlet [m^2]; or "network" with n), "fluvial", "router" and "law"
 * (kind "off" for a process that is off; a component without a params
 * op, one written in Lua, gets its kind only), and "model" (U, cfl,
 * dt_max, and time [yr] so far). */
void dfle_model_describe(const dfle_model *m, dfle_record *rec);

/* CSV of every field (dfle_table_write): `rec` as comment lines (may be
 * NULL), the units line, the field names, one row per node with 10
 * significant digits. */
int dfle_model_write_csv(dfle_model *m, const char *path, const dfle_record *rec,
                         dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
