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
