/*
 * lua_router_define.c - dfle.router.define{...}: a bulk debris-flow router
 * whose flow relations are written in Lua (a user variant of the empirical
 * router), run by the model through dfle_router_ops like any other.
 *
 *   local rt = dfle.router.define{
 *     name = "mine", params = { ... },
 *     flow = function(c, p)        -- c.S, c.A, c.w, c.x in; set c.h, c.v, c.t_p, ...
 *       ...
 *       return c.Theta > 0         -- does the flow go on past this node?
 *     end,
 *   }
 *
 * Like the empirical router it is local (routed at every landscape step)
 * and gives node_flow, so the implicit and direct solvers work with it.
 * A shell like dfle.law.define (lua_shell.h): a Lua thread of its own,
 * anchored to the router object, holds the function, the params and a
 * reused record; the state is a userdata on that thread, so the
 * collector owns everything; every op is one protected call, whose
 * error (with the user's file:line) the op returns.
 */
#include "lua/core/lua_shell.h"

#include <math.h>

/* Slots on the router thread's stack (lua_shell.h: the shell's own
 * come first). */
enum {
    SLOT_PARAMS = DFLE_SHELL_PARAMS, /* the router's copy of params */
    SLOT_FLOW = DFLE_SHELL_SLOTS + 1, /* flow(c, p)                 */
    SLOT_REC,      /* the node record c            */
    SLOT_SWEEP,    /* sweep closure over the slots */
    SLOT_COUNT = SLOT_SWEEP
};
#define UP(slot) lua_upvalueindex(slot)

/* Outputs read back from c after each call, and whether required. */
static const struct { const char *name; int required; } outputs[] = {
    {"h", 1}, {"v", 1}, {"t_p", 1}, {"M", 0}, {"Q", 0}, {"tau", 0}, {"Theta", 0},
};
enum { O_H, O_V, O_T_P, O_M, O_Q, O_TAU, O_THETA, N_OUT };

typedef struct lua_router {
    dfle_lua_shell sh;   /* the thread (user value 1 of the router), name, who */
    dfle_router_ops ops; /* named after the user's router */
    /* The call in progress (set only once dfle_lua_shell_enter let it
     * start: a nested route would otherwise point these at another
     * model's network and flow under the running sweep). */
    const dfle_network *net;
    const double *S;   /* route: n slopes, by node; node_flow: &s */
    size_t node;       /* node_flow: the node; route: ALL_NODES */
    dfle_flow *flow;
    int node_goes_on;  /* out (node_flow) */
} lua_router;

#define ALL_NODES ((size_t)-1)

/* The slope the call in progress gives node i. */
static double slope_at(const lua_router *r, size_t i)
{
    return r->node == ALL_NODES ? r->S[i] : r->S[0];
}

static int bad_output(lua_State *T, const lua_router *r, size_t i, const char *field,
                      const char *why)
{
    lua_Debug ar;
    const char *what = lua_type(T, -1) == LUA_TNUMBER ? dfle_lua_number_text(T, lua_tonumber(T, -1))
                                                      : dfle_lua_typename(T, -1);
    lua_pushvalue(T, UP(SLOT_FLOW));
    lua_getinfo(T, ">S", &ar);
    return luaL_error(T, "router '%s': flow (defined at %s:%d) set %s to %s, %s, at node %d "
                         "(S = %f, A = %f m^2)", r->sh.name, ar.short_src, ar.linedefined, field,
                      what, why, (int)i + 1, slope_at(r, i), dfle_network_A(r->net)[i]);
}

static void set_num(lua_State *T, const char *k, double v)
{
    lua_pushnumber(T, v);
    lua_setfield(T, UP(SLOT_REC), k);
}

/* Call flow() for node i; write its outputs to flow index j.  Returns
 * whether the flow goes on. */
