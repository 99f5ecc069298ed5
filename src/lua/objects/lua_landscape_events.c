/*
 * lua_landscape_events.c - ls:run_events{years =, dt = 1, seed = 1,
 * hold = true}: a landscape's debris-flow population as events on its
 * surface as it is (landscape_events.h).  Returns the table of
 * m:run_events with one value per cell (NaN on NoData).
 */
#include "lua/core/dfle_lua.h"

#include "dfle/landscape_events.h"
#include "lua/objects/lua_events.h"
#include "lua/objects/lua_landscape.h"

int dfle_lua_ls_run_events(lua_State *L)
{
    static const char *const fn = "landscape:run_events";
    lua_ls *u;
    dfle_events_opts o;
    dfle_events_result res;
    dfle_error err;
    size_t n;
    double *sum;
    int st;

    dfle_lua_check_object(L, 1, DFLE_LUA_LANDSCAPE);
    u = lua_touserdata(L, 1);
    n = dfle_landscape_nx(u->ls) * dfle_landscape_ny(u->ls);
    dfle_lua_read_events_opts(L, 2, fn, 1, &o);
    sum = lua_newuserdatauv(L, 2 * n * sizeof *sum, 0);
    dfle_lua_begin_use(L, 1, "dfle.landscape:run_events");
    u->L = L;
    u->cb_err[0] = '\0';
    st = dfle_landscape_run_events(u->ls, &o, &res, sum, sum + n, &err);
    dfle_lua_end_use(L, 1);
    if (st != DFLE_OK)
        return dfle_lua_ls_raise(L, u, &err);
    dfle_lua_push_events_result(L, &res, sum, sum + n, n);
    return 1;
}
