/*
 * lua_model.c - dfle.model{...}: the channel-profile model from Lua.
 *
 *   local m = dfle.model{ channel = ch, U = 5e-4, fluvial = fl,
 *                         router = rt, law = law }
 *   m:run_to_steady{ tol = 1e-3, max_time = 2e7 }
 *   m:get("S"), m:write_csv("profile.csv")
 *
 * Every component is optional and defaults to the paper's (Fig. 9);
 * `fluvial = false` or `router = false` switches that process off.  The
 * model userdata keeps its components alive through user values, so a
 * script may drop its own references to them.
 */
#include "lua/core/dfle_lua.h"
#include "dfle/netcdf.h"

#include <stdio.h>
#include <string.h>
#include <time.h>

enum { UV_CHANNEL = 1, UV_FLUVIAL, UV_ROUTER, UV_LAW,
       UV_U,   /* U(t): the uplift function, or nil */
       UV_RUN, /* the last run since the state was set: {kind =, opts =, result =}, or nil */
       UV_COUNT = UV_RUN };

/* Push component `key` of the options table, or a default built by
 * calling dfle.<ctor_path>{}; push nil when the user said `false`. */
static void push_component(lua_State *L, int opts, const char *key, const char *tname,
                           lua_CFunction fallback_ctor, int can_be_off)
{
    int t = lua_istable(L, opts) ? lua_getfield(L, opts, key) : (lua_pushnil(L), LUA_TNIL);
    if (can_be_off && t == LUA_TBOOLEAN && !lua_toboolean(L, -1)) {
        lua_pop(L, 1);
        lua_pushnil(L);
        return;
    }
    if (t == LUA_TNIL) {
        lua_pop(L, 1);
        lua_pushcfunction(L, fallback_ctor);
        lua_call(L, 0, 1);
        return;
    }
    if (luaL_testudata(L, -1, tname) == NULL)
        luaL_error(L, "dfle.model: parameter '%s' must be a %s%s, got %s", key, tname,
                   can_be_off ? " or false" : "", dfle_lua_typename(L, -1));
}

/* Default constructors, called with no arguments. */
static int default_channel(lua_State *L);
static int default_fluvial(lua_State *L);
static int default_router(lua_State *L);
static int default_law(lua_State *L);

static int call_module_ctor(lua_State *L, const char *sub, const char *name)
{
    dfle_lua_push_module(L);
    if (sub != NULL)
        lua_getfield(L, -1, sub);
    lua_getfield(L, -1, name);
    lua_call(L, 0, 1);
    return 1;
}
static int default_channel(lua_State *L) { return call_module_ctor(L, NULL, "channel"); }
static int default_fluvial(lua_State *L)
{
    return call_module_ctor(L, "fluvial", "stochastic_threshold");
}
static int default_router(lua_State *L) { return call_module_ctor(L, "router", "empirical"); }
static int default_law(lua_State *L) { return call_module_ctor(L, "law", "power"); }

static void *udata_ptr(lua_State *L, int idx)
{
    return lua_isnil(L, idx) ? NULL : dfle_lua_object_ptr(L, idx);
}

