/*
 * lua_channel.c - dfle.channel{...}: the channel grid from Lua.
 *
 *   local ch = dfle.channel{ dx = 5, A_max = 8e6 }
 *   ch.n, ch.dx, ch.length, ch:get("A")
 */
#include "dfle_lua.h"

#include <string.h>

static int l_channel_new(lua_State *L)
{
    dfle_channel_opts o;
    dfle_lua_channel *u;
    dfle_error err;
    const dfle_lua_param params[] = {
        {"dx", &o.dx},         {"A0", &o.A0},   {"hack_coef", &o.hack_coef},
        {"hack_exp", &o.hack_exp}, {"k_w", &o.k_w}, {"b", &o.b},
        {"A_max", &o.A_max},   {"length", &o.length},
    };

    dfle_channel_opts_default(&o);
    dfle_lua_read_params(L, 1, "channel", params, sizeof params / sizeof params[0], NULL);
    u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_CHANNEL, 0);
    if (dfle_channel_new(&o, &u->ch, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

static const char *const channel_arrays[] = {"x", "A", "w", NULL};

static int l_channel_get(lua_State *L)
{
    dfle_channel *ch = dfle_lua_check_channel(L, 1);
    int which = luaL_checkoption(L, 2, NULL, channel_arrays);
    const double *v = which == 0   ? dfle_channel_x(ch)
                      : which == 1 ? dfle_channel_A(ch)
                                   : dfle_channel_w(ch);
    dfle_lua_push_array(L, v, dfle_channel_size(ch));
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
        lua_pushnil(L);
    return 1;
}

static int l_channel_len(lua_State *L)
{
    lua_pushinteger(L, (lua_Integer)dfle_channel_size(dfle_lua_check_channel(L, 1)));
    return 1;
}

static int l_channel_tostring(lua_State *L)
{
    dfle_channel *ch = dfle_lua_check_channel(L, 1);
    size_t n = dfle_channel_size(ch);
    lua_pushfstring(L, "dfle.channel(n = %d, dx = %f m, length = %f m, A = %f..%f m^2)",
                    (int)n, dfle_channel_dx(ch), dfle_channel_x(ch)[n - 1],
                    dfle_channel_A(ch)[0], dfle_channel_A(ch)[n - 1]);
    return 1;
}

static int l_channel_gc(lua_State *L)
{
    dfle_lua_channel *u = luaL_checkudata(L, 1, DFLE_LUA_CHANNEL);
    dfle_channel_free(u->ch);
    u->ch = NULL;
    return 0;
}

void dfle_lua_open_channel(lua_State *L)
{
    static const luaL_Reg methods[] = {{"get", l_channel_get}, {NULL, NULL}};
    static const luaL_Reg meta[] = {
        {"__gc", l_channel_gc},
        {"__len", l_channel_len}, {"__tostring", l_channel_tostring},
        {NULL, NULL},
    };
    dfle_lua_register_type(L, DFLE_LUA_CHANNEL, methods, meta, l_channel_property);
    lua_pushcfunction(L, l_channel_new);
    lua_setfield(L, -2, "channel");
}
