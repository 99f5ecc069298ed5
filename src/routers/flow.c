/*
 * flow.c - allocation of the per-node flow record that routers fill.
 *
 * All seven arrays come from one block so a flow is one allocation and
 * one free, and clearing it is a single memset.
 */
#include "dfle/flow.h"

#include <stdlib.h>
#include <string.h>

enum { FLOW_ARRAYS = 8 };

int dfle_flow_init(dfle_flow *flow, size_t n, dfle_error *err)
{
    double *block;

    memset(flow, 0, sizeof *flow);
    if (n == 0)
        return dfle_error_set(err, DFLE_EINVAL, "flow: need at least one node");
    block = calloc(FLOW_ARRAYS * n, sizeof *block);
    if (block == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "flow: out of memory for %zu nodes", n);
    flow->n = n;
    flow->M = block;
    flow->Q = block + n;
    flow->h = block + 2 * n;
    flow->v = block + 3 * n;
    flow->t_p = block + 4 * n;
    flow->tau = block + 5 * n;
    flow->Theta = block + 6 * n;
    flow->integral = block + 7 * n;
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
        memset(flow->M, 0, FLOW_ARRAYS * flow->n * sizeof *flow->M);
    flow->runout_end = 0;
    flow->time_resolved = 0;
}
