/*
 * lua_ensemble_host.c - what the ensemble's entry points (lua_ensemble.c)
 * and its worker pool (lua_ensemble_pool.c) share below both: the host a
 * lua_State was given, the registry keys of a worker's mode and of the
 * ensemble table it hands over, and the clock progress is timed with.
 * Kept apart so that the pool, which the entry points call, never calls
 * back into them.
 */
#include <time.h>

#include "lua/ensemble/lua_ensemble_internal.h"

static const char host_key = 'h';
const char dfle_lua_ens_worker_key = 'w';
const char dfle_lua_ens_spec_key = 's';

void dfle_lua_set_ensemble_host(lua_State *L, const dfle_lua_ensemble_host *h)
{
    if (h != NULL)
        lua_pushlightuserdata(L, (void *)h);
    else
        lua_pushnil(L);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &host_key);
}

const dfle_lua_ensemble_host *dfle_lua_ens_host(lua_State *L)
{
    const dfle_lua_ensemble_host *h;
    lua_rawgetp(L, LUA_REGISTRYINDEX, &host_key);
    h = lua_touserdata(L, -1);
    lua_pop(L, 1);
    return h;
}

double dfle_lua_ens_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
