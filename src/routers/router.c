/*
 * router.c - the generic router handle: an ops table plus its state.
 *
 * Keeping the handle opaque means the model cannot reach into any one
 * router's state; everything goes through dfle_router_ops (router.h).
 */
#include "dfle/router.h"

#include <stdlib.h>

struct dfle_router {
    const dfle_router_ops *ops;
    void *state;
    int routing; /* a route or node_flow call is running (router.h) */
};

int dfle_router_new(const dfle_router_ops *ops, void *state,
                    dfle_router **out, dfle_error *err)
{
    dfle_router *rt;

    *out = NULL;
    if (ops != NULL && (ops->version < 1 || ops->version > DFLE_ROUTER_OPS_VERSION)) {
        if (ops->destroy != NULL) /* later versions only append: it is where we look */
            ops->destroy(state);
        return dfle_error_set(err, DFLE_EINVAL,
                              "router %s: ops version %d, this library knows 1 to %d (set "
                              ".version = DFLE_ROUTER_OPS_VERSION)",
                              ops->name != NULL ? ops->name : "?", ops->version,
                              DFLE_ROUTER_OPS_VERSION);
    }
    if (ops == NULL || ops->route == NULL) {
        if (ops != NULL && ops->destroy != NULL)
            ops->destroy(state);
        return dfle_error_set(err, DFLE_EINVAL, "router: ops table lacks route()");
    }
    rt = malloc(sizeof *rt);
    if (rt == NULL) {
        if (ops->destroy != NULL)
            ops->destroy(state);
        return dfle_error_set(err, DFLE_ENOMEM, "router: out of memory");
    }
    rt->ops = ops;
    rt->state = state;
    rt->routing = 0;
    *out = rt;
    return DFLE_OK;
}

void dfle_router_free(dfle_router *rt)
{
    if (rt == NULL)
        return;
    if (rt->ops->destroy != NULL)
        rt->ops->destroy(rt->state);
    free(rt);
}

/* A routing calls the law's integrand, which may be Lua that runs
 * another model with this router: that nested routing would reallocate
 * and overwrite the state (arrival times, snapshots) the outer one is
 * writing into. */
static int refuse_nested(const dfle_router *rt, dfle_error *err)
{
    return dfle_error_set(err, DFLE_ECALLBACK,
                          "router.%s: used again while it is routing (from inside a function the "
                          "routing calls: the erosion law's integrand, a flow() written in Lua); "
                          "a router routes one flow at a time", rt->ops->name);
}

int dfle_router_route(dfle_router *rt, const dfle_network *net,
                      const double *S, dfle_flow *flow, dfle_error *err)
{
    int st;
    if (rt->routing)
        return refuse_nested(rt, err);
    rt->routing = 1;
    if (flow->clean_by != (const void *)rt->ops)
        flow->clean_for = 0; /* another router wrote it: nothing is known */
    flow->clean_by = rt->ops;
    st = rt->ops->route(rt->state, net, S, flow, err);
    if (st != DFLE_OK)
        flow->clean_for = 0;
    rt->routing = 0;
    return st;
}

int dfle_router_is_routing(const dfle_router *rt) { return rt->routing; }

int dfle_router_needs_reroute(dfle_router *rt, size_t n, const double *S_routed,
                              const double *S, int *reroute, dfle_error *err)
{
    *reroute = 1;
    if (rt->ops->needs_reroute == NULL)
        return DFLE_OK;
    return rt->ops->needs_reroute(rt->state, n, S_routed, S, reroute, err);
}

int dfle_router_node_flow(dfle_router *rt, const dfle_network *net, size_t i,
                          double S, dfle_flow *node, int *goes_on, dfle_error *err)
{
    int st;
    *goes_on = 0;
    if (rt->ops->node_flow == NULL)
        return dfle_error_set(err, DFLE_ESTATE,
                              "router.%s cannot evaluate the flow at one node", rt->ops->name);
    if (rt->routing)
        return refuse_nested(rt, err);
    rt->routing = 1;
    st = rt->ops->node_flow(rt->state, net, i, S, node, goes_on, err);
    rt->routing = 0;
    return st;
}

int dfle_router_node_flow_dlnS(dfle_router *rt, const dfle_network *net, size_t i, double S,
                               double lnS, dfle_flow *node, dfle_flow_dlnS *d, int *goes_on,
                               dfle_error *err)
{
    *goes_on = 0;
    if (rt->ops->node_flow_dlnS == NULL)
        return dfle_error_set(err, DFLE_ESTATE,
                              "router.%s cannot say how the flow at one node answers its slope",
                              rt->ops->name);
    return rt->ops->node_flow_dlnS(rt->state, net, i, S, lnS, node, d, goes_on, err);
}

int dfle_router_has_node_flow_dlnS(const dfle_router *rt)
{
    return rt->ops->node_flow_dlnS != NULL;
}

size_t dfle_router_params(const dfle_router *rt, dfle_param *out, size_t cap)
{
    if (rt->ops->params == NULL)
        return (size_t)-1;
    return rt->ops->params(rt->state, out, cap);
}

int dfle_router_is_local(const dfle_router *rt)
{
    return rt->ops->needs_reroute == NULL;
}

const char *dfle_router_name(const dfle_router *rt) { return rt->ops->name; }
const dfle_router_ops *dfle_router_get_ops(const dfle_router *rt) { return rt->ops; }
void *dfle_router_state(const dfle_router *rt) { return rt->state; }
