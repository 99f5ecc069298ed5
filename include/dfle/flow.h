/*
 * flow.h - bulk properties of one routed debris flow, per channel node.
 *
 * A router fills this record; an erosion law reads it.  It is the only
 * thing the two share, which is what lets any law run with any router.
 * Arrays hold n values (one per node).  reach[i] counts the debris flows
 * that go on at node i (0: none reaches it, or it stops there; every
 * other array is then zero and E_df = 0).  On a 1D channel one flow
 * starts at the head and the reached nodes are [0, runout_end); on a
 * network every source releases one, and they join where they meet.
 *
 * Two kinds of router fill it:
 *  - bulk routers (the empirical one): one representative value per
 *    node, used as in Eq. (6);
 *  - time-resolved routers (the process-based one): peaks over the flow
 *    event, and `integral`, the Eq. (11) sum of g(h, v, lambda) Phi dt
 *    [s times the unit of g] over the flow's own time steps, where g is
 *    the law's integrand (h^beta for the power law).  The model sets
 *    `integrand` before routing.
 */
#ifndef DFLE_FLOW_H
#define DFLE_FLOW_H

#include <stddef.h>
#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_flow {
    size_t n;          /* number of nodes                                 */
    size_t runout_end; /* chain: first node the flow does not reach (n = all);
                        * a network: the number of nodes reached        */
    double *M;         /* volume passing the node [m^3]                   */
    double *Q;         /* peak discharge [m^3/s]                          */
    double *h;         /* representative flow depth [m]                   */
    double *v;         /* representative velocity [m/s]                   */
    double *t_p;       /* passage time [s]                                */
    double *tau;       /* basal shear stress [Pa]                         */
    double *Theta;     /* threshold factor 1 - tau_y/tau [-]              */
    double *reach;     /* debris flows going on at the node [-]           */

    /* Time-resolved routers only (time_resolved = 1). */
    int time_resolved;
    double *integral;  /* Eq. (11): sum over flow steps of g Phi dt        */
    /* The law's integrand g (law.h): 0 with *g set, or a negative
     * dfle_status with err set (the routing then fails with it). */
    int (*integrand)(void *law_state, double h, double v, double lambda, double *g,
                     dfle_error *err);
    void *integrand_state; /* first argument of integrand               */

    /* Kept by routers (router.h), 0 everywhere else: the network version
     * for which every node no flow can reach (none of its upstream nodes
     * a source) is known to hold zeros, so a router may skip those nodes;
     * clean_by is the ops table of the router that last routed this
     * flow (dfle_router_route clears clean_for when another one does). */
    unsigned long long clean_for;
    const void *clean_by;
} dfle_flow;

/* How the bulk flow at one node answers that node's own slope S: the
 * derivatives with respect to ln S, of ln X for the fields that are
 * positive where a flow is (M, Q, h, v, t_p, tau) and of Theta itself
 * (which reaches 0 where the flow stops, so has no logarithm there).  A
 * field that does not move with S has 0 (M, Q and t_p depend on the
 * drainage area alone in the empirical router).  Filled by a router's
 * node_flow_dlnS op (router.h), read by a law's rate_dlnS op (law.h):
 * with both, the node solvers take Newton steps in ln S. */
typedef struct dfle_flow_dlnS {
    double M, Q, h, v, t_p, tau; /* d ln X / d ln S [-] */
    double Theta;                /* d Theta / d ln S [-] */
} dfle_flow_dlnS;

/* Doubles a flow's arrays take per node (M, Q, h, v, t_p, tau, Theta,
 * reach, integral): the size of the block dfle_flow_bind carves. */
#define DFLE_FLOW_ARRAYS 9

/* Allocate zeroed arrays for n nodes (integral included); runout_end
 * starts at 0, time_resolved at 0, integrand NULL. */
int dfle_flow_init(dfle_flow *flow, size_t n, dfle_error *err);

/* Point the arrays of `flow` into `block` (DFLE_FLOW_ARRAYS * n
 * doubles, owned by the caller: a stack buffer, a Lua userdata) for n
 * nodes; everything else is zeroed.  dfle_flow_release must not be
 * called on such a flow. */
void dfle_flow_bind(dfle_flow *flow, double *block, size_t n);

/* Release the arrays (flow may be zeroed or NULL); idempotent. */
void dfle_flow_release(dfle_flow *flow);

/* Zero every array and set runout_end = 0 (and clean_for). */
void dfle_flow_clear(dfle_flow *flow);

#ifdef __cplusplus
}
#endif
#endif
