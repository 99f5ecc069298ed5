/*
 * lua_dfle.c - luaopen_dfle: assembles the `dfle` module table.
 *
 * Each concern's binding file adds its own entries; this file only
 * creates the table, records the version and keeps a registry reference
 * so that bindings can reach the module without going through globals.
 */
#include "lua/core/dfle_lua.h"

#include "dfle/lua.h"

#include <gsl/gsl_errno.h>

#ifndef DFLE_VERSION
#define DFLE_VERSION "unknown"
#endif

static const char module_key = 'm';

void dfle_lua_push_module(lua_State *L)
{
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &module_key) != LUA_TTABLE)
        luaL_error(L, "dfle: module table missing (was luaopen_dfle called?)");
}

int luaopen_dfle(lua_State *L)
{
    luaL_checkversion(L);
    dfle_lua_touch(L); /* creates the epoch counter */
    /* A failure inside GSL (only allocation can fail in the fit) must come
     * back as an error status, not abort the host program. */
    gsl_set_error_handler_off();
    lua_newtable(L);
    lua_pushliteral(L, DFLE_VERSION);
    lua_setfield(L, -2, "version");
    dfle_lua_open_channel(L);
    dfle_lua_open_fluvial(L);
    dfle_lua_open_router(L);
    dfle_lua_open_law(L);
    dfle_lua_open_model(L);
    dfle_lua_open_analysis(L);
    dfle_lua_open_plot(L);
    dfle_lua_open_sampling(L);
    dfle_lua_open_dem(L);
    dfle_lua_open_ensemble(L);
    lua_pushvalue(L, -1);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &module_key);
    return 1;
}
