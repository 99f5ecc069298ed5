/*
 * router_process_internal.h - what the process-based router's files
 * share: one flow routed down one path of cells (router_process_path.c),
 * used for the single channel (router_process.c) and for every channel
 * head of a network (router_process_network.c).  Not installed.
 */
#ifndef DFLE_ROUTER_PROCESS_INTERNAL_H
#define DFLE_ROUTER_PROCESS_INTERNAL_H

#include "dfle/router_process.h"

/* A path of n nodes, from a channel head down its receivers: per node
 * the length of its cell [m] (dx, or dx0 for every cell when dx is
 * NULL), width w [m], slope S [-] and drainage area A [m^2]. */
typedef struct process_path {
    size_t n;
    const double *dx;
    double dx0;
    const double *w, *S, *A;
} process_path;

/* Depth snapshots to take on the way (n_snap = 0: none). */
typedef struct process_snaps {
    size_t n_snap;
    const double *times; /* requested [s]          */
    double *t, *h;       /* taken, n_snap and n_snap x n */
} process_snaps;

/* How one routing went (router_process.h's report, for one flow). */
typedef struct process_path_result {
    int end;
    double volume_in, volume_out, volume_left, duration;
    size_t steps, cell_steps;
} process_path_result;

/* Route one flow down path p into flow (n nodes: every array, reach and
 * runout_end; flow->integrand set by the caller), with arrival times
 * into arrival[n] and cos_theta[n] as scratch.  Ghost cells extend the
 * head (its width, slope and cell length). */
int dfle_process_route_path(const dfle_process_opts *o, const process_path *p, dfle_flow *flow,
                            double *arrival, double *cos_theta, const process_snaps *snaps,
                            process_path_result *res, dfle_error *err);

/* The flows of every head of a network (router_process_network.c): a
 * cache of each head's last routing, kept by the router. */
typedef struct process_network process_network;

/* Route the flows of net's sources over slopes S into flow (combined:
 * router_process.h), re-routing a head only where its path changed or a
 * slope on it moved by reroute_dS since that head's last routing; the
 * report's network fields and totals into rep.  *cache is made on first
 * use and renewed for another network. */
int dfle_process_route_network(process_network **cache, const dfle_process_opts *o,
                               const dfle_network *net, const double *S, dfle_flow *flow,
                               dfle_process_report *rep, dfle_error *err);
void dfle_process_network_free(process_network *cache);

#endif
