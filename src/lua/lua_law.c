/*
 * lua_law.c - dfle.law.power{k_df =, alpha =, beta =}: erosion laws.
 */
#include "dfle_lua.h"

#include <stdio.h>
#include <string.h>

#include "dfle/law_power.h"

static int l_law_power(lua_State *L)
{
    dfle_power_law_opts o;
    dfle_lua_law *u;
    dfle_error err;
    const dfle_lua_param params[] = {
        {"k_df", &o.k_df}, {"alpha", &o.alpha}, {"beta", &o.beta}};

    dfle_power_law_opts_default(&o);
    dfle_lua_read_params(L, 1, "law.power", params, 3, NULL);
    u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_LAW, 0);
    if (dfle_law_new_power(&o, &u->law, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

static int l_law_params(lua_State *L)
{
    const dfle_power_law_opts *o = dfle_law_power_opts(dfle_lua_check_law(L, 1));
    lua_newtable(L);
    if (o != NULL) {
        lua_pushnumber(L, o->k_df), lua_setfield(L, -2, "k_df");
        lua_pushnumber(L, o->alpha), lua_setfield(L, -2, "alpha");
        lua_pushnumber(L, o->beta), lua_setfield(L, -2, "beta");
    }
    return 1;
}

static int l_law_property(lua_State *L)
{
    dfle_law *law = dfle_lua_check_law(L, 1);
    const char *key = lua_tostring(L, 2);
    if (strcmp(key, "name") == 0) {
        lua_pushstring(L, dfle_law_name(law));
        return 1;
    }
    lua_pushcfunction(L, l_law_params);
    lua_pushvalue(L, 1);
    lua_call(L, 1, 1);
    lua_getfield(L, -1, key);
    return 1;
}

static int l_law_tostring(lua_State *L)
{
    dfle_law *law = dfle_lua_check_law(L, 1);
    const dfle_power_law_opts *o = dfle_law_power_opts(law);
    char buf[160];
    if (o != NULL)
        snprintf(buf, sizeof buf, "dfle.law.power(k_df = %g, alpha = %g, beta = %g)", o->k_df,
                 o->alpha, o->beta);
    else
        snprintf(buf, sizeof buf, "dfle.law.%s", dfle_law_name(law));
    lua_pushstring(L, buf);
    return 1;
}

static int l_law_gc(lua_State *L)
{
    dfle_lua_law *u = luaL_checkudata(L, 1, DFLE_LUA_LAW);
    dfle_law_free(u->law);
    u->law = NULL;
    return 0;
}

void dfle_lua_open_law(lua_State *L)
{
    static const luaL_Reg methods[] = {{"params", l_law_params}, {NULL, NULL}};
    static const luaL_Reg meta[] = {
        {"__gc", l_law_gc}, {"__tostring", l_law_tostring},
        {NULL, NULL}};
    dfle_lua_register_type(L, DFLE_LUA_LAW, methods, meta, l_law_property);
    lua_newtable(L);
    lua_pushcfunction(L, l_law_power);
    lua_setfield(L, -2, "power");
    lua_setfield(L, -2, "law");
}
