/*
 * flow.c - allocation of the per-node flow record that routers fill.
 *
 * All nine arrays come from one block so a flow is one allocation and
 * one free, and clearing it is a single memset.  dfle_flow_bind carves
 * the same layout out of a caller's block (a one-node view, a Lua
 * userdata), so there is one place that knows it.
 */
#include "dfle/flow.h"

#include <stdlib.h>
#include <string.h>

void dfle_flow_bind(dfle_flow *flow, double *block, size_t n)
{
    memset(flow, 0, sizeof *flow);
    flow->n = n;
    flow->M = block;
    flow->Q = block + n;
    flow->h = block + 2 * n;
    flow->v = block + 3 * n;
    flow->t_p = block + 4 * n;
    flow->tau = block + 5 * n;
    flow->Theta = block + 6 * n;
    flow->reach = block + 7 * n;
    flow->integral = block + 8 * n;
}

int dfle_flow_init(dfle_flow *flow, size_t n, dfle_error *err)
{
    double *block;

    memset(flow, 0, sizeof *flow);
    if (n == 0)
        return dfle_error_set(err, DFLE_EINVAL, "flow: need at least one node");
    block = calloc(DFLE_FLOW_ARRAYS * n, sizeof *block);
    if (block == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "flow: out of memory for %zu nodes", n);
    dfle_flow_bind(flow, block, n);
    return DFLE_OK;
}

void dfle_flow_release(dfle_flow *flow)
{
    if (flow == NULL)
        return;
    free(flow->M); /* the block starts at M */
    memset(flow, 0, sizeof *flow);
}

void dfle_flow_clear(dfle_flow *flow)
{
    if (flow->M != NULL)
        memset(flow->M, 0, DFLE_FLOW_ARRAYS * flow->n * sizeof *flow->M);
    flow->runout_end = 0;
    flow->time_resolved = 0;
    flow->clean_for = 0;
}
