/*
 * lua_router.c - dfle.router.empirical{...}: debris-flow routers.
 *
 * A router object from Lua is just the C router handle; the model takes
 * it through the ops table, whatever its kind.  rt:params() returns the
 * parameters so scripts can record what they ran.
 */
#include "dfle_lua.h"

#include <stdio.h>
#include <string.h>

#include "dfle/router_empirical.h"

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

static void push_empirical_params(lua_State *L, const dfle_empirical_opts *o)
{
    lua_createtable(L, 0, 8);
    lua_pushnumber(L, o->M0), lua_setfield(L, -2, "M0");
    lua_pushnumber(L, o->gamma), lua_setfield(L, -2, "gamma");
    lua_pushnumber(L, o->mu), lua_setfield(L, -2, "mu");
    lua_pushnumber(L, o->tau_y), lua_setfield(L, -2, "tau_y");
    lua_pushnumber(L, o->c1), lua_setfield(L, -2, "c1");
    lua_pushnumber(L, o->c2), lua_setfield(L, -2, "c2");
    lua_pushnumber(L, o->rho_b), lua_setfield(L, -2, "rho_b");
    lua_pushnumber(L, o->g), lua_setfield(L, -2, "g");
}

static int l_router_params(lua_State *L)
{
    dfle_router *rt = dfle_lua_check_router(L, 1);
    const dfle_empirical_opts *o = dfle_router_empirical_opts(rt);
    if (o != NULL)
        push_empirical_params(L, o);
    else
        lua_newtable(L);
    return 1;
}

static int l_router_property(lua_State *L)
{
    dfle_router *rt = dfle_lua_check_router(L, 1);
    const char *key = lua_tostring(L, 2);
    const dfle_empirical_opts *o = dfle_router_empirical_opts(rt);

    if (strcmp(key, "name") == 0) {
        lua_pushstring(L, dfle_router_name(rt));
        return 1;
    }
    if (o != NULL) {
        push_empirical_params(L, o);
        lua_getfield(L, -1, key);
        return 1;
    }
    lua_pushnil(L);
    return 1;
}

static int l_router_tostring(lua_State *L)
{
    dfle_router *rt = dfle_lua_check_router(L, 1);
    const dfle_empirical_opts *o = dfle_router_empirical_opts(rt);
    char buf[200];
    if (o != NULL)
        snprintf(buf, sizeof buf,
                 "dfle.router.empirical(M0 = %g, gamma = %g, mu = %g Pa s, tau_y = %g Pa)",
                 o->M0, o->gamma, o->mu, o->tau_y);
    else
        snprintf(buf, sizeof buf, "dfle.router.%s", dfle_router_name(rt));
    lua_pushstring(L, buf);
    return 1;
}

static int l_router_gc(lua_State *L)
{
    dfle_lua_router *u = luaL_checkudata(L, 1, DFLE_LUA_ROUTER);
    dfle_router_free(u->rt);
    u->rt = NULL;
    return 0;
}

void dfle_lua_open_router(lua_State *L)
{
    static const luaL_Reg methods[] = {{"params", l_router_params}, {NULL, NULL}};
    static const luaL_Reg meta[] = {
        {"__gc", l_router_gc},
        {"__tostring", l_router_tostring}, {NULL, NULL}};
    dfle_lua_register_type(L, DFLE_LUA_ROUTER, methods, meta, l_router_property);
    lua_newtable(L);
    lua_pushcfunction(L, l_router_empirical);
    lua_setfield(L, -2, "empirical");
    lua_setfield(L, -2, "router");
}
