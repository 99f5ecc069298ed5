/*
 * router.h - the debris-flow router interface.
 *
 * A router turns the current profile of a drainage network (network.h:
 * a 1D channel is one) into the bulk properties of the debris flows at
 * every node (flow.h): one flow released at each source, travelling down
 * the receivers.  Each kind of router is a
 * `static const dfle_router_ops` table plus a private state; the model
 * only ever calls through the table, so the empirical router, the
 * process-based router and routers written in Lua are interchangeable.
 *
 * Every op that can fail returns 0 on success and a negative dfle_status
 * on failure, with a message in `err`.  A router keeps no state that
 * depends on which model calls it (the model keeps the slopes of its
 * last routing), so one router object may serve several models.
 */
#ifndef DFLE_ROUTER_H
#define DFLE_ROUTER_H

#include <stddef.h>
#include "dfle/error.h"
#include "dfle/flow.h"
#include "dfle/network.h"
#include "dfle/param.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The version of dfle_router_ops this header describes: set .version
 * to it.  Later versions only append members; the library reads those a
 * table's version says it has (SQLite's iVersion). */
#define DFLE_ROUTER_OPS_VERSION 2

struct dfle_population; /* router_population.h */

typedef struct dfle_router_ops {
    int version;      /* DFLE_ROUTER_OPS_VERSION */
    const char *name;
    /* Route the flows over the profile.  S holds n slopes [-] (a base
     * level repeats the slope of its largest donor).  Fill every array
     * of `flow`, reach included, and its runout_end.  A router that only
     * works on a single channel checks dfle_network_is_chain.  Required. */
    int (*route)(void *state, const dfle_network *net, const double *S,
                 dfle_flow *flow, dfle_error *err);
    /* Optional.  Set *reroute nonzero when the slopes S have moved far
     * enough from S_routed, the slopes the caller last routed over, that
     * the flow must be routed again.  The caller (the model) keeps
     * S_routed, so one router may serve several models.  NULL means the
     * router is cheap and local and is routed at every landscape step. */
    int (*needs_reroute)(void *state, size_t n, const double *S_routed, const double *S,
                         int *reroute, dfle_error *err);
    /* Optional; only for routers routed every step.  The flow at node i
     * alone for slope S, as if it had arrived there: fill the one-node
     * view `node` (its arrays point at one value each) and set *goes_on
     * to 1 if it goes on (e.g. tau >= tau_y), 0 if it stops here (then
     * Theta = 0).  The implicit and direct solvers need it to treat E_df
     * at a node as a function of that node's slope. */
    int (*node_flow)(void *state, const dfle_network *net, size_t i, double S,
                     dfle_flow *node, int *goes_on, dfle_error *err);
    /* Optional.  The parameters (param.h): write up to cap of them to
     * out and return how many there are. */
    size_t (*params)(const void *state, dfle_param *out, size_t cap);
    /* Optional.  Release the state. */
    void (*destroy)(void *state);
    /* Optional, with node_flow: what node_flow does, and in *d how that
     * flow answers S (flow.h: d ln h / d ln S and so on; all 0 where
     * S <= 0).  Where the flow stops (*goes_on = 0, Theta = 0) d->Theta
     * is 0, like Theta.  With it (and the law's rate_dlnS) the node
     * solvers take Newton steps in ln S; without it they difference E.
     * lnS is ln S, which the solvers keep: a power of S then costs an
     * exp, not a pow or a cbrt (half the cost of a steady state). */
    int (*node_flow_dlnS)(void *state, const dfle_network *net, size_t i, double S, double lnS,
                          dfle_flow *node, dfle_flow_dlnS *d, int *goes_on, dfle_error *err);
    /* Version 2.  Optional.  The population of flows the router stands
     * for (router_population.h): the model then evaluates the erosion
     * law for every member flow and weighs them by their rates. */
    const struct dfle_population *(*population)(const void *state);
} dfle_router_ops;

typedef struct dfle_router dfle_router;

/* Wrap `state` (owned from here on, destroyed even if this fails). */
int dfle_router_new(const dfle_router_ops *ops, void *state,
                    dfle_router **out, dfle_error *err);
void dfle_router_free(dfle_router *rt);

/* Route one flow.  A router routes one flow at a time: called again
 * while it routes (a law's integrand, run in the middle of a routing,
 * that runs a model or a routing with the same router) it returns
 * DFLE_ECALLBACK at once, before anything of its state is touched; so
 * does dfle_router_node_flow. */
int dfle_router_route(dfle_router *rt, const dfle_network *net,
                      const double *S, dfle_flow *flow, dfle_error *err);
/* 1 while a route or node_flow call of the router is running. */
int dfle_router_is_routing(const dfle_router *rt);
/* *reroute = 1 if the router must be routed again for slopes S, having
 * last been routed over S_routed (always 1 without the op). */
int dfle_router_needs_reroute(dfle_router *rt, size_t n, const double *S_routed,
                              const double *S, int *reroute, dfle_error *err);
/* The node_flow op, or DFLE_ESTATE (with a message) if the router has
 * none.  *goes_on receives its verdict. */
int dfle_router_node_flow(dfle_router *rt, const dfle_network *net, size_t i,
                          double S, dfle_flow *node, int *goes_on, dfle_error *err);

/* The node_flow_dlnS op, or DFLE_ESTATE (with a message) if the router
 * has none (dfle_router_has_node_flow_dlnS says which). */
int dfle_router_node_flow_dlnS(dfle_router *rt, const dfle_network *net, size_t i, double S,
                               double lnS, dfle_flow *node, dfle_flow_dlnS *d, int *goes_on,
                               dfle_error *err);
int dfle_router_has_node_flow_dlnS(const dfle_router *rt);

/* The parameters (param.h), up to cap of them; returns how many there
 * are, or (size_t)-1 when the router has no params op (a router written
 * in Lua keeps its own). */
size_t dfle_router_params(const dfle_router *rt, dfle_param *out, size_t cap);

/* 1 if the router is routed at every step (no needs_reroute op). */
int dfle_router_is_local(const dfle_router *rt);

const char *dfle_router_name(const dfle_router *rt);
const dfle_router_ops *dfle_router_get_ops(const dfle_router *rt);
void *dfle_router_state(const dfle_router *rt);

#ifdef __cplusplus
}
#endif
#endif