static int call_node(lua_State *T, lua_router *r, size_t i, size_t j)
{
    const double s = slope_at(r, i);
    dfle_flow *fl = r->flow;
    double out[N_OUT];
    int goes_on;

    set_num(T, "S", s);
    set_num(T, "A", dfle_network_A(r->net)[i]);
    set_num(T, "w", dfle_network_w(r->net)[i]);
    set_num(T, "x", dfle_network_x(r->net)[i]);
    for (int k = 0; k < N_OUT; k++) { /* no stale values from the last node */
        lua_pushnil(T);
        lua_setfield(T, UP(SLOT_REC), outputs[k].name);
    }
    lua_pushvalue(T, UP(SLOT_FLOW));
    lua_pushvalue(T, UP(SLOT_REC));
    lua_pushvalue(T, UP(SLOT_PARAMS));
    lua_call(T, 2, 1);
    goes_on = lua_toboolean(T, -1);
    lua_pop(T, 1);
    for (int k = 0; k < N_OUT; k++) {
        int t = lua_getfield(T, UP(SLOT_REC), outputs[k].name);
        if (t == LUA_TNIL && !outputs[k].required) {
            out[k] = k == O_THETA ? (goes_on ? 1.0 : 0.0) : 0.0;
        } else {
            if (t != LUA_TNUMBER)
                bad_output(T, r, i, outputs[k].name, "expected a number");
            out[k] = lua_tonumber(T, -1);
            if (!isfinite(out[k]))
                bad_output(T, r, i, outputs[k].name, "expected a finite number");
            if (k != O_THETA && out[k] < 0)
                bad_output(T, r, i, outputs[k].name, "expected a number >= 0");
        }
        lua_pop(T, 1);
    }
    fl->h[j] = out[O_H];
    fl->v[j] = out[O_V];
    fl->t_p[j] = out[O_T_P];
    fl->M[j] = out[O_M];
    fl->Q[j] = out[O_Q];
    fl->tau[j] = out[O_TAU];
    fl->Theta[j] = out[O_THETA];
    return goes_on;
}

static void zero_node(dfle_flow *fl, size_t j)
{
    fl->M[j] = fl->Q[j] = fl->h[j] = fl->v[j] = fl->t_p[j] = fl->tau[j] = fl->Theta[j] =
        fl->reach[j] = 0.0;
}

/* The protected sweep.  node_flow: the one node.  route: a flow from
 * every source down the receivers (reverse stack order: every node after
 * its donors, whose arriving flows it counts), stopping at a reverse
 * slope or where flow() says the flow stops - the empirical router's
 * rule, so on a channel it is the runout from the head down. */
static int sweep(lua_State *T)
{
    lua_router *r = lua_touserdata(T, 1);
    r->node_goes_on = 0;
    if (r->node != ALL_NODES) {
        if (!(r->S[0] > 0))
            return 0;
        if (call_node(T, r, r->node, 0))
            r->node_goes_on = 1;
        else
            r->flow->Theta[0] = 0.0; /* arriving, it stops here: no erosion */
        r->flow->reach[0] = r->node_goes_on;
        return 0;
    }
    {
        const size_t n = dfle_network_size(r->net);
        const size_t *stack = dfle_network_stack(r->net), *recv = dfle_network_receivers(r->net);
        const unsigned char *source = dfle_network_sources(r->net);
        dfle_flow *fl = r->flow;
        for (size_t i = 0; i < n; i++)
            fl->reach[i] = source[i];
        for (size_t k = n; k-- > 0;) {
            const size_t i = stack[k];
            const double arriving = fl->reach[i];
            if (!(arriving > 0) || !(r->S[i] > 0) || !call_node(T, r, i, i)) {
                zero_node(fl, i);
                continue;
            }
            fl->reach[i] = arriving;
            if (recv[i] != i)
                fl->reach[recv[i]] += arriving;
        }
    }
    return 0;
}

