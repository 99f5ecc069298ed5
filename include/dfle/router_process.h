/*
 * router_process.h - the process-based debris-flow router (Sect. 2.2,
 * Appendix E): a debris flow released from a static pile of volume M0
 * on n_ghost ghost cells above the channel head (same slope and width
 * as the head) and routed down the current profile with the two-phase
 * solver of flow1d.h until it has left the domain or come to rest.
 *
 * Along the way it records, per channel node: peak depth, peak speed,
 * peak discharge, arrival and passage time, the volume that passed, and
 * the Eq. (11) sum of g(h, v, lambda) Phi dt with the erosion law's
 * integrand g (h^beta for the power law) and Phi = 1 where |v| h >
 * q_erode.  E_df = k_df S^alpha * sum is then evaluated every landscape
 * step from the cached sum; the flow is re-routed only when some node's
 * slope has changed by reroute_dS or more since the last routing.
 *
 * A routing ends (the criterion, explicitly):
 *   left  - the volume in the domain, ghost cells included, is at most
 *           volume_tol * volume released;
 *   rest  - every cell has |v| h <= q_rest [m^2/s] after the flow has
 *           once been faster than that, or every cell is still (q = 0,
 *           a pile friction holds);
 *   time  - t_max seconds have passed (reported; not an error).
 * A routing that needs more than max_steps flow steps (a tiny cfl, a
 * flow too fast for its cells) fails with DFLE_ENUMERIC and says so. 
 */
#ifndef DFLE_ROUTER_PROCESS_H
#define DFLE_ROUTER_PROCESS_H

#include "dfle/flow1d.h"
#include "dfle/router.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_process_opts {
    dfle_flow1d_params flow; /* Eqs. (7)-(10); Table G2/G4, Fig. 6 defaults */
    double M0;          /* released volume [m^3]                    (200)   */
    int n_ghost;        /* ghost cells above the head               (20)    */
    double reroute_dS;  /* re-route when any |S - S_last| >= this   (0.05)  */
    double q_erode;     /* Phi = 1 where |v| h > q_erode [m^2/s]    (0.01)  */
    double q_rest;      /* at rest: every |v| h <= q_rest [m^2/s]   (1e-3)  */
    double volume_tol;  /* left: volume in domain <= tol * released (1e-4)  */
    double t_max;       /* longest routing [s]                      (3600)  */
    double max_steps;   /* most flow time steps in one routing, a bound
                         * on work whatever cfl and the flow do: past it
                         * the routing fails saying so        (1e6)     */
    /* Appendix D: scale the erosion sum (so k_df) by
     * 1000 (1e-6 A)^gamma / M0, a debris-flow frequency growing with A. */
    int frequency_scaling; /* 0 or 1                                (0)     */
    double gamma;          /* exponent of the scaling [-]           (0)     */
    /* On a network: a width on a head's path that moved by less than
     * this fraction since its last routing keeps that routing (a
     * hillslope cell that changes receiver moves its area between
     * channels at every step, and with it the widths below). */
    double reroute_dw;     /* relative, > 0                         (0.05)  */
} dfle_process_opts;

/* Fig. 6 defaults: M0 = 200, eta = 60, mu_2 = 0.62, D = 5e-6, mu_s =
 * 0.384, I0 = 0.279, lambda0 = 0.9, v_f = 0.5, D_eff = 0.09, rho = 1800,
 * rho_s = 2600. */
void dfle_process_opts_default(dfle_process_opts *o);

int dfle_router_new_process(const dfle_process_opts *opts, dfle_router **out,
                            dfle_error *err);

/* The parameters of a process-based router, or NULL for another kind. */
const dfle_process_opts *dfle_router_process_opts(const dfle_router *rt);

enum dfle_process_end {
    DFLE_PROCESS_LEFT = 0, /* the flow left through the outlet */
    DFLE_PROCESS_REST = 1, /* the flow came to rest            */
    DFLE_PROCESS_TIME = 2  /* t_max was reached                */
};
const char *dfle_process_end_name(int end); /* "left", "rest", "time" */

/* What the last routing did.  Arrays have n (channel nodes) values and
 * stay valid until the next routing or the router's destruction. */
typedef struct dfle_process_report {
    int routed;          /* 0 before the first routing            */
    int end;             /* enum dfle_process_end                 */
    double volume_in;    /* released [m^3]                        */
    double volume_out;   /* through the outlet [m^3]              */
    double volume_left;  /* still in the domain [m^3]             */
    double duration;     /* flow time [s]                         */
    size_t steps;        /* flow time steps                       */
    size_t cell_steps;   /* cells the steps worked on, summed: the
                          * wet window's mean length times steps  */
    size_t n;            /* channel nodes                         */
    const double *arrival; /* first time with Phi = 1 [s]; NaN if never */
    size_t n_snapshots;  /* snapshots requested                   */
    const double *snapshot_t; /* time each was taken [s]; NaN if the flow ended first */
    const double *snapshot_h; /* n_snapshots x n depths [m], row-major */
    /* One flow per channel head.  On a single channel 1 head; on a
     * network (heads_network = 1) every source's, the volumes, steps and
     * durations above summed (duration: the longest) over the heads
     * routed by the last routing, arrival the first of any flow. */
    int heads_network;   /* 1: the last routing was on a network      */
    size_t heads;        /* heads (flows) of the last routing         */
    size_t heads_routed; /* of them routed again by it (the others kept
                          * their last routing: the re-routing rule)  */
    size_t head_routings; /* heads routed since the router was made   */
    size_t route_calls;  /* routings asked for since it was made (a
                          * call may route no head: the rule kept all) */
    double volume_error; /* max over the flows routed of
                          * |in - out - left| / in [-]: round-off     */
} dfle_process_report;

const dfle_process_report *dfle_router_process_report(const dfle_router *rt);


/* Ask the next routings to record the depth along the channel at these
 * flow times [s] (ascending; k <= 1000).  k = 0 clears the request. */
int dfle_router_process_set_snapshots(dfle_router *rt, size_t k, const double *times,
                                      dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
