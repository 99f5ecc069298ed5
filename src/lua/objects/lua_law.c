/*
 * lua_law.c - erosion laws from Lua:
 *   dfle.law.power{k_df =, alpha =, beta =}         Eq. (6)
 *   dfle.law.inertial{k =, D =, rho_s =, alpha =}   Stock and Dietrich (2006)
 *   dfle.law.excess_stress{k =, tau_c =, p =}       k (tau - tau_c)^p
 *   dfle.law.define{...}                            written in Lua (lua_law_define.c)
 * doc/laws.md describes them all.
 */
#include "lua/core/dfle_lua.h"


#include "dfle/law_excess_stress.h"
#include "dfle/law_inertial.h"
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

static int l_law_inertial(lua_State *L)
{
    dfle_inertial_law_opts o;
    dfle_lua_law *u;
    dfle_error err;
    const dfle_lua_param params[] = {
        {"k", &o.k}, {"D", &o.D}, {"rho_s", &o.rho_s}, {"alpha", &o.alpha}};

    dfle_inertial_law_opts_default(&o);
    dfle_lua_read_params(L, 1, "law.inertial", params, 4, NULL);
    u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_LAW, 0);
    if (dfle_law_new_inertial(&o, &u->law, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

static int l_law_excess_stress(lua_State *L)
{
    dfle_excess_stress_law_opts o;
    dfle_lua_law *u;
    dfle_error err;
    const dfle_lua_param params[] = {{"k", &o.k}, {"tau_c", &o.tau_c}, {"p", &o.p}};

    dfle_excess_stress_law_opts_default(&o);
    dfle_lua_read_params(L, 1, "law.excess_stress", params, 3, NULL);
    u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_LAW, 0);
    if (dfle_law_new_excess_stress(&o, &u->law, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

/* The law's params op, as the binding's parameter helpers take it. */
static size_t law_params(const void *law, dfle_param *out, size_t cap)
{
    return dfle_law_params(law, out, cap);
}

static int l_law_params(lua_State *L)
{
    dfle_lua_push_params(L, 1, law_params, dfle_lua_check_law(L, 1));
    return 1;
}

/* law:compiled(): which functions of a dfle.law.define law run compiled
 * (lua_trace.h); nil for the built-in laws, which are C already. */
static int l_law_compiled(lua_State *L)
{
    dfle_law *law = dfle_lua_check_law(L, 1);
    if (!dfle_lua_law_compiled(L, law))
        lua_pushnil(L);
    return 1;
}

static int l_law_property(lua_State *L)
{
    dfle_law *law = dfle_lua_check_law(L, 1);
    return dfle_lua_push_param_field(L, dfle_law_name(law), law_params, law);
}

static void law_describe(lua_State *L, void *obj)
{
    dfle_lua_push_described(L, 1, "dfle.law", dfle_law_name(obj), law_params, obj);
}

static void law_free(void *obj) { dfle_law_free(obj); }

void dfle_lua_open_law(lua_State *L)
{
    static const luaL_Reg methods[] = {
        {"params", l_law_params}, {"compiled", l_law_compiled}, {NULL, NULL}};
    static const dfle_lua_type type = {
        .name = DFLE_LUA_LAW, .free = law_free, .describe = law_describe,
        .methods = methods, .property = l_law_property,
    };
    dfle_lua_register(L, &type);
    lua_newtable(L);
    lua_pushcfunction(L, l_law_power);
    lua_setfield(L, -2, "power");
    lua_pushcfunction(L, l_law_inertial);
    lua_setfield(L, -2, "inertial");
    lua_pushcfunction(L, l_law_excess_stress);
    lua_setfield(L, -2, "excess_stress");
    dfle_lua_open_law_define(L);
    lua_setfield(L, -2, "law");
}
