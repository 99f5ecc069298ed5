/*
 * lua_router.c - dfle.router.empirical{...}, dfle.router.process{...} and
 * dfle.router.define{...} (lua_router_define.c): debris-flow routers.
 *
 * A router object from Lua is just the C router handle; the model takes
 * it through the ops table, whatever its kind.  rt:params(), rt.<param>
 * and tostring(rt) come from its params op (lua_params.c), so scripts
 * can record what they ran.
 */
#include "lua/core/dfle_lua.h"

#include <string.h>

#include "dfle/router_empirical.h"
#include "dfle/router_process.h"

static int l_router_empirical(lua_State *L)
{
    dfle_empirical_opts o;
    dfle_lua_router *u;
    dfle_error err;
    const dfle_lua_param params[] = {
        {"M0", &o.M0}, {"gamma", &o.gamma}, {"mu", &o.mu},       {"tau_y", &o.tau_y},
        {"c1", &o.c1}, {"c2", &o.c2},       {"rho_b", &o.rho_b}, {"g", &o.g},
    };

    dfle_empirical_opts_default(&o);
    dfle_lua_read_params(L, 1, "router.empirical", params, sizeof params / sizeof params[0],
                         NULL);
    u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_ROUTER, 0);
    if (dfle_router_new_empirical(&o, &u->rt, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

static int l_router_process(lua_State *L)
{
    dfle_process_opts o;
    dfle_lua_router *u;
    dfle_error err;
    double n_ghost, frequency_scaling = 0;
    static const char *const other[] = {"frequency_scaling", NULL};
    const dfle_lua_param params[] = {
        {"M0", &o.M0},           {"eta", &o.flow.eta},         {"mu2", &o.flow.mu_2},
        {"mu_s", &o.flow.mu_s},  {"I0", &o.flow.I0},           {"D", &o.flow.D},
        {"D_eff", &o.flow.D_eff}, {"lambda0", &o.flow.lambda0}, {"v_f", &o.flow.v_f},
        {"rho_b", &o.flow.rho},  {"rho_s", &o.flow.rho_s},     {"g", &o.flow.g},
        {"cfl", &o.flow.cfl},    {"h_dry", &o.flow.h_dry},     {"n_ghost", &n_ghost},
        {"reroute_dS", &o.reroute_dS}, {"q_erode", &o.q_erode}, {"q_rest", &o.q_rest},
        {"volume_tol", &o.volume_tol}, {"t_max", &o.t_max},    {"gamma", &o.gamma},
        {"max_steps", &o.max_steps}, {"reroute_dw", &o.reroute_dw},
    };

    dfle_process_opts_default(&o);
    n_ghost = o.n_ghost;
    dfle_lua_read_params(L, 1, "router.process", params, sizeof params / sizeof params[0], other);
    o.n_ghost = (int)dfle_lua_check_whole(L, n_ghost, "router.process", "n_ghost", 1, 10000);
    if (lua_istable(L, 1) && lua_getfield(L, 1, "frequency_scaling") != LUA_TNIL) {
        if (!lua_isboolean(L, -1))
            luaL_error(L, "dfle.router.process: parameter 'frequency_scaling' must be a boolean, "
                          "got %s", dfle_lua_typename(L, -1));
        frequency_scaling = lua_toboolean(L, -1);
    }
    o.frequency_scaling = frequency_scaling != 0;
    u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_ROUTER, 0);
    if (dfle_router_new_process(&o, &u->rt, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

/* The router's params op, as the binding's parameter helpers take it. */
static size_t router_params(const void *rt, dfle_param *out, size_t cap)
{
    return dfle_router_params(rt, out, cap);
}

static void set_array(lua_State *L, const char *key, const double *v, size_t n)
{
    dfle_lua_push_array(L, v, n);
    lua_setfield(L, -2, key);
}

/* rt:route(m [, {snapshots = {t1, t2, ...}}]): route one flow over model
 * m's current profile with m's erosion law, and return what it did. */
static int l_router_route(lua_State *L)
{
    dfle_router *rt = dfle_lua_check_router(L, 1);
    dfle_model *m = dfle_lua_check_model(L, 2);
    static const char *const keys[] = {"snapshots", NULL};
    const dfle_network *net = dfle_model_network(m);
    const size_t n = dfle_model_size(m);
    const dfle_process_report *rep;
    double *S, *block, *times = NULL;
    size_t ntimes = 0;
    dfle_flow flow;
    dfle_error err;
    int st;

    lua_settop(L, 3);
    dfle_lua_read_params(L, 3, "router:route", NULL, 0, keys);
    if (lua_istable(L, 3) && lua_getfield(L, 3, "snapshots") != LUA_TNIL) {
        times = dfle_lua_check_array(L, -1, "router:route: snapshots", &ntimes);
        if (dfle_router_process_opts(rt) == NULL)
            luaL_error(L, "dfle.router:route: snapshots need a process-based router");
    }
    if (dfle_model_law(m) == NULL)
        luaL_error(L, "dfle.router:route: the model has no erosion law (router = false)");
    /* The flow's arrays and the slopes live in a userdata: nothing to
     * free if we raise.  The slopes alone, not an evaluation of the
     * model: that would route the model's router (this one, often) over
     * the same profile first. */
    block = lua_newuserdatauv(L, (DFLE_FLOW_ARRAYS + 1) * n * sizeof *block, 0);
    memset(block, 0, DFLE_FLOW_ARRAYS * n * sizeof *block);
    dfle_flow_bind(&flow, block, n);
    S = block + DFLE_FLOW_ARRAYS * n;
    dfle_model_slopes(m, S);
    flow.integrand = dfle_law_get_ops(dfle_model_law(m))->integrand;
    flow.integrand_state = dfle_law_state(dfle_model_law(m));
    if (times != NULL && dfle_router_process_set_snapshots(rt, ntimes, times, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    /* The law's integrand may be Lua: neither object may go meanwhile. */
    dfle_lua_begin_use(L, 2, "dfle.router:route"); /* raises if busy: pins nothing */
    dfle_lua_end_use(L, 2);
    dfle_lua_begin_use(L, 1, "dfle.router:route");
    dfle_lua_begin_use(L, 2, "dfle.router:route"); /* idle, just checked: cannot raise */
    st = dfle_router_route(rt, net, S, &flow, &err);
    dfle_lua_end_use(L, 2);
    dfle_lua_end_use(L, 1);
    rep = dfle_router_process_report(rt);
    lua_createtable(L, 0, 24);
    set_array(L, "h", flow.h, n);
    set_array(L, "v", flow.v, n);
    set_array(L, "Q", flow.Q, n);
    set_array(L, "M", flow.M, n);
    set_array(L, "t_p", flow.t_p, n);
    set_array(L, "tau", flow.tau, n);
    set_array(L, "Theta", flow.Theta, n);
    set_array(L, "reach", flow.reach, n);
    lua_pushinteger(L, (lua_Integer)flow.runout_end), lua_setfield(L, -2, "runout_end");
    if (st == DFLE_OK && rep != NULL) {
        lua_getfield(L, -1, "h"), lua_setfield(L, -2, "h_peak");
        lua_getfield(L, -1, "v"), lua_setfield(L, -2, "v_peak");
        lua_getfield(L, -1, "t_p"), lua_setfield(L, -2, "passage");
        set_array(L, "sum", flow.integral, n);
        set_array(L, "arrival", rep->arrival, n);
        lua_pushnumber(L, rep->volume_in), lua_setfield(L, -2, "volume_in");
        lua_pushnumber(L, rep->volume_out), lua_setfield(L, -2, "volume_out");
        lua_pushnumber(L, rep->volume_left), lua_setfield(L, -2, "volume_left");
        lua_pushnumber(L, rep->duration), lua_setfield(L, -2, "duration");
        lua_pushinteger(L, (lua_Integer)rep->steps), lua_setfield(L, -2, "steps");
        lua_pushinteger(L, (lua_Integer)rep->cell_steps), lua_setfield(L, -2, "cell_steps");
        lua_pushinteger(L, (lua_Integer)rep->heads), lua_setfield(L, -2, "heads");
        lua_pushinteger(L, (lua_Integer)rep->heads_routed), lua_setfield(L, -2, "heads_routed");
        lua_pushnumber(L, rep->volume_error), lua_setfield(L, -2, "volume_error");
        lua_pushstring(L, dfle_process_end_name(rep->end)), lua_setfield(L, -2, "ended");
        lua_createtable(L, (int)rep->n_snapshots, 0);
        for (size_t j = 0; j < rep->n_snapshots; j++) {
            lua_createtable(L, 0, 2);
            lua_pushnumber(L, rep->snapshot_t[j]), lua_setfield(L, -2, "t");
            set_array(L, "h", rep->snapshot_h + j * n, n);
            lua_rawseti(L, -2, (lua_Integer)j + 1);
        }
        lua_setfield(L, -2, "snapshots");
    }
    if (times != NULL) /* the request was for this routing only */
        dfle_router_process_set_snapshots(rt, 0, NULL, NULL);
    /* The router now remembers this routing, not the model's last one. */
    if (rt == dfle_model_router(m))
        dfle_model_invalidate_flow(m);
    if (st != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

/* r:routings() -> { total = flows routed since the router was made,
 * heads = flows of the last routing, routed = of them routed again by
 * it, calls = routings asked for }, for a process-based router (nil for
 * another kind). */
static int l_router_routings(lua_State *L)
{
    const dfle_process_report *rep = dfle_router_process_report(dfle_lua_check_router(L, 1));
    if (rep == NULL) {
        lua_pushnil(L);
        return 1;
    }
    lua_createtable(L, 0, 3);
    lua_pushinteger(L, (lua_Integer)rep->head_routings), lua_setfield(L, -2, "total");
    lua_pushinteger(L, (lua_Integer)rep->heads), lua_setfield(L, -2, "heads");
    lua_pushinteger(L, (lua_Integer)rep->heads_routed), lua_setfield(L, -2, "routed");
    lua_pushinteger(L, (lua_Integer)rep->route_calls), lua_setfield(L, -2, "calls");
    return 1;
}

static int l_router_params(lua_State *L)
{
    dfle_lua_push_params(L, 1, router_params, dfle_lua_check_router(L, 1));
    return 1;
}

static int l_router_property(lua_State *L)
{
    dfle_router *rt = dfle_lua_check_router(L, 1);
    return dfle_lua_push_param_field(L, dfle_router_name(rt), router_params, rt);
}

static void router_describe(lua_State *L, void *obj)
{
    dfle_lua_push_described(L, 1, "dfle.router", dfle_router_name(obj), router_params, obj);
}

static void router_free(void *obj) { dfle_router_free(obj); }

void dfle_lua_open_router(lua_State *L)
{
    static const luaL_Reg methods[] = {
        {"params", l_router_params}, {"route", l_router_route},
        {"routings", l_router_routings}, {NULL, NULL}};
    static const dfle_lua_type type = {
        .name = DFLE_LUA_ROUTER, .free = router_free, .describe = router_describe,
        .methods = methods, .property = l_router_property,
    };
    dfle_lua_register(L, &type);
    lua_newtable(L);
    lua_pushcfunction(L, l_router_empirical);
    lua_setfield(L, -2, "empirical");
    lua_pushcfunction(L, l_router_process);
    lua_setfield(L, -2, "process");
    dfle_lua_open_router_define(L); /* dfle.router.define (lua_router_define.c) */
    dfle_lua_open_router_population(L); /* dfle.router.population (lua_population.c) */
    lua_setfield(L, -2, "router");
}
