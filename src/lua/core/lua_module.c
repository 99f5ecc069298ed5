/*
 * lua_module.c - luaopen_dfle: assembles the `dfle` module table.
 *
 * The top of the binding: each concern's file adds its own entries, and
 * this file only creates the table, records the version and hands the
 * table to lua_state.c, where the binding files find it again without
 * going through globals (and without calling back up here).
 */
#include "lua/core/dfle_lua.h"

#include "dfle/lua.h"

#include <gsl/gsl_errno.h>

#ifndef DFLE_VERSION
#define DFLE_VERSION "unknown"
#endif

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
    dfle_lua_open_network(L);
    dfle_lua_open_analysis(L);
    dfle_lua_open_plot(L);
    dfle_lua_open_chi(L); /* after plot: adds dfle.plot.chi, ... */
    dfle_lua_open_sampling(L);
    dfle_lua_open_args(L);
    dfle_lua_open_write_csv(L);
    dfle_lua_open_dem(L);
    dfle_lua_open_landscape(L);
    dfle_lua_open_ensemble(L);
    dfle_lua_open_invert(L);
    dfle_lua_open_trace_hook(L);
    dfle_lua_set_module(L, -1);
    return 1;
}
