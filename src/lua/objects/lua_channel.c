/*
 * lua_channel.c - dfle.channel{...}: the channel grid from Lua.
 *
 *   local ch = dfle.channel{ dx = 5, A_max = 8e6 }
 *   ch.n, ch.dx, ch.length, ch:get("A")
 */
#include "lua/core/dfle_lua.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Most nodes a user's area(x) is followed for while looking for A_max:
 * a function that never gets there must end in an error, not a hang. */
#define AREA_SEARCH_MAX_NODES 1000000

/* Call the user's function at the top of the stack-independent index
 * `fidx` with argument v; return its number or raise naming `what`. */
static double call_number(lua_State *L, int fidx, double v, const char *what, const char *arg_name)
{
    double r;
    lua_pushvalue(L, fidx);
    lua_pushnumber(L, v);
    lua_call(L, 1, 1);
    if (lua_type(L, -1) != LUA_TNUMBER)
        luaL_error(L, "dfle.channel: %s must return a number, got %s (at %s = %f)", what,
                   dfle_lua_typename(L, -1), arg_name, v);
    r = lua_tonumber(L, -1);
    lua_pop(L, 1);
    return r;
}

/* User geometry: `area` (function of x [m] or array of n values [m^2])
 * and/or `width` (function of A [m^2] or array [m]).  Both are
 * evaluated once, here, so the model's inner loops never call Lua. */
