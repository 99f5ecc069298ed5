/*
 * lua_landscape.c - dfle.landscape{...}: the model on a raster grid
 * (landscape.h) from Lua.
 *
 *   local ls = dfle.landscape{ nx = 200, ny = 200, dx = 30, U = 5e-4,
 *                              noise = { amplitude = 1, seed = 7 } }
 *   local ls = dfle.landscape{ dem = dfle.dem.read(path), outlet = {E, N} }
 *   ls:run_to_steady{ tol = 1e-3 }           ls:run{ years = 1e5, dt = 500 }
 *   ls:get("z"), ls:write_geotiff("z.tif", {"z", "E_df"}), ls:plot("map.png")
 *
 * Components are held as a model holds them (user values, pins); fields
 * given as Lua functions and a custom combine rule are kept as registry
 * references and called back during runs, under lua_pcall, with the
 * thread that runs the call; an error in one comes back as the run's
 * error with the function's own message.  Building one (dfle.landscape
 * itself) is in lua_landscape_new.c; the methods are here.
 */
#include "lua/core/dfle_lua.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/dem.h"
#include "dfle/landscape.h"
#include "dfle/plot.h"
#include "dfle/raster.h"

#include "lua/objects/lua_landscape.h"
#include "lua/objects/lua_events.h"

static lua_ls *check_ls(lua_State *L, int arg)
{
    dfle_lua_check_object(L, arg, DFLE_LUA_LANDSCAPE);
    return lua_touserdata(L, arg);
}

/* Raise err, preferring a callback's own message. */
int dfle_lua_ls_raise(lua_State *L, lua_ls *u, const dfle_error *err)
{
    if (u->cb_err[0] != '\0') {
        dfle_error e;
        e.code = DFLE_ECALLBACK;
        snprintf(e.msg, sizeof e.msg, "%s", u->cb_err);
        u->cb_err[0] = '\0';
        return dfle_lua_raise(L, &e);
    }
    return dfle_lua_raise(L, err);
}

/* ---------------------------------------------------------------- */
/* Methods                                                          */
/* ---------------------------------------------------------------- */

/* Begin a call that may run Lua code (fields, combine, Lua laws). */
static lua_ls *begin(lua_State *L, const char *what)
{
    lua_ls *u = check_ls(L, 1);
    dfle_lua_begin_use(L, 1, what);
    u->L = L;
    u->cb_err[0] = '\0';
    return u;
}

static int field_id(lua_State *L, int idx, const char *fn)
{
    const char *name = dfle_lua_check_string(L, idx, fn, "the field name");
    int f = dfle_landscape_field_lookup(name);
    if (f < 0) {
        luaL_Buffer b;
        luaL_buffinit(L, &b);
        for (int k = 0; k < DFLE_LS_NFIELDS; k++) {
            luaL_addstring(&b, k ? ", " : "");
            luaL_addstring(&b, dfle_landscape_field_name(k));
        }
        luaL_pushresult(&b);
        luaL_error(L, "dfle.%s: no field '%s' (fields: %s)", fn, name, lua_tostring(L, -1));
    }
    return f;
}

/* The field's nx * ny values into a scratch userdata left on the stack. */
static double *get_field(lua_State *L, int field, const char *what)
{
    lua_ls *u = check_ls(L, 1);
    size_t n = dfle_landscape_nx(u->ls) * dfle_landscape_ny(u->ls);
    double *v = lua_newuserdatauv(L, n * sizeof *v, 0);
    dfle_error err;
    int st;
    begin(L, what);
    st = dfle_landscape_get(u->ls, field, v, &err);
    dfle_lua_end_use(L, 1);
    if (st != DFLE_OK)
        dfle_lua_ls_raise(L, u, &err);
    return v;
}

static int l_get(lua_State *L)
{
    lua_ls *u = check_ls(L, 1);
    int f = field_id(L, 2, "landscape:get");
    double *v = get_field(L, f, "dfle.landscape:get");
    dfle_lua_push_array(L, v, dfle_landscape_nx(u->ls) * dfle_landscape_ny(u->ls));
    return 1;
}

