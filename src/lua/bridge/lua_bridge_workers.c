/*
 * lua_bridge_workers.c - worker states for a host's parallel calls
 * (lua_bridge.h: dfle_bridge_begin_parallel).
 *
 * The dfle command's workers replay the script up to the call they
 * serve.  A host has no script: its program is in another language and
 * may have made any number of calls before.  So the host writes the one
 * call as Lua source (the spec, with the build or measure given as Lua
 * source), and each worker runs that, its call counts set to the main
 * state's so that the replay stops at this very call.  The kinds then
 * check, as for the command, that the worker built the same run.
 */
#include <stdlib.h>
#include <string.h>

#include <lauxlib.h>
#include <lualib.h>

#include "dfle/lua.h"

#include "lua/bridge/lua_bridge_internal.h"

/* Worker states' warnings are the main state's again: only its own are
 * passed on (as the dfle command does). */
static void drop_warning(void *ud, const char *msg, int tocont)
{
    (void)ud;
    (void)msg;
    (void)tocont;
}

static int open_worker_p(lua_State *L)
{
    const dfle_bridge *b = lua_touserdata(L, 1);
    luaL_openlibs(L);
    luaL_requiref(L, "dfle", luaopen_dfle, 1);
    lua_pop(L, 1);
    for (int k = 0; k < DFLE_LUA_PAR_KINDS; k++)
        dfle_lua_par_set_calls(L, k, b->calls[k]);
    if (luaL_loadbufferx(L, b->worker_script, b->worker_len, "=parallel call", "t") != LUA_OK)
        return lua_error(L);
    return 1;
}

static lua_State *open_worker(void *ud, int *nargs, dfle_error *err)
{
    lua_State *L = luaL_newstate();
    if (L == NULL) {
        dfle_error_set(err, DFLE_ENOMEM, "cannot create a worker's Lua state: not enough memory");
        return NULL;
    }
    lua_setwarnf(L, drop_warning, NULL);
    lua_pushcfunction(L, open_worker_p);
    lua_pushlightuserdata(L, ud);
    if (lua_pcall(L, 1, 1, 0) != LUA_OK) {
        dfle_error_set(err, DFLE_ECALLBACK, "%s",
                       lua_tostring(L, -1) ? lua_tostring(L, -1) : "worker failed");
        lua_close(L);
        return NULL;
    }
    *nargs = 0; /* the chunk alone */
    return L;
}

int dfle_bridge_begin_parallel(dfle_bridge *b, const char *script, size_t len)
{
    char *copy = malloc(len + 1);
    if (copy == NULL)
        return -1;
    memcpy(copy, script, len);
    copy[len] = '\0';
    free(b->worker_script);
    b->worker_script = copy;
    b->worker_len = len;
    for (int k = 0; k < DFLE_LUA_PAR_KINDS; k++)
        b->calls[k] = dfle_lua_par_calls(b->main, k);
    memset(&b->host, 0, sizeof b->host);
    b->host.open_state = open_worker;
    b->host.ud = b;
    dfle_lua_set_host(b->main, &b->host);
    return 0;
}

void dfle_bridge_end_parallel(dfle_bridge *b)
{
    dfle_lua_set_host(b->main, NULL);
    free(b->worker_script);
    b->worker_script = NULL;
    b->worker_len = 0;
}
