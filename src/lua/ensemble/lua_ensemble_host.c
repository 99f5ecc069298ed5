/*
 * lua_ensemble_host.c - what the ensemble's entry points (lua_ensemble.c)
 * and its worker pool (lua_ensemble_pool.c) share below both: the host a
 * lua_State was given, the registry keys of a worker's mode and of the
 * ensemble table it hands over, the count of parallel calls that decides
 * where a worker's replay stops, and the clock progress is timed with.
 * Kept apart so that the pool, which the entry points call, never calls
 * back into them.
 */
#include <time.h>

#include "lua/ensemble/lua_ensemble_internal.h"

static const char host_key = 'h';
const char dfle_lua_ens_worker_key = 'w';
const char dfle_lua_ens_spec_key = 's';
static const char calls_key[DFLE_LUA_PAR_KINDS] = {'c', 'i'};
static const char depth_key = 'd';
static const char stop_key = 'x'; /* the error value that stops a worker's script */

const char *dfle_lua_par_name(int kind)
{
    return kind == DFLE_LUA_PAR_INVERT ? "dfle.invert" : "dfle.ensemble";
}

void dfle_lua_par_depth(lua_State *L, int delta)
{
    lua_Integer d;
    lua_rawgetp(L, LUA_REGISTRYINDEX, &depth_key);
    d = lua_tointeger(L, -1) + delta;
    lua_pop(L, 1);
    lua_pushinteger(L, d > 0 ? d : 0);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &depth_key);
}

/* The worker mode of state L (NULL: not a worker); *depth the parallel
 * calls in progress. */
static worker_mode *par_state(lua_State *L, lua_Integer *depth)
{
    worker_mode *wm;
    lua_rawgetp(L, LUA_REGISTRYINDEX, &dfle_lua_ens_worker_key);
    wm = lua_touserdata(L, -1);
    lua_rawgetp(L, LUA_REGISTRYINDEX, &depth_key);
    *depth = lua_tointeger(L, -1);
    lua_pop(L, 2);
    return wm;
}

int dfle_lua_par_inside(lua_State *L)
{
    lua_Integer depth;
    const worker_mode *wm = par_state(L, &depth);
    return (wm != NULL && wm->serving) || depth > 0;
}

int dfle_lua_par_enter(lua_State *L, int kind, int arg, lua_Integer *call)
{
    worker_mode *wm;
    lua_Integer depth;

    arg = lua_absindex(L, arg);
    wm = par_state(L, &depth);
    *call = 0;
    if ((wm != NULL && wm->serving) || depth > 0)
        return DFLE_LUA_PAR_NESTED;
    lua_rawgetp(L, LUA_REGISTRYINDEX, &calls_key[kind]);
    *call = lua_tointeger(L, -1) + 1;
    lua_pop(L, 1);
    lua_pushinteger(L, *call);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &calls_key[kind]);
    if (wm == NULL)
        return DFLE_LUA_PAR_RUN;
    if (wm->kind == kind && *call >= wm->target) {
        /* A worker replaying the script: hand the table over and stop. */
        if (*call == wm->target) {
            lua_pushvalue(L, arg);
            lua_rawsetp(L, LUA_REGISTRYINDEX, &dfle_lua_ens_spec_key);
        }
        lua_pushlightuserdata(L, (void *)&stop_key);
        lua_error(L);
    }
    return DFLE_LUA_PAR_EARLIER;
}

void dfle_lua_set_ensemble_host(lua_State *L, const dfle_lua_ensemble_host *h)
{
    dfle_lua_set_pointer(L, &host_key, h);
}

const dfle_lua_ensemble_host *dfle_lua_ens_host(lua_State *L)
{
    return dfle_lua_get_pointer(L, &host_key);
}

double dfle_lua_ens_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