static int l_fields(lua_State *L)
{
    lua_createtable(L, DFLE_LS_NFIELDS, 0);
    for (int f = 0; f < DFLE_LS_NFIELDS; f++) {
        lua_pushstring(L, dfle_landscape_field_name(f));
        lua_rawseti(L, -2, f + 1);
    }
    return 1;
}

static void push_status(lua_State *L, const dfle_landscape_status *s)
{
#define NUM(k, v) (lua_pushnumber(L, (v)), lua_setfield(L, -2, k))
#define INT(k, v) (lua_pushinteger(L, (lua_Integer)(v)), lua_setfield(L, -2, k))
    NUM("q_ratio", s->q_ratio);
    NUM("mean_ratio", s->mean_ratio);
    NUM("max_ratio", s->max_ratio);
    NUM("frac_above", s->frac_above);
    NUM("channel_q_ratio", s->channel_q_ratio);
    NUM("channel_max_ratio", s->channel_max_ratio);
    NUM("channel_frac_above", s->channel_frac_above);
    INT("channel_above", s->channel_above);
    NUM("hillslope_q_ratio", s->hillslope_q_ratio);
    NUM("hillslope_max_ratio", s->hillslope_max_ratio);
    NUM("hillslope_frac_above", s->hillslope_frac_above);
    NUM("uplift_flux", s->uplift_flux);
    NUM("outflux", s->outflux);
    NUM("volume_balance", s->volume_balance);
    INT("rcv_changes", s->rcv_changes);
    INT("stable", s->stable);
    INT("channel_cells", s->channel_cells);
    INT("heads", s->heads);
    INT("reached", s->reached);
    NUM("dV", s->dV);
    NUM("V_uplift", s->V_uplift);
    NUM("V_fluvial", s->V_fluvial);
    NUM("V_df", s->V_df);
    NUM("V_hillslope", s->V_hillslope);
    NUM("dt", s->dt);
#undef NUM
#undef INT
}

/* ls:step(dt) -> status table */
static int l_step(lua_State *L)
{
    lua_ls *u = check_ls(L, 1);
    double dt = luaL_checknumber(L, 2);
    dfle_landscape_status st;
    dfle_error err;
    int s;
    dfle_lua_check_interrupt(L, "landscape:step");
    begin(L, "dfle.landscape:step");
    s = dfle_landscape_step(u->ls, dt, 1e-3, &st, &err);
    dfle_lua_end_use(L, 1);
    if (s != DFLE_OK)
        return dfle_lua_ls_raise(L, u, &err);
    lua_createtable(L, 0, 16);
    push_status(L, &st);
    return 1;
}

/* What a run carries to its callbacks. */
typedef struct run_ctx {
    lua_ls *u;
    lua_ls_series series; /* the NetCDF time series (lua_landscape_files.c) */
    const dfle_lua_progress *prog;
    double max_time, tol;
    const char *fn, *ratio_name;
} run_ctx;

static int progress_cb(void *ud, const dfle_landscape_status *s)
{
    run_ctx *c = ud;
    /* A transient shows its time only (tol 0): the steady target means
     * nothing for a run of fixed length. */
    dfle_run_status rs = {.time = s->time, .max_time = c->max_time, .steps = s->steps,
                          .dt = s->dt, .rate_ratio = s->channel_q_ratio, .tol = c->tol,
                          .fraction = s->fraction, .ratio_name = c->ratio_name};
    return c->prog->update(c->prog->ud, &rs);
}

/* The run's doubts, as warnings at the script's line. */
static void warn_cb(void *ud, const char *msg)
{
    run_ctx *c = ud;
    dfle_lua_warn(c->u->L, c->fn, msg);
}

