/*
 * lua_replay.c - where a worker state's replay of the script stops: the
 * host a state was given, the registry keys of a worker's mode and of
 * the table it hands over, the count of parallel calls of each kind,
 * and the replay itself (lua_drive_internal.h).
 *
 * A Lua function with its upvalues cannot be copied between states in
 * general (string.dump loses upvalues, C functions and userdata), so a
 * worker does what redis and wrk do: it runs the same script, which
 * builds the same functions, and stops at the same call.
 */
#include <pthread.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "lua/drive/lua_parallel.h"

static const char host_key = 'h';
static const char worker_key = 'w';
static const char spec_key = 's';
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
    lua_rawgetp(L, LUA_REGISTRYINDEX, &worker_key);
    wm = lua_touserdata(L, -1);
    lua_rawgetp(L, LUA_REGISTRYINDEX, &depth_key);
    *depth = lua_tointeger(L, -1);
    lua_pop(L, 2);
    return wm;
}

int dfle_lua_is_worker(lua_State *L)
{
    lua_Integer depth;
    return par_state(L, &depth) != NULL;
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
            lua_rawsetp(L, LUA_REGISTRYINDEX, &spec_key);
        }
        lua_pushlightuserdata(L, (void *)&stop_key);
        lua_error(L);
    }
    return DFLE_LUA_PAR_EARLIER;
}

lua_Integer dfle_lua_par_calls(lua_State *L, int kind)
{
    lua_Integer n;
    lua_rawgetp(L, LUA_REGISTRYINDEX, &calls_key[kind]);
    n = lua_tointeger(L, -1);
    lua_pop(L, 1);
    return n;
}

void dfle_lua_par_set_calls(lua_State *L, int kind, lua_Integer n)
{
    lua_pushinteger(L, n);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &calls_key[kind]);
}

void dfle_lua_set_host(lua_State *L, const dfle_lua_host *h)
{
    dfle_lua_set_pointer(L, &host_key, h);
}

const dfle_lua_host *dfle_lua_host_of(lua_State *L) { return dfle_lua_get_pointer(L, &host_key); }

int dfle_lua_par_workers(const dfle_lua_host *host, int table_workers, int cores)
{
    if (host != NULL && host->workers > 0)
        return host->workers;
    if (table_workers > 0)
        return table_workers;
    if (cores > 0)
        return cores;
    return dfle_lua_cores();
}

double dfle_lua_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ------------------------------------------------------------------ */
/* The replay.                                                         */

static pthread_mutex_t open_lock = PTHREAD_MUTEX_INITIALIZER;

lua_State *dfle_lua_par_open(const dfle_lua_host *host, int *nargs, dfle_error *err)
{
    lua_State *L;
    if (host == NULL || host->open_state == NULL) {
        dfle_error_set(err, DFLE_ESTATE, "worker: no host to make a worker's Lua state");
        return NULL;
    }
    pthread_mutex_lock(&open_lock);
    L = host->open_state(host->ud, nargs, err);
    pthread_mutex_unlock(&open_lock);
    return L;
}

/* replay_main(kind, chunk, args...): runs protected in the worker's
 * state; leaves the call's table. */
static int replay_main(lua_State *L)
{
    int kind = (int)lua_tointeger(L, 1);
    int nargs = lua_gettop(L) - 2, st;

    st = lua_pcall(L, nargs, 0, 0);
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &spec_key) != LUA_TTABLE) {
        if (st != LUA_OK)
            return luaL_error(L, "worker: the script failed before reaching %s: %s",
                              dfle_lua_par_name(kind),
                              lua_tostring(L, -2) ? lua_tostring(L, -2) : "(no message)");
        return luaL_error(L, "worker: the script ended without reaching the same %s call (the "
                             "script must do the same thing on every run up to it)",
                          dfle_lua_par_name(kind));
    }
    lua_pushnil(L);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &spec_key);
    return 1;
}

int dfle_lua_par_replay(lua_State *L, int nargs, worker_mode *wm, const dfle_lua_host *host,
                        dfle_error *err)
{
    wm->serving = 0;
    dfle_lua_set_host(L, host);
    lua_pushlightuserdata(L, wm);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &worker_key);
    /* stack: chunk, args -> replay_main, kind, chunk, args */
    lua_pushcfunction(L, replay_main);
    lua_insert(L, 1);
    lua_pushinteger(L, wm->kind);
    lua_insert(L, 2);
    if (lua_pcall(L, nargs + 2, 1, 0) != LUA_OK) {
        const char *m = lua_tostring(L, -1);
        dfle_error_set(err, DFLE_ECALLBACK, "%s", m != NULL ? m : "worker failed");
        lua_settop(L, 0);
        lua_pushnil(L);
        lua_rawsetp(L, LUA_REGISTRYINDEX, &worker_key);
        return DFLE_ECALLBACK;
    }
    wm->serving = 1;
    return DFLE_OK;
}