/* The sweep, for an op that dfle_lua_shell_enter let start. */
static int run_sweep(lua_router *r, dfle_error *err)
{
    int st = dfle_lua_shell_sweep(&r->sh, SLOT_COUNT, SLOT_SWEEP, "error in flow()", err);
    dfle_lua_shell_leave(&r->sh);
    return st;
}

static int lr_route(void *state, const dfle_network *net, const double *S, dfle_flow *flow,
                    dfle_error *err)
{
    lua_router *r = state;
    const size_t n = dfle_network_size(net);
    size_t reached = 0, first_gap = n;
    int st;

    if (flow->n != n)
        return dfle_error_set(err, DFLE_EINVAL, "router.%s: flow has %zu nodes, network %zu",
                              r->sh.name, flow->n, n);
    if ((st = dfle_lua_shell_enter(&r->sh, "flow()", err)) != DFLE_OK)
        return st;
    flow->time_resolved = 0;
    r->net = net, r->S = S, r->node = ALL_NODES, r->flow = flow;
    if ((st = run_sweep(r, err)) != DFLE_OK)
        return st;
    for (size_t i = 0; i < n; i++) {
        reached += flow->reach[i] > 0;
        if (first_gap == n && !(flow->reach[i] > 0))
            first_gap = i;
    }
    flow->runout_end = dfle_network_is_chain(net) ? first_gap : reached;
    return DFLE_OK;
}

static int lr_node_flow(void *state, const dfle_network *net, size_t i, double S,
                        dfle_flow *node, int *goes_on, dfle_error *err)
{
    lua_router *r = state;
    int st;

    *goes_on = 0;
    node->time_resolved = 0;
    zero_node(node, 0);
    if (!(S > 0))
        return DFLE_OK;
    if ((st = dfle_lua_shell_enter(&r->sh, "flow()", err)) != DFLE_OK)
        return st;
    r->net = net, r->S = &S, r->node = i, r->flow = node;
    if ((st = run_sweep(r, err)) != DFLE_OK)
        return st;
    *goes_on = r->node_goes_on;
    return DFLE_OK;
}

static const dfle_router_ops lua_router_ops = {
    .version = DFLE_ROUTER_OPS_VERSION,
    .name = "lua",
    .route = lr_route,
    .needs_reroute = NULL, /* local: routed at every landscape step */
    .node_flow = lr_node_flow,
    .destroy = NULL,       /* the state is a userdata on the router's thread */
};

/* dfle.router.define{ name =, params =, flow = } -> dfle.router */
static int l_router_define(lua_State *L)
{
    static const char *const keys[] = {"name", "params", "flow", NULL};
    static const dfle_lua_shell_def def = {
        .kind = "router", .tname = DFLE_LUA_ROUTER, .object_size = sizeof(dfle_lua_router),
        .state_size = sizeof(lua_router), .keys = keys, .stack = SLOT_COUNT,
    };
    lua_router *r;
    dfle_error err;

    r = dfle_lua_shell_new(L, &def);
    if (lua_getfield(L, 1, "flow") != LUA_TFUNCTION)
        luaL_error(L, "dfle.router.define: 'flow' (a function of c, p) is required, got %s",
                   dfle_lua_typename(L, -1));
    lua_xmove(L, r->sh.T, 1);               /* SLOT_FLOW */
    lua_createtable(r->sh.T, 0, 12);        /* SLOT_REC */
    dfle_lua_shell_close(r->sh.T, sweep);   /* SLOT_SWEEP */
    r->ops = lua_router_ops;
    r->ops.name = r->sh.name;
    if (dfle_router_new(&r->ops, r, &((dfle_lua_router *)lua_touserdata(L, 2))->rt, &err) !=
        DFLE_OK)
        return dfle_lua_raise(L, &err);
    lua_settop(L, 2);
    return 1;
}

void dfle_lua_open_router_define(lua_State *L)
{
    lua_pushcfunction(L, l_router_define);
    lua_setfield(L, -2, "define");
}