static int channel_from_lua(lua_State *L, const dfle_channel_opts *o, int area_t,
                            int width_t, dfle_lua_channel *u)
{
    const int area_idx = 2, width_idx = 3; /* pushed by the caller */
    double *A, *w;
    size_t n = 0;
    dfle_error err;

    if (area_t == LUA_TTABLE) {
        A = dfle_lua_check_array(L, area_idx, "channel: area", &n);
    } else if (area_t == LUA_TFUNCTION) {
        if (o->length > 0) {
            n = (size_t)ceil(o->length / o->dx - 1e-9) + 1;
        } else {
            /* The outlet is the first node whose area reaches A_max.  An
             * area that is not a finite positive number stops the search
             * at once: NaN or 0 never reaches A_max, and the search went
             * on for a million calls before saying so wrongly. */
            for (n = 1; n <= AREA_SEARCH_MAX_NODES; n++) {
                const double x = (double)(n - 1) * o->dx;
                const double a = call_number(L, area_idx, x, "area(x)", "x");
                if (!(isfinite(a) && a > 0))
                    luaL_error(L, "dfle.channel: A at node %d must be > 0 m^2 (got %s from "
                                  "area(x) at x = %f m)", (int)n, dfle_lua_number_text(L, a), x);
                if (a >= o->A_max)
                    break;
            }
            if (n > AREA_SEARCH_MAX_NODES)
                luaL_error(L, "dfle.channel: area(x) did not reach A_max = %f m^2 within %d "
                              "nodes; give length instead", o->A_max, AREA_SEARCH_MAX_NODES);
        }
        A = lua_newuserdatauv(L, n * sizeof *A, 0);
        for (size_t i = 0; i < n; i++)
            A[i] = call_number(L, area_idx, (double)i * o->dx, "area(x)", "x");
    } else {
        dfle_channel *hack;
        if (dfle_channel_new(o, &hack, &err) != DFLE_OK)
            return dfle_lua_raise(L, &err);
        n = dfle_channel_size(hack);
        A = lua_newuserdatauv(L, n * sizeof *A, 0);
        memcpy(A, dfle_channel_A(hack), n * sizeof *A);
        dfle_channel_free(hack);
    }
    if (width_t == LUA_TTABLE) {
        size_t nw;
        w = dfle_lua_check_array(L, width_idx, "channel: width", &nw);
        if (nw != n)
            luaL_error(L, "dfle.channel: width has %d values but the channel has %d nodes",
                       (int)nw, (int)n);
    } else {
        w = lua_newuserdatauv(L, (n ? n : 1) * sizeof *w, 0);
        for (size_t i = 0; i < n; i++)
            w[i] = width_t == LUA_TFUNCTION ? call_number(L, width_idx, A[i], "width(A)", "A")
                                            : o->k_w * pow(A[i], o->b);
    }
    if (dfle_channel_new_from_arrays(n, o->dx, A, w, &u->ch, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

static int l_channel_new(lua_State *L)
{
    static const char *const geometry_keys[] = {"area", "width", NULL};
    dfle_channel_opts o;
    dfle_lua_channel *u;
    dfle_error err;
    int area_t = LUA_TNIL, width_t = LUA_TNIL;
    const dfle_lua_param params[] = {
        {"dx", &o.dx},         {"A0", &o.A0},   {"hack_coef", &o.hack_coef},
        {"hack_exp", &o.hack_exp}, {"k_w", &o.k_w}, {"b", &o.b},
        {"A_max", &o.A_max},   {"length", &o.length},
    };

    dfle_channel_opts_default(&o);
    lua_settop(L, 1);
    dfle_lua_read_params(L, 1, "channel", params, sizeof params / sizeof params[0],
                         geometry_keys);
    if (lua_istable(L, 1)) {
        area_t = lua_getfield(L, 1, "area");
        width_t = lua_getfield(L, 1, "width");
    } else {
        lua_pushnil(L);
        lua_pushnil(L);
    }
    if ((area_t != LUA_TNIL && area_t != LUA_TFUNCTION && area_t != LUA_TTABLE) ||
        (width_t != LUA_TNIL && width_t != LUA_TFUNCTION && width_t != LUA_TTABLE))
        luaL_error(L, "dfle.channel: '%s' must be a function or an array of numbers, got %s",
                   area_t != LUA_TNIL && area_t != LUA_TFUNCTION && area_t != LUA_TTABLE
                       ? "area" : "width",
                   dfle_lua_typename(L, area_t != LUA_TNIL && area_t != LUA_TFUNCTION &&
                                            area_t != LUA_TTABLE ? 2 : 3));
    /* Parameters the user geometry replaces must not be given with it:
     * one of the two would be silently ignored. */
    if (area_t != LUA_TNIL) {
        static const char *const hack[] = {"A0", "hack_coef", "hack_exp", NULL};
        for (int k = 0; hack[k] != NULL; k++)
            if (lua_getfield(L, 1, hack[k]) != LUA_TNIL)
                luaL_error(L, "dfle.channel: give '%s' or 'area', not both", hack[k]);
            else
                lua_pop(L, 1);
        if (area_t == LUA_TTABLE && (lua_getfield(L, 1, "length") != LUA_TNIL ||
                                     lua_getfield(L, 1, "A_max") != LUA_TNIL))
            luaL_error(L, "dfle.channel: an 'area' array sets the nodes; drop length and A_max");
        lua_settop(L, 3);
    }
    if (width_t != LUA_TNIL) {
        if (lua_getfield(L, 1, "k_w") != LUA_TNIL || lua_getfield(L, 1, "b") != LUA_TNIL)
            luaL_error(L, "dfle.channel: give 'width' or k_w and b, not both");
        lua_settop(L, 3);
    }
    u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_CHANNEL, 0);
    if (area_t != LUA_TNIL || width_t != LUA_TNIL) {
        channel_from_lua(L, &o, area_t, width_t, u);
        lua_settop(L, 4);
        return 1;
    }
    if (dfle_channel_new(&o, &u->ch, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

static const char *const channel_arrays[] = {"x", "A", "w", NULL};

static int l_channel_get(lua_State *L)
{
    dfle_channel *ch = dfle_lua_check_channel(L, 1);
    int which = (dfle_lua_check_string(L, 2, "channel:get", "the array name"),
                 luaL_checkoption(L, 2, NULL, channel_arrays));
    const double *v = which == 0   ? dfle_channel_x(ch)
                      : which == 1 ? dfle_channel_A(ch)
                                   : dfle_channel_w(ch);
    dfle_lua_push_array(L, v, dfle_channel_size(ch));
    return 1;
}

static size_t channel_params(const void *ch, dfle_param *out, size_t cap)
{
    return dfle_channel_params(ch, out, cap);
}

/* ch:params(): the options it was built from (only dx for a channel
 * given area or width: its geometry is the arrays). */
static int l_channel_params(lua_State *L)
{
    dfle_lua_push_params(L, 1, channel_params, dfle_lua_check_channel(L, 1));
    return 1;
}

static int l_channel_property(lua_State *L)
{
    dfle_channel *ch = dfle_lua_check_channel(L, 1);
    const char *key = lua_tostring(L, 2);
    size_t n = dfle_channel_size(ch);

    if (strcmp(key, "n") == 0)
        lua_pushinteger(L, (lua_Integer)n);
    else if (strcmp(key, "dx") == 0)
        lua_pushnumber(L, dfle_channel_dx(ch));
    else if (strcmp(key, "length") == 0)
        lua_pushnumber(L, dfle_channel_x(ch)[n - 1]);
    else if (strcmp(key, "A_max") == 0)
        lua_pushnumber(L, dfle_channel_A(ch)[n - 1]);
    else
        return 0; /* not a field: __index says so */
    return 1;
}

static int l_channel_len(lua_State *L)
{
    lua_pushinteger(L, (lua_Integer)dfle_channel_size(dfle_lua_check_channel(L, 1)));
    return 1;
}

static void channel_describe(lua_State *L, void *obj)
{
    const dfle_channel *ch = obj;
    size_t n = dfle_channel_size(ch);
    char buf[160];
    snprintf(buf, sizeof buf, "dfle.channel(n = %zu, dx = %g m, length = %g m, A = %.4g..%.4g m^2)",
             n, dfle_channel_dx(ch), dfle_channel_x(ch)[n - 1], dfle_channel_A(ch)[0],
             dfle_channel_A(ch)[n - 1]);
    lua_pushstring(L, buf);
}

static void channel_free(void *obj) { dfle_channel_free(obj); }

void dfle_lua_open_channel(lua_State *L)
{
    static const luaL_Reg methods[] = {
        {"get", l_channel_get}, {"params", l_channel_params}, {NULL, NULL}};
    static const luaL_Reg meta[] = {{"__len", l_channel_len}, {NULL, NULL}};
    static const dfle_lua_type type = {
        .name = DFLE_LUA_CHANNEL, .free = channel_free, .describe = channel_describe,
        .methods = methods, .property = l_channel_property, .meta = meta,
        .fields = "n, dx, length, A_max",
    };
    dfle_lua_register(L, &type);
    lua_pushcfunction(L, l_channel_new);
    lua_setfield(L, -2, "channel");
}