static int landscape_run(lua_State *L, int steady)
{
    static const char *const other[] = {"method", "record", "netcdf", "fields", "float32",
                                        "progress", NULL};
    const char *fn = steady ? "landscape:run_to_steady" : "landscape:run";
    lua_ls *u = check_ls(L, 1);
    dfle_landscape_run_opts o;
    dfle_landscape_result res;
    dfle_error err;
    double years = 0, max_steps, stable, verify_steps;
    run_ctx ctx;
    int st;

    memset(&ctx, 0, sizeof ctx);
    ctx.u = u;
    ctx.fn = fn;
    lua_settop(L, 2);
    if (!steady)
        luaL_checktype(L, 2, LUA_TTABLE);
    dfle_landscape_run_opts_default(&o);
    max_steps = (double)o.max_steps;
    stable = (double)o.stable_steps;
    verify_steps = (double)o.verify_steps;
    {
        int rcv_tol_given = lua_istable(L, 2) && lua_getfield(L, 2, "rcv_tol") != LUA_TNIL &&
                            lua_getfield(L, 2, "rcv_tol_cycle") == LUA_TNIL;
        const dfle_lua_param sp[] = {{"tol", &o.tol}, {"channel_quantile", &o.channel_quantile},
                                     {"hillslope_quantile", &o.hillslope_quantile},
                                     {"stable_steps", &stable}, {"max_time", &o.max_time},
                                     {"max_steps", &max_steps}, {"dt", &o.dt}, {"cfl", &o.cfl},
                                     {"rcv_tol", &o.rcv_tol}, {"rcv_tol_cycle", &o.rcv_tol_cycle},
                                     {"verify_steps", &verify_steps},
                                     {"verify_dt", &o.verify_dt}};
        const dfle_lua_param tp[] = {{"years", &years}, {"max_steps", &max_steps},
                                     {"dt", &o.dt}, {"cfl", &o.cfl}};
        lua_settop(L, 2);
        if (steady)
            dfle_lua_read_params(L, 2, fn, sp, sizeof sp / sizeof sp[0], other);
        else
            dfle_lua_read_params(L, 2, fn, tp, sizeof tp / sizeof tp[0], other);
        /* A looser rcv_tol given without rcv_tol_cycle is the rule
         * throughout (the cycle rule cannot be stricter than it). */
        if (rcv_tol_given && o.rcv_tol_cycle < o.rcv_tol)
            o.rcv_tol_cycle = o.rcv_tol;
    }
    if (!steady) {
        if (!(years > 0))
            luaL_error(L, "dfle.landscape:run: parameter 'years' (> 0) is required");
        o.years = years;
    }
    o.max_steps = (size_t)dfle_lua_check_whole(L, max_steps, fn, "max_steps", 1, 1e15);
    o.stable_steps = (size_t)dfle_lua_check_whole(L, stable, fn, "stable_steps", 0, 1e9);
    o.verify_steps = (size_t)dfle_lua_check_whole(L, verify_steps, fn, "verify_steps", 0, 1000);
    o.method = steady ? DFLE_METHOD_AUTO : DFLE_METHOD_IMPLICIT;
    if (lua_istable(L, 2) && lua_getfield(L, 2, "method") != LUA_TNIL) {
        o.method = dfle_lua_check_method(L, -1, fn);
        if (!steady && o.method == DFLE_METHOD_DIRECT)
            luaL_error(L, "dfle.landscape:run: method 'direct' finds steady states only; use "
                          "run_to_steady, or 'implicit' or 'explicit' here");
    }
    lua_settop(L, 2);
    /* Records into NetCDF: record = {t, ...} [yr], netcdf = path,
     * fields = {"z", ...} (default z), float32 = true. */
    dfle_lua_ls_series_open(L, u, 2, fn, &o, &ctx.series);
    ctx.prog = dfle_lua_get_progress(L);
    if (lua_istable(L, 2) && lua_getfield(L, 2, "progress") != LUA_TNIL && !lua_toboolean(L, -1))
        ctx.prog = NULL;
    ctx.max_time = steady ? o.max_time : years;
    ctx.tol = steady ? o.tol : 0.0;
    ctx.ratio_name = "channel |dz/dt|/U (q99)";
    o.warn = warn_cb;
    o.warn_ud = &ctx;
    if (ctx.prog != NULL && ctx.prog->update != NULL) {
        o.progress = progress_cb;
        o.progress_ud = &ctx;
    }
    if (dfle_lua_interrupted(L)) {
        dfle_lua_ls_series_abort(&ctx.series);
        dfle_lua_check_interrupt(L, fn);
    }
    o.interrupt = dfle_lua_get_interrupt(L);
    begin(L, steady ? "dfle.landscape:run_to_steady" : "dfle.landscape:run");
    st = dfle_landscape_run(u->ls, &o, &res, &err);
    dfle_lua_end_use(L, 1);
    if (ctx.prog != NULL && ctx.prog->finish != NULL)
        ctx.prog->finish(ctx.prog->ud);
    if (st != DFLE_OK) {
        dfle_lua_ls_series_abort(&ctx.series); /* nothing half-written */
        return dfle_lua_ls_raise(L, u, &err);
    }
    if (dfle_lua_ls_series_close(L, &ctx.series, &res, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    if (res.reason == DFLE_STOP_INTERRUPTED)
        dfle_lua_set_interrupt_note(L, "%s stopped at t = %f yr and kept its state (reason "
                                       "\"interrupted\")", fn, dfle_landscape_time(u->ls));
    else if (steady && !res.converged) /* never silently */
        dfle_lua_warn(L, fn, res.note);
    lua_createtable(L, 0, 40);
    lua_pushboolean(L, res.converged), lua_setfield(L, -2, "converged");
    lua_pushboolean(L, res.verified), lua_setfield(L, -2, "verified");
    lua_pushinteger(L, (lua_Integer)res.verify_steps), lua_setfield(L, -2, "verify_steps");
    lua_pushnumber(L, res.rcv_tol), lua_setfield(L, -2, "rcv_tol");
    if (res.verify_steps > 0) {
        lua_createtable(L, 0, 20);
        push_status(L, &res.verify);
        lua_setfield(L, -2, "verify");
    }
    lua_pushstring(L, dfle_stop_reason_name(res.reason)), lua_setfield(L, -2, "reason");
    lua_pushstring(L, dfle_method_name(res.method)), lua_setfield(L, -2, "method");
    lua_pushboolean(L, res.fallback), lua_setfield(L, -2, "fallback");
    lua_pushinteger(L, (lua_Integer)res.direct_rounds), lua_setfield(L, -2, "direct_rounds");
    lua_pushnumber(L, res.last.time), lua_setfield(L, -2, "time");
    lua_pushinteger(L, (lua_Integer)res.last.steps), lua_setfield(L, -2, "steps");
    lua_pushinteger(L, (lua_Integer)res.routings), lua_setfield(L, -2, "routings");
    lua_pushinteger(L, (lua_Integer)res.n_recorded), lua_setfield(L, -2, "recorded");
    lua_pushnumber(L, res.dt_min), lua_setfield(L, -2, "dt_min");
    lua_pushnumber(L, res.dt_max), lua_setfield(L, -2, "dt_max");
    lua_pushstring(L, res.note), lua_setfield(L, -2, "note");
    push_status(L, &res.last);
    return 1;
}

static int l_run(lua_State *L) { return landscape_run(L, 0); }
static int l_run_to_steady(lua_State *L) { return landscape_run(L, 1); }

/* ls:plot(path [, { title =, channels = true, reach = true }]) */
static int l_plot(lua_State *L)
{
    lua_ls *u = check_ls(L, 1);
    const char *path = dfle_lua_check_string(L, 2, "landscape:plot", "the path");
    static const char *const other[] = {"title", "channels", "reach", NULL};
    dfle_plot_map m;
    dfle_error err;
    int channels = 1, reach = dfle_landscape_model(u->ls) != NULL;
    char chlab[96];

    lua_settop(L, 3);
    dfle_lua_read_params(L, 3, "landscape:plot", NULL, 0, other);
    memset(&m, 0, sizeof m);
    if (lua_istable(L, 3)) {
        if (lua_getfield(L, 3, "title") != LUA_TNIL)
            m.title = dfle_lua_check_string(L, -1, "landscape:plot", "title");
        if (lua_getfield(L, 3, "channels") != LUA_TNIL)
            channels = lua_toboolean(L, -1);
        if (lua_getfield(L, 3, "reach") != LUA_TNIL)
            reach = lua_toboolean(L, -1) && dfle_landscape_model(u->ls) != NULL;
    }
    m.nx = dfle_landscape_nx(u->ls);
    m.ny = dfle_landscape_ny(u->ls);
    m.x0 = u->x0, m.y0 = u->y0;
    m.dx = dfle_landscape_dx(u->ls), m.dy = dfle_landscape_dy(u->ls);
    m.crs = u->crs; /* named in the axis labels */
    m.z = get_field(L, DFLE_LS_Z, "dfle.landscape:plot");
    if (channels)
        m.channel = get_field(L, DFLE_LS_CHANNEL, "dfle.landscape:plot");
    if (reach)
        m.reach = get_field(L, DFLE_LS_REACH, "dfle.landscape:plot");
    snprintf(chlab, sizeof chlab, reach ? "Channels beyond the debris-flow reach (A ≥ A_0)"
                                        : "Channel network (A ≥ A_0)");
    m.channel_label = chlab;
    if (dfle_plot_hillshade(path, &m, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    lua_settop(L, 1);
    return 1;
}

/* ls:slope_area() -> {A, S} of the channel cells (slope to the receiver). */
static int l_slope_area(lua_State *L)
{
    lua_ls *u = check_ls(L, 1);
    const size_t n = dfle_landscape_nx(u->ls) * dfle_landscape_ny(u->ls);
    const double *A = get_field(L, DFLE_LS_A, "dfle.landscape:slope_area");
    const double *S = get_field(L, DFLE_LS_S, "dfle.landscape:slope_area");
    const double *ch = get_field(L, DFLE_LS_CHANNEL, "dfle.landscape:slope_area");
    const double *bl = get_field(L, DFLE_LS_BASE, "dfle.landscape:slope_area");
    lua_Integer k = 0;
    lua_createtable(L, 0, 2);
    lua_newtable(L);
    lua_newtable(L);
    for (size_t c = 0; c < n; c++)
        if (ch[c] > 0 && bl[c] == 0 && S[c] > 0) {
            k++;
            lua_pushnumber(L, A[c]), lua_rawseti(L, -3, k);
            lua_pushnumber(L, S[c]), lua_rawseti(L, -2, k);
        }
    lua_setfield(L, -3, "S");
    lua_setfield(L, -2, "A");
    return 1;
}

/* ls:dem() -> a dfle.dem of the current surface (georeferenced). */
static int l_dem(lua_State *L)
{
    lua_ls *u = check_ls(L, 1);
    dfle_dem_geo g = {u->x0, u->y0, dfle_landscape_dx(u->ls), dfle_landscape_dy(u->ls)};
    dfle_lua_object *d = dfle_lua_newobject(L, sizeof(dfle_lua_object), "dfle.dem", 0);
    dfle_dem *dem;
    dfle_error err;
    if (dfle_dem_new(dfle_landscape_nx(u->ls), dfle_landscape_ny(u->ls), dfle_landscape_z(u->ls),
                     &g, &dem, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    d->ptr = dem;
    if (u->crs != NULL && dfle_dem_set_crs(dem, u->crs, &err) != DFLE_OK) /* the same place */
        return dfle_lua_raise(L, &err);
    return 1;
}

static int l_property(lua_State *L)
{
    lua_ls *u = check_ls(L, 1);
    const char *key = lua_tostring(L, 2);
    dfle_landscape *ls = u->ls;
    if (strcmp(key, "nx") == 0)
        lua_pushinteger(L, (lua_Integer)dfle_landscape_nx(ls));
    else if (strcmp(key, "ny") == 0)
        lua_pushinteger(L, (lua_Integer)dfle_landscape_ny(ls));
    else if (strcmp(key, "n") == 0)
        lua_pushinteger(L, (lua_Integer)(dfle_landscape_nx(ls) * dfle_landscape_ny(ls)));
    else if (strcmp(key, "dx") == 0)
        lua_pushnumber(L, dfle_landscape_dx(ls));
    else if (strcmp(key, "dy") == 0)
        lua_pushnumber(L, dfle_landscape_dy(ls));
    else if (strcmp(key, "time") == 0)
        lua_pushnumber(L, dfle_landscape_time(ls));
    else if (strcmp(key, "data_cells") == 0)
        lua_pushinteger(L, (lua_Integer)dfle_landscape_data_cells(ls));
    else if (strcmp(key, "memory") == 0)
        lua_pushinteger(L, (lua_Integer)dfle_landscape_memory(ls));
    else if (strcmp(key, "has_run") == 0)
        lua_pushboolean(L, dfle_landscape_has_run(ls));
    else if (strcmp(key, "x0") == 0)
        lua_pushnumber(L, u->x0);
    else if (strcmp(key, "y0") == 0)
        lua_pushnumber(L, u->y0);
    else if (strcmp(key, "fluvial") == 0)
        lua_getiuservalue(L, 1, UV_FLUVIAL);
    else if (strcmp(key, "router") == 0)
        lua_getiuservalue(L, 1, UV_ROUTER);
    else if (strcmp(key, "law") == 0)
        lua_getiuservalue(L, 1, UV_LAW);
    else
        lua_pushnil(L);
    return 1;
}

static void describe(lua_State *L, void *obj)
{
    dfle_landscape *ls = obj;
    char buf[200];
    snprintf(buf, sizeof buf, "dfle.landscape(%zu x %zu cells of %g x %g m, %zu with data, t = %g "
             "yr, debris flows %s)", dfle_landscape_nx(ls), dfle_landscape_ny(ls),
             dfle_landscape_dx(ls), dfle_landscape_dy(ls), dfle_landscape_data_cells(ls),
             dfle_landscape_time(ls), dfle_landscape_model(ls) != NULL ? "on" : "off");
    lua_pushstring(L, buf);
}

static void ls_free(void *obj) { dfle_landscape_free(obj); }

static void release(lua_State *L, int idx)
{
    lua_ls *u = lua_touserdata(L, idx);
    for (int k = UV_FLUVIAL; k <= UV_LAW; k++) {
        if (lua_getiuservalue(L, idx, k) == LUA_TUSERDATA)
            dfle_lua_unhold(L, lua_gettop(L));
        lua_pop(L, 1);
    }
    luaL_unref(L, LUA_REGISTRYINDEX, u->ref_combine);
    for (int k = 0; k < F_COUNT; k++)
        luaL_unref(L, LUA_REGISTRYINDEX, u->cb[k].ref);
    u->ref_combine = LUA_NOREF;
    for (int k = 0; k < F_COUNT; k++)
        u->cb[k].ref = LUA_NOREF;
    u->crs = NULL;
}

int dfle_lua_ls_field_id(lua_State *L, int idx, const char *fn) { return field_id(L, idx, fn); }

double *dfle_lua_ls_get_field(lua_State *L, int field, const char *what)
{
    return get_field(L, field, what);
}

void dfle_lua_open_landscape(lua_State *L)
{
    static const luaL_Reg methods[] = {
        {"run", l_run}, {"run_to_steady", l_run_to_steady}, {"step", l_step},
        {"get", l_get}, {"fields", l_fields}, {"set_z", dfle_lua_ls_set_z},
        {"write_geotiff", dfle_lua_ls_write_geotiff}, {"plot", l_plot}, {"slope_area", l_slope_area},
        {"dem", l_dem}, {"run_events", dfle_lua_ls_run_events}, {NULL, NULL}};
    static const dfle_lua_type type = {
        .name = DFLE_LUA_LANDSCAPE, .free = ls_free, .describe = describe, .methods = methods,
        .property = l_property, .closable = 1, .release = release,
    };
    dfle_lua_register(L, &type);
    lua_pushcfunction(L, dfle_lua_landscape_new);
    lua_setfield(L, -2, "landscape");
}
