/*
 * model_internal.h - the model object, shared by model.c (the object,
 * its domain and fields) and model_rates.c (evaluating the rates).
 * Not installed, and not for solvers: they sit above the model and use
 * model.h only.
 */
#ifndef DFLE_MODEL_INTERNAL_H
#define DFLE_MODEL_INTERNAL_H

#include "dfle/flow.h"
#include "dfle/model.h"
#include "dfle/network.h"

#define NO_NODE ((size_t)-1)

/* The nodes a routed flow reaches, and the law's view of them.  On a
 * channel they are a prefix [0, n) of the nodes and the law reads the
 * model's arrays in place; on a network they are gathered into `g_*`
 * (contiguous, as every law expects) and the results scattered back. */
typedef struct reached_set {
    size_t *node; /* n_active node indices, increasing */
    size_t n;
    int prefix;   /* node[k] == k for all k */
} reached_set;

typedef struct model_population model_population; /* model_population.c */

struct dfle_model {
    const dfle_channel *ch;   /* NULL when the model was given a network */
    const dfle_network *net;  /* the domain                               */
    dfle_network *own_net;    /* the chain made from ch, else NULL        */
    const dfle_fluvial *fl;   /* NULL: no fluvial erosion  */
    dfle_router *rt;          /* NULL: no debris flows     */
    model_population *pop;    /* rt's population of flows, or NULL */
    dfle_law *law;
    double U, cfl, dt_max;
    size_t n;
    double time; /* total simulated years */
    int combine;                                   /* enum dfle_df_combine */
    double (*frequency)(void *ud, double count, double A);
    void *frequency_ud;

    /* Terms derived from the network's shape, renewed when its version
     * changes (a landscape re-routes): see sync_domain(). */
    unsigned long long net_version;
    double *inv_len; /* 1 / L_i: slopes multiply by it, as they always have */
    double *KAm;     /* K A^m per node (times K_scale; 0 off the channels)  */
    const double *K_scale, *df_scale; /* erodibility in space, or NULL   */
    const unsigned char *channel;     /* the network's channel mask, or NULL */

    /* State and fields: one block of n-arrays, see model_alloc(). */
    double *z, *S, *E_f, *E_df, *dzdt, *F;
    double *S_routed; /* slopes of this model's last routing [-]      */
    double *S_pert, *E_pert, *F_pert, *celerity;
    dfle_flow flow, flow_pert;
    reached_set reached, reached_pert;
    /* Gathered views for a law on a network (see reached_set). */
    double *g_block;  /* S, A, w, F, E: 5 n, then a flow of n */
    dfle_flow g_flow;
    /* A one-node flow for per-node evaluations (node_flow op). */
    double node_block[DFLE_FLOW_ARRAYS];
    dfle_flow node;

    int evaluated;       /* fields match z                        */
    int flow_valid;      /* flow/F match the last routing         */
    size_t routings;     /* routings since creation               */
    size_t node_evaluations; /* one-node erosions since creation  */
    size_t nonpositive;  /* non-base nodes with S <= 0 at the last evaluation */
};

/* The steps of a debris-flow erosion (model_rates.c), for one member
 * flow of a population. */
void dfle_model_find_reached(const dfle_model *m, const dfle_flow *flow, reached_set *r);
int dfle_model_law_on_reached(dfle_model *m, const double *S, const dfle_flow *flow,
                              const reached_set *r, double *F, double *E, int route,
                              dfle_error *err);
double dfle_model_combine_factor(const dfle_model *m, double count, double A);
double dfle_model_df_scale(const dfle_model *m, size_t i);

/* A population of flows (model_population.c).  pop_new sets m->pop when
 * the router has a population; pop_erosion is debris_flow_erosion for
 * it (commit: remember which members go on where, for the node
 * solvers); pop_node_erosion the E_df part of a one-node erosion. */
int dfle_model_pop_new(dfle_model *m, dfle_error *err);
void dfle_model_pop_free(dfle_model *m);
/* Bytes the population's arrays hold (0 without one). */
size_t dfle_model_pop_memory(const dfle_model *m);
/* The celerity's perturbed copies of the fields, made on first use. */
int dfle_model_pert_alloc(dfle_model *m, dfle_error *err);
int dfle_model_pop_erosion(dfle_model *m, const double *S, dfle_flow *sum, reached_set *r,
                           double *F, double *E, int commit, dfle_error *err);
int dfle_model_pop_node_erosion(dfle_model *m, size_t i, double S, double lnS, double *E,
                                double *dE, int *goes_on, dfle_error *err);

/* Renew what derives from the network's shape if it changed (model.c). */
void dfle_model_sync_domain(dfle_model *m);

#endif
