/*
 * model_internal.h - the model object, shared by model.c (the object,
 * its topology and fields) and model_rates.c (evaluating the rates).
 * Not installed, and not for solvers: they sit above the model and use
 * model.h only.
 */
#ifndef DFLE_MODEL_INTERNAL_H
#define DFLE_MODEL_INTERNAL_H

#include "dfle/flow.h"
#include "dfle/model.h"

/* Receiver-tree topology (model.h).  For a base-level node recv[i] = i
 * and base_donor[i] is the donor whose slope it repeats (NO_NODE: none). */
#define NO_NODE ((size_t)-1)

struct dfle_model {
    const dfle_channel *ch;
    const dfle_fluvial *fl; /* NULL: no fluvial erosion  */
    dfle_router *rt;        /* NULL: no debris flows     */
    dfle_law *law;
    double U, cfl, dt_max;
    size_t n;
    double time; /* total simulated years */

    /* Topology: one block, see topology_alloc(). */
    size_t *recv, *stack, *base_donor;
    double *len, *inv_len; /* L_i [m] and 1 / L_i (slopes multiply by it) */
    unsigned char *is_base;
    size_t *base;          /* the n_base base-level nodes                 */
    size_t n_base;
    int uniform_len;       /* every L_i is the same (a 1D channel)        */

    /* State and fields: one block of n-arrays, see model_alloc(). */
    double *z, *S, *E_f, *E_df, *dzdt, *F, *KAm;
    double *S_routed; /* slopes of this model's last routing [-]      */
    double *S_pert, *E_pert, *F_pert, *celerity;
    dfle_flow flow, flow_pert;
    /* A one-node flow for per-node evaluations (node_flow op). */
    double node_block[DFLE_FLOW_ARRAYS];
    dfle_flow node;

    int evaluated;       /* fields match z                        */
    int flow_valid;      /* flow/F match the last routing         */
    size_t routings;     /* routings since creation               */
    size_t nonpositive;  /* non-base nodes with S <= 0 at the last evaluation */
};

#endif
