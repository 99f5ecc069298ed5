/*
 * law.h - the debris-flow erosion-law interface.
 *
 * A law turns a routed flow (flow.h) and the channel slope into an
 * erosion rate E_df [m/yr] per node.  It is split in two so that the
 * expensive, flow-dependent part is evaluated only when the flow is
 * routed and the cheap slope-dependent part at every landscape step
 * (the caching of the paper's Eq. 11):
 *
 *   F_i    = flow_factor(flow, node i)       after each routing
 *   E_df,i = rate(S_i, F_i, node i)          every landscape step
 *
 * For the power family of Eq. (6), F = t_p h^beta Theta and
 * E_df = k_df S^alpha F.  With a time-resolved router (Eq. 11) the
 * router sums the law's integrand over the flow (flow.h) and
 * F = sum h^beta Phi dt.  Laws are `static const dfle_law_ops` tables
 * with a private state, exactly like routers; a law written in Lua is
 * one more table.  Every op that can fail returns 0 or a negative
 * dfle_status with `err` set.
 */
#ifndef DFLE_LAW_H
#define DFLE_LAW_H

#include <stddef.h>
#include "dfle/error.h"
#include "dfle/flow.h"
#include "dfle/param.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What a law sees.  Arrays have at least n values. */
typedef struct dfle_law_ctx {
    size_t n;              /* active nodes: those the flow reaches [0, n) */
    const double *S;       /* channel slope [-], > 0 where active          */
    const double *A;       /* drainage area [m^2]                          */
    const double *w;       /* channel width [m]                            */
    const dfle_flow *flow; /* the routed flow                              */
} dfle_law_ctx;

/* The version of dfle_law_ops this header describes: set .version to
 * it.  Later versions only append members; the library reads those a
 * table's version says it has (SQLite's iVersion). */
#define DFLE_LAW_OPS_VERSION 1

typedef struct dfle_law_ops {
    int version;      /* DFLE_LAW_OPS_VERSION */
    const char *name;
    /* Required.  Fill F[0..n) with the flow-dependent factor. */
    int (*flow_factor)(void *state, const dfle_law_ctx *ctx, double *F,
                       dfle_error *err);
    /* Required.  Fill E[0..n) [m/yr] from ctx->S and the cached F. */
    int (*rate)(void *state, const dfle_law_ctx *ctx, const double *F,
                double *E, dfle_error *err);
    /* Optional; needed only with time-resolved routers (the process-based
     * one).  The integrand g of Eq. (11) at one node and flow step: the
     * router sums g Phi dt into flow->integral, which flow_factor then
     * reads.  For the power law g = h^beta.  h [m], v [m/s], lambda [-].
     * Sets *g and returns 0, or fails like the other ops. */
    int (*integrand)(void *state, double h, double v, double lambda, double *g,
                     dfle_error *err);
    /* Optional.  The parameters (param.h): write up to cap of them to
     * out and return how many there are. */
    size_t (*params)(const void *state, dfle_param *out, size_t cap);
    /* Optional.  Release the state. */
    void (*destroy)(void *state);
    /* Optional.  dE[0..n) = d E_df / d ln S [m/yr]: the derivative of
     * E[0..n), what rate just gave for ctx->S and F, where the flow's
     * fields move with ln S as d[j] says for node j (flow.h), or stay as
     * they are when d is NULL (a flow routed rarely: its cached factor
     * stands and only the slope moves).  0 wherever E is 0 by the rate's
     * own rules (S <= 0, F = 0).  With it (and, for a router routed
     * every step, the router's node_flow_dlnS) the node solvers take
     * Newton steps in ln S; without it they difference E.  An ops table
     * may gain and lose this op as its state changes (a law written in
     * Lua has it while its compiled programs can be differentiated):
     * callers ask dfle_law_has_rate_dlnS each time, never once for all. */
    int (*rate_dlnS)(void *state, const dfle_law_ctx *ctx, const double *F, const double *E,
                     const dfle_flow_dlnS *d, double *dE, dfle_error *err);
} dfle_law_ops;

typedef struct dfle_law dfle_law;

/* Wrap `state` (owned from here on, destroyed even if this fails). */
int dfle_law_new(const dfle_law_ops *ops, void *state, dfle_law **out,
                 dfle_error *err);
void dfle_law_free(dfle_law *law);

int dfle_law_flow_factor(dfle_law *law, const dfle_law_ctx *ctx, double *F,
                         dfle_error *err);
int dfle_law_rate(dfle_law *law, const dfle_law_ctx *ctx, const double *F,
                  double *E, dfle_error *err);

/* The rate_dlnS op, or DFLE_ESTATE (with a message) if the law has none
 * (dfle_law_has_rate_dlnS says which). */
int dfle_law_rate_dlnS(dfle_law *law, const dfle_law_ctx *ctx, const double *F,
                       const double *E, const dfle_flow_dlnS *d, double *dE, dfle_error *err);
int dfle_law_has_rate_dlnS(const dfle_law *law);

/* The parameters (param.h), up to cap of them; returns how many there
 * are, or (size_t)-1 when the law has no params op (a law written in Lua
 * keeps its own). */
size_t dfle_law_params(const dfle_law *law, dfle_param *out, size_t cap);

const char *dfle_law_name(const dfle_law *law);
const dfle_law_ops *dfle_law_get_ops(const dfle_law *law);
void *dfle_law_state(const dfle_law *law);

#ifdef __cplusplus
}
#endif
#endif