static int l_model_new(lua_State *L)
{
    static const char *const component_keys[] = {"channel", "fluvial", "router", "law",
                                                 "network", "k_w", "b", "combine", NULL};
    dfle_model_opts o;
    dfle_lua_model *u;
    dfle_error err;
    int base;
    const dfle_lua_param params[] = {{"U", &o.U}, {"cfl", &o.cfl}, {"dt_max", &o.dt_max}};

    /* U may be a number [m/yr] or a function of model time [yr]. */
    static const char *const component_keys_U[] = {"channel", "fluvial", "router", "law", "U",
                                                   "network", "k_w", "b", "combine", NULL};
    int U_fn;

    dfle_model_opts_default(&o);
    if (!lua_isnoneornil(L, 1))
        luaL_checktype(L, 1, LUA_TTABLE);
    lua_settop(L, 1);
    U_fn = lua_istable(L, 1) && lua_getfield(L, 1, "U") == LUA_TFUNCTION;
    lua_settop(L, 1);
    if (U_fn) {
        dfle_lua_read_params(L, 1, "model", params + 1, 2, component_keys_U);
        lua_getfield(L, 1, "U");
        lua_pushnumber(L, 0.0);
        lua_call(L, 1, 1);
        if (lua_type(L, -1) != LUA_TNUMBER)
            luaL_error(L, "dfle.model: U(t) must return a number, got %s (at t = 0)",
                       dfle_lua_typename(L, -1));
        o.U = lua_tonumber(L, -1);
        lua_settop(L, 1);
    } else {
        dfle_lua_read_params(L, 1, "model", params, 3, component_keys);
    }

    base = lua_gettop(L);
    if (!dfle_lua_model_network(L, 1, &o.network))
        push_component(L, 1, "channel", DFLE_LUA_CHANNEL, default_channel, 0);
    if (lua_istable(L, 1) && lua_getfield(L, 1, "combine") != LUA_TNIL) {
        static const char *const rules[] = {"any", "count", NULL};
        if (o.network == NULL)
            luaL_error(L, "dfle.model: 'combine' is for a network (network =): on a channel "
                          "flows do not meet");
        o.df_combine = luaL_checkoption(L, -1, NULL, rules) == 0 ? DFLE_DF_ANY : DFLE_DF_COUNT;
    }
    lua_settop(L, base + 1);
    push_component(L, 1, "fluvial", DFLE_LUA_FLUVIAL, default_fluvial, 1);
    push_component(L, 1, "router", DFLE_LUA_ROUTER, default_router, 1);
    if (lua_isnil(L, base + 3)) {
        if (lua_getfield(L, 1, "law") != LUA_TNIL)
            luaL_error(L, "dfle.model: 'law' given but router = false (no debris flows)");
        lua_pop(L, 1);
        lua_pushnil(L);
    } else {
        push_component(L, 1, "law", DFLE_LUA_LAW, default_law, 0);
    }

    o.channel = o.network != NULL ? NULL : udata_ptr(L, base + 1);
    o.fluvial = udata_ptr(L, base + 2);
    o.router = udata_ptr(L, base + 3);
    o.law = udata_ptr(L, base + 4);
    if ((o.channel == NULL && o.network == NULL) || (lua_isuserdata(L, base + 2) && o.fluvial == NULL) ||
        (lua_isuserdata(L, base + 3) && o.router == NULL) ||
        (lua_isuserdata(L, base + 4) && o.law == NULL))
        luaL_error(L, "dfle.model: a component has been closed");

    u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_MODEL, UV_COUNT);
    for (int k = UV_CHANNEL; k <= UV_LAW; k++) {
        lua_pushvalue(L, base + k);
        lua_setiuservalue(L, -2, k);
    }
    if (U_fn) {
        lua_getfield(L, 1, "U");
        lua_setiuservalue(L, -2, UV_U);
    }
    if (dfle_model_new(&o, &u->m, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    if (o.network != NULL)
        dfle_lua_model_network_z(L, 1, u->m);
    /* The components now serve this model: a __gc or close of one of
     * them waits until the model is gone (model_release). */
    for (int k = UV_CHANNEL; k <= UV_LAW; k++)
        if (!lua_isnil(L, base + k))
            dfle_lua_hold(L, base + k);
    return 1;
}

/* Raise unless the model at 1 is idle: its state must not change under
 * a run (a call from inside its own U(t), law or router). */
static void check_idle(lua_State *L, const char *what)
{
    dfle_lua_begin_use(L, 1, what);
    dfle_lua_end_use(L, 1);
}

/* The state of the model at 1 was set anew: no run led to it. */
static void forget_run(lua_State *L)
{
    lua_pushnil(L);
    lua_setiuservalue(L, 1, UV_RUN);
}

static int l_model_init_fluvial_steady(lua_State *L)
{
    dfle_model *m = dfle_lua_check_model(L, 1);
    const dfle_fluvial *fl = lua_isnoneornil(L, 2) ? NULL : dfle_lua_check_fluvial(L, 2);
    dfle_error err;
    check_idle(L, "dfle.model:init_fluvial_steady");
    if (dfle_model_init_fluvial_steady(m, fl, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    lua_settop(L, 1);
    forget_run(L);
    return 1;
}

static int l_model_set_z(lua_State *L)
{
    dfle_model *m = dfle_lua_check_model(L, 1);
    size_t n;
    double *z = dfle_lua_check_array(L, 2, "model:set_z: z", &n);
    dfle_error err;
    check_idle(L, "dfle.model:set_z");
    if (dfle_model_set_z(m, z, n, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    lua_settop(L, 1);
    forget_run(L);
    return 1;
}

static int l_model_set_U(lua_State *L)
{
    dfle_model *m = dfle_lua_check_model(L, 1);
    dfle_error err;
    check_idle(L, "dfle.model:set_U");
    if (dfle_model_set_U(m, luaL_checknumber(L, 2), &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    lua_pushnil(L); /* a constant U replaces a U(t) function */
    dfle_lua_warn_implausible(L, "model:set_U", "U", lua_tonumber(L, 2));
    lua_setiuservalue(L, 1, UV_U);
    lua_settop(L, 1);
    forget_run(L);
    return 1;
}

static void push_result(lua_State *L, const dfle_run_result *r)
{
    lua_createtable(L, 0, 9);
    lua_pushboolean(L, r->converged), lua_setfield(L, -2, "converged");
    lua_pushstring(L, dfle_stop_reason_name(r->reason)), lua_setfield(L, -2, "reason");
    lua_pushnumber(L, r->time), lua_setfield(L, -2, "time");
    lua_pushinteger(L, (lua_Integer)r->steps), lua_setfield(L, -2, "steps");
    lua_pushinteger(L, (lua_Integer)r->routings), lua_setfield(L, -2, "routings");
    lua_pushnumber(L, r->rate_ratio), lua_setfield(L, -2, "rate_ratio");
    lua_pushnumber(L, r->dt_min), lua_setfield(L, -2, "dt_min");
    lua_pushnumber(L, r->dt_max), lua_setfield(L, -2, "dt_max");
    lua_pushinteger(L, (lua_Integer)r->nonpositive_slope_nodes);
    lua_setfield(L, -2, "nonpositive_slope_nodes");
    lua_pushstring(L, dfle_method_name(r->method)), lua_setfield(L, -2, "method");
    lua_pushboolean(L, r->fallback), lua_setfield(L, -2, "fallback");
    lua_pushinteger(L, (lua_Integer)r->iterations), lua_setfield(L, -2, "iterations");
    if (r->note[0] != '\0')
        lua_pushstring(L, r->note), lua_setfield(L, -2, "note");
}

/* The run's uplift callback: calls the model's
 * U function (at stack index fidx of L, the thread running the run) under
 * lua_pcall with a traceback, so an error comes back as a status. */
typedef struct { lua_State *L; int fidx; } uplift_ctx;

static int uplift_msgh(lua_State *L)
{
    const char *msg = lua_tostring(L, 1);
    luaL_traceback(L, L, msg != NULL ? msg : "(error object is not a string)", 1);
    return 1;
}

static int lua_uplift(void *ud, double t, double *U, dfle_error *err)
{
    uplift_ctx *c = ud;
    lua_State *L = c->L;
    int top = lua_gettop(L), ok;
    lua_pushcfunction(L, uplift_msgh);
    lua_pushvalue(L, c->fidx);
    lua_pushnumber(L, t);
    dfle_lua_touch(L); /* U(t) may change what a compiled law read */
    if (lua_pcall(L, 1, 1, top + 1) != LUA_OK) {
        dfle_error_set(err, DFLE_ECALLBACK, "model: U(t) failed at t = %g yr: %s", t,
                       lua_tostring(L, -1) != NULL ? lua_tostring(L, -1) : "?");
        lua_settop(L, top);
        return DFLE_ECALLBACK;
    }
    ok = lua_type(L, -1) == LUA_TNUMBER;
    if (ok)
        *U = lua_tonumber(L, -1);
    else
        dfle_error_set(err, DFLE_ECALLBACK, "model: U(t) must return a number, got %s (at t = %g yr)",
                       dfle_lua_typename(L, -1), t);
    lua_settop(L, top);
    return ok ? DFLE_OK : DFLE_ECALLBACK;
}

/* Keep what the run at the top of the stack was asked and gave, for the
 * model's records (dfle_lua_record_model). */
static void remember_run(lua_State *L, int steady, const dfle_run_opts *o, double years)
{
    lua_createtable(L, 0, 3);
    lua_pushstring(L, steady ? "run_to_steady" : "run");
    lua_setfield(L, -2, "kind");
    lua_createtable(L, 0, 5);
    lua_pushstring(L, dfle_method_name(o->method));
    lua_setfield(L, -2, "method_asked"); /* the result says which ran */
    if (steady) {
        lua_pushnumber(L, o->tol), lua_setfield(L, -2, "tol");
        lua_pushnumber(L, o->max_time), lua_setfield(L, -2, "max_time");
        lua_pushnumber(L, o->direct_tol), lua_setfield(L, -2, "direct_tol");
    } else {
        lua_pushnumber(L, years), lua_setfield(L, -2, "years");
        lua_pushnumber(L, o->rtol), lua_setfield(L, -2, "rtol");
    }
    lua_pushinteger(L, (lua_Integer)o->max_steps), lua_setfield(L, -2, "max_steps");
    lua_setfield(L, -2, "opts");
    lua_newtable(L);
    dfle_lua_copy_table(L, -3, -1); /* a copy: the script may change its own */
    lua_setfield(L, -2, "result");
    lua_setiuservalue(L, 1, UV_RUN);
}

/* Shared by run_to_steady and run: `steady` selects the defaults. */
/* m:run{ record = {...}, netcdf = path [, float32 = true] }: the recorded
 * states z(t, x) as a CF NetCDF file (netcdf.h), with the model's record
 * (every parameter, the run) as its global attributes. */
static void write_records(lua_State *L, dfle_model *m, const char *path, const dfle_run_opts *o,
                          const dfle_run_result *res, int float32)
{
    static const dfle_nc_var z_var = {"z", "m", "elevation above the outlet", NULL, NULL};
    const double *x, *A, *values[1];
    dfle_nc_opts no;
    dfle_record *rec;
    dfle_error err;
    if ((x = dfle_model_field(m, DFLE_FIELD_X, &err)) == NULL ||
        (A = dfle_model_field(m, DFLE_FIELD_A, &err)) == NULL)
        dfle_lua_raise(L, &err);
    if (res->n_recorded == 0)
        luaL_error(L, "dfle.model:run: no record time was reached; '%s' not written", path);
    values[0] = o->record_z;
    dfle_nc_opts_default(&no);
    no.title = "dfle: a channel profile's recorded states (m:run)";
    no.float32 = float32;
    rec = dfle_lua_push_record(L, "the recorded states z(time, x) of a channel profile, x "
                                  "from the head");
    dfle_lua_record_model(L, rec, 1);
    no.provenance = rec;
    if (dfle_nc_write_profiles(path, dfle_model_size(m), x, A, res->n_recorded, o->record_times,
                               1, &z_var, values, &no, &err) != DFLE_OK)
        dfle_lua_raise(L, &err);
    lua_pop(L, 1);
    dfle_lua_note_file(L, path);
    dfle_lua_note(L, DFLE_LUA_DETAIL, "wrote %s (%zu states of %zu nodes)", path, res->n_recorded,
                  dfle_model_size(m));
}

/* How a run ended, for its --verbose line. */
static const char *outcome(int steady, int reason)
{
    switch (reason) {
    case DFLE_STOP_STEADY:
        return "steady";
    case DFLE_STOP_TIME:
        return steady ? "not steady at max_time" : "done";
    case DFLE_STOP_STEPS:
        return "stopped at max_steps";
    default:
        return "interrupted";
    }
}

/* Wall-clock seconds, for the --verbose line of a run. */
static double clock_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int model_run(lua_State *L, int steady)
{
    static const char *const steady_keys[] = {"progress", "method", NULL};
    static const char *const run_keys[] = {"progress", "method", "record", "netcdf", "float32",
                                           NULL};
    dfle_model *m = dfle_lua_check_model(L, 1);
    const char *fn = steady ? "model:run_to_steady" : "model:run";
    dfle_run_opts o;
    dfle_run_result res;
    dfle_error err;
    double max_steps, years = -1;
    const dfle_lua_progress *prog = dfle_lua_get_progress(L);
    const char *netcdf = NULL;
    int float32 = 0;
    int keep;
    double wall;
    int st;

    lua_settop(L, 2);
    dfle_run_opts_default(&o);
    o.method = steady ? DFLE_METHOD_AUTO : DFLE_METHOD_EXPLICIT;
    max_steps = (double)o.max_steps;
    if (steady) {
        const dfle_lua_param params[] = {{"tol", &o.tol}, {"max_time", &o.max_time},
                                         {"max_steps", &max_steps}, {"direct_tol", &o.direct_tol}};
        dfle_lua_read_params(L, 2, fn, params, 4, steady_keys);
    } else {
        const dfle_lua_param params[] = {{"years", &years}, {"max_steps", &max_steps},
                                         {"rtol", &o.rtol}};
        luaL_checktype(L, 2, LUA_TTABLE);
        dfle_lua_read_params(L, 2, fn, params, 3, run_keys);
        if (lua_getfield(L, 2, "years") == LUA_TNIL)
            luaL_error(L, "dfle.model:run: parameter 'years' is required");
        lua_pop(L, 1);
        /* `years` is this API's name for the run's max_time */
        if (!(years > 0))
            luaL_error(L, "dfle.model:run: years must be > 0 (got %s)", dfle_lua_number_text(L, years));
        o.max_time = years;
        o.tol = 0; /* plain time stepping: no steady-state stop */
    }
    o.max_steps = (size_t)dfle_lua_check_whole(L, max_steps, fn, "max_steps", 1, 1e15);
    if (lua_istable(L, 2) && lua_getfield(L, 2, "method") != LUA_TNIL) {
        if (lua_type(L, -1) != LUA_TSTRING)
            luaL_error(L, "dfle.%s: parameter 'method' must be a string, got %s", fn,
                       dfle_lua_typename(L, -1));
        o.method = dfle_lua_check_method(L, -1, fn);
    }
    lua_settop(L, 2);
    if (lua_istable(L, 2) && lua_getfield(L, 2, "record") != LUA_TNIL) {
        size_t k;
        o.record_times = dfle_lua_check_array(L, 3, "model:run: record", &k);
        o.n_record = k;
        o.record_z = (double *)o.record_times; /* checked below, before the space is made */
    }
    /* The options, checked once, by the solvers' own rules. */
    if (dfle_run_opts_check(&o, steady, &err) != DFLE_OK)
        return luaL_error(L, "dfle.%s: %s", fn, err.msg);
    if (o.n_record > 0)
        o.record_z = lua_newuserdatauv(L, o.n_record * dfle_model_size(m) * sizeof(double), 0);
    keep = lua_gettop(L); /* the record arrays stay for the run */
    if (lua_istable(L, 2) && lua_getfield(L, 2, "netcdf") != LUA_TNIL) {
        if (lua_type(L, -1) != LUA_TSTRING)
            luaL_error(L, "dfle.%s: parameter 'netcdf' must be a file name, got %s", fn,
                       dfle_lua_typename(L, -1));
        netcdf = dfle_lua_check_string(L, -1, fn, "netcdf"); /* the options table keeps it */
        if (o.n_record == 0)
            luaL_error(L, "dfle.model:run: 'netcdf' writes the recorded states: give 'record' "
                          "times too");
    }
    lua_settop(L, keep);
    if (lua_istable(L, 2) && lua_getfield(L, 2, "float32") != LUA_TNIL) {
        if (!lua_isboolean(L, -1) || netcdf == NULL)
            luaL_error(L, "dfle.%s: parameter 'float32' (true or false) goes with 'netcdf'", fn);
        float32 = lua_toboolean(L, -1);
    }
    lua_settop(L, keep);
    if (lua_istable(L, 2) && lua_getfield(L, 2, "progress") != LUA_TNIL) {
        if (!lua_isboolean(L, -1))
            luaL_error(L, "dfle.%s: parameter 'progress' must be a boolean", fn);
        if (!lua_toboolean(L, -1))
            prog = NULL;
    }
    if (prog != NULL) {
        o.progress = prog->update;
        o.progress_ud = prog->ud;
    }
    /* After an interrupt, nothing new starts (dfle_lua_set_interrupt). */
    dfle_lua_check_interrupt(L, fn);
    o.interrupt = dfle_lua_get_interrupt(L);
    /* A U(t) function stays on the stack for the run. */
    uplift_ctx uc = {L, 0};
    if (lua_getiuservalue(L, 1, UV_U) == LUA_TFUNCTION) {
        uc.fidx = lua_gettop(L);
        o.uplift = lua_uplift;
        o.uplift_ud = &uc;
    }
    /* In use for the run: U(t), laws and routers written in Lua run in
     * the middle of it, and may neither free the model nor run it again. */
    wall = clock_seconds();
    dfle_lua_begin_use(L, 1, steady ? "dfle.model:run_to_steady" : "dfle.model:run");
    st = dfle_solver_run(m, &o, &res, &err);
    wall = clock_seconds() - wall;
    dfle_lua_end_use(L, 1);
    if (prog != NULL && prog->finish != NULL)
        prog->finish(prog->ud);
    if (st != DFLE_OK)
        return dfle_lua_raise(L, &err);
    if (res.reason == DFLE_STOP_INTERRUPTED)
        dfle_lua_set_interrupt_note(L, "%s stopped at t = %f yr after %d steps and returned its "
                                       "state so far (reason \"interrupted\")", fn,
                                    dfle_model_time(m), (int)res.steps);
    if (res.method == DFLE_METHOD_DIRECT)
        dfle_lua_note(L, DFLE_LUA_DETAIL, "%s: %s by the direct solve (%zu rounds, %zu routings; %.2f s)",
                      fn, outcome(steady, res.reason), res.iterations, res.routings, wall);
    else
        dfle_lua_note(L, DFLE_LUA_DETAIL, "%s: %s after %zu %s steps, t = %g yr%s (%.2f s)", fn,
                      outcome(steady, res.reason), res.steps, dfle_method_name(res.method),
                      res.time, res.fallback ? ", after the direct solve fell back" : "", wall);
    push_result(L, &res);
    remember_run(L, steady, &o, years);
    if (o.n_record > 0) {
        const size_t n = dfle_model_size(m);
        lua_createtable(L, (int)res.n_recorded, 0);
        for (size_t j = 0; j < res.n_recorded; j++) {
            lua_createtable(L, 0, 2);
            lua_pushnumber(L, o.record_times[j]), lua_setfield(L, -2, "t");
            dfle_lua_push_array(L, o.record_z + j * n, n), lua_setfield(L, -2, "z");
            lua_rawseti(L, -2, (lua_Integer)j + 1);
        }
        lua_setfield(L, -2, "records");
    }
    if (netcdf != NULL)
        write_records(L, m, netcdf, &o, &res, float32);
    return 1;
}

static int l_model_run_to_steady(lua_State *L) { return model_run(L, 1); }
static int l_model_run(lua_State *L) { return model_run(L, 0); }

static void push_field_names(lua_State *L)
{
    luaL_Buffer b;
    luaL_buffinit(L, &b);
    for (int f = 0; f < DFLE_FIELD_COUNT; f++) {
        if (f)
            luaL_addstring(&b, ", ");
        luaL_addstring(&b, dfle_field_name(f));
    }
    luaL_pushresult(&b);
}

static int l_model_get(lua_State *L)
{
    dfle_model *m = dfle_lua_check_model(L, 1);
    const char *name = dfle_lua_check_string(L, 2, "model:get", "the field name");
    int f = dfle_field_lookup(name);
    const double *v;

    if (f < 0) {
        push_field_names(L);
        return luaL_error(L, "dfle.model:get: no field '%s' (fields: %s)", name,
                          lua_tostring(L, -1));
    }
    v = dfle_lua_model_field(L, 1, f, "dfle.model:get");
    dfle_lua_push_array(L, v, dfle_model_size(m));
    return 1;
}

static int l_model_fields(lua_State *L)
{
    lua_createtable(L, DFLE_FIELD_COUNT, 0);
    for (int f = 0; f < DFLE_FIELD_COUNT; f++) {
        lua_pushstring(L, dfle_field_name(f));
        lua_rawseti(L, -2, f + 1);
    }
    return 1;
}

/* The run result's values a record keeps, in this order, with units. */
static const struct { const char *key, *unit; } run_keys[] = {
    {"converged", NULL}, {"reason", NULL},   {"method", NULL},   {"fallback", NULL},
    {"note", NULL},      {"time", "yr"},     {"steps", NULL},    {"routings", NULL},
    {"iterations", NULL}, {"rate_ratio", NULL}, {"dt_min", "yr"}, {"dt_max", "yr"},
    {"nonpositive_slope_nodes", NULL}};
/* ... and the options it was given. */
static const struct { const char *key, *unit; } run_opts[] = {
    {"method_asked", NULL}, {"tol", NULL}, {"max_time", "yr"}, {"direct_tol", NULL},
    {"years", "yr"}, {"rtol", NULL}, {"max_steps", NULL}};

void dfle_lua_record_model(lua_State *L, dfle_record *rec, int idx)
{
    dfle_model *m = dfle_lua_check_model(L, idx);
    int top = lua_gettop(L);

    idx = lua_absindex(L, idx);
    dfle_model_describe(m, rec);
    /* Components written in Lua keep their params in Lua. */
    dfle_lua_record_lua_parts(L, rec, idx, UV_ROUTER, UV_LAW);
    if (lua_getiuservalue(L, idx, UV_U) == LUA_TFUNCTION) {
        dfle_record_section(rec, "model", NULL);
        dfle_record_bool(rec, "U_of_t", 1);
    }
    lua_settop(L, top);
    if (lua_getiuservalue(L, idx, UV_RUN) == LUA_TTABLE) {
        int run = lua_gettop(L);
        lua_getfield(L, run, "kind");
        dfle_record_section(rec, "run", lua_tostring(L, -1));
        lua_getfield(L, run, "opts");
        for (size_t k = 0; k < sizeof run_opts / sizeof run_opts[0]; k++) {
            int t = lua_getfield(L, -1, run_opts[k].key);
            if (t == LUA_TNUMBER)
                dfle_record_param_number(rec, run_opts[k].key, lua_tonumber(L, -1),
                                         run_opts[k].unit);
            else if (t == LUA_TSTRING)
                dfle_record_param_text(rec, run_opts[k].key, lua_tostring(L, -1));
            lua_pop(L, 1);
        }
        lua_getfield(L, run, "result");
        for (size_t k = 0; k < sizeof run_keys / sizeof run_keys[0]; k++) {
            int t = lua_getfield(L, -1, run_keys[k].key);
            if (t == LUA_TNUMBER)
                dfle_record_number(rec, run_keys[k].key, lua_tonumber(L, -1), run_keys[k].unit);
            else if (t == LUA_TBOOLEAN)
                dfle_record_bool(rec, run_keys[k].key, lua_toboolean(L, -1));
            else if (t == LUA_TSTRING)
                dfle_record_text(rec, run_keys[k].key, lua_tostring(L, -1));
            lua_pop(L, 1);
        }
    }
    lua_settop(L, top);
}

/* m:write_csv(path [, { record = true | false | "run.json" }]) */
static int l_model_write_csv(lua_State *L)
{
    dfle_model *m = dfle_lua_check_model(L, 1);
    const char *path = dfle_lua_check_string(L, 2, "model:write_csv", "the path");
    dfle_record *rec;
    const char *jpath;
    dfle_error err;
    int st;

    lua_settop(L, 3);
    if (!lua_isnil(L, 3)) {
        static const char *const keys[] = {"record", NULL};
        luaL_checktype(L, 3, LUA_TTABLE);
        dfle_lua_read_params(L, 3, "model:write_csv", NULL, 0, keys);
    }
    rec = dfle_lua_push_record(L, "model profile: one row per node, from the channel head "
                                  "(x = 0) to the outlet");
    check_idle(L, "dfle.model:write_csv");
    dfle_lua_record_model(L, rec, 1);
    jpath = dfle_lua_record_path(L, rec, 3, path, "model:write_csv");
    dfle_lua_begin_use(L, 1, "dfle.model:write_csv");
    st = dfle_model_write_csv(m, path, rec, &err);
    dfle_lua_end_use(L, 1);
    if (st != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_record_done(L, rec, path, jpath);
    dfle_lua_note(L, DFLE_LUA_DETAIL, "wrote %s (%zu nodes)", path, dfle_model_size(m));
    lua_settop(L, 1);
    return 1;
}

/* m:write_record(path): the JSON record alone (a run kept as plots). */
static int l_model_write_record(lua_State *L)
{
    const char *path = dfle_lua_check_string(L, 2, "model:write_record", "the path");
    dfle_record *rec;
    dfle_lua_check_model(L, 1);
    lua_settop(L, 2);
    rec = dfle_lua_push_record(L, "model");
    dfle_lua_record_model(L, rec, 1);
    dfle_lua_write_record(L, rec, NULL, path);
    lua_settop(L, 1);
    return 1;
}

static size_t model_params(const void *m, dfle_param *out, size_t cap)
{
    return dfle_model_params(m, out, cap);
}

/* m:params(): U (now), cfl, dt_max, and each component's params() under
 * its name (false for a process that is off). */
static int l_model_params(lua_State *L)
{
    static const char *const components[] = {"channel", "fluvial", "router", "law"};
    dfle_lua_push_params(L, 1, model_params, dfle_lua_check_model(L, 1));
    for (int k = 0; k < 4; k++) {
        if (lua_getiuservalue(L, 1, k + 1) == LUA_TNIL) {
            lua_pop(L, 1);
            lua_pushboolean(L, 0);
        } else {
            /* The component's own method: each kind knows its list. */
            lua_getfield(L, -1, "params");
            lua_insert(L, -2);
            lua_call(L, 1, 1);
        }
        lua_setfield(L, -2, components[k]);
    }
    return 1;
}

static int l_model_property(lua_State *L)
{
    dfle_model *m = dfle_lua_check_model(L, 1);
    const char *key = lua_tostring(L, 2);
    static const char *const components[] = {"channel", "fluvial", "router", "law"};

    if (strcmp(key, "time") == 0) {
        lua_pushnumber(L, dfle_model_time(m));
        return 1;
    }
    if (strcmp(key, "U") == 0) {
        lua_pushnumber(L, dfle_model_U(m));
        return 1;
    }
    if (strcmp(key, "n") == 0) {
        lua_pushinteger(L, (lua_Integer)dfle_model_size(m));
        return 1;
    }
    if (strcmp(key, "has_run") == 0) { /* the profile is a run's, not one set */
        lua_pushboolean(L, lua_getiuservalue(L, 1, UV_RUN) == LUA_TTABLE);
        return 1;
    }
    for (int k = 0; k < 4; k++)
        if (strcmp(key, components[k]) == 0) {
            lua_getiuservalue(L, 1, k + 1);
            return 1;
        }
    return 0; /* not a field: __index says so */
}

static void model_describe(lua_State *L, void *obj)
{
    dfle_model *m = obj;
    char buf[200];
    snprintf(buf, sizeof buf, "dfle.model(n = %zu, U = %g m/yr, t = %g yr, fluvial = %s, router = %s)",
             dfle_model_size(m), dfle_model_U(m), dfle_model_time(m),
             dfle_model_fluvial(m) ? dfle_fluvial_name(dfle_model_fluvial(m)) : "off",
             dfle_model_router(m) ? dfle_router_name(dfle_model_router(m)) : "off");
    lua_pushstring(L, buf);
}

static void model_free(void *obj) { dfle_model_free(obj); }

/* The model is freed: its components are free to go too. */
static void model_release(lua_State *L, int idx)
{
    for (int k = UV_CHANNEL; k <= UV_LAW; k++) {
        if (lua_getiuservalue(L, idx, k) == LUA_TUSERDATA)
            dfle_lua_unhold(L, lua_gettop(L));
        lua_pop(L, 1);
    }
}

void dfle_lua_open_model(lua_State *L)
{
    static const luaL_Reg methods[] = {
        {"init_fluvial_steady", l_model_init_fluvial_steady},
        {"set_z", l_model_set_z},
        {"set_U", l_model_set_U},
        {"run_to_steady", l_model_run_to_steady},
        {"run", l_model_run},
        {"run_events", dfle_lua_model_run_events},
        {"get", l_model_get},
        {"fields", l_model_fields},
        {"write_csv", l_model_write_csv},
        {"params", l_model_params},
        {"write_record", l_model_write_record},
        {NULL, NULL}};
    static const dfle_lua_type type = {
        .name = DFLE_LUA_MODEL, .free = model_free, .describe = model_describe,
        .methods = methods, .property = l_model_property, .closable = 1,
        .fields = "time, U, n, channel, fluvial, router, law",
        /* Read-only: say how to change them. */
        .setters = "U: m:set_U(U); z: m:set_z(z)",
        .release = model_release,
    };
    dfle_lua_register(L, &type);
    lua_pushcfunction(L, l_model_new);
    lua_setfield(L, -2, "model");
}
