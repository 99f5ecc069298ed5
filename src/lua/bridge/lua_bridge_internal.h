/*
 * lua_bridge_internal.h - the bridge's state, shared by the files of
 * src/lua/bridge/ (not installed, not seen by hosts).
 */
#ifndef DFLE_LUA_BRIDGE_INTERNAL_H
#define DFLE_LUA_BRIDGE_INTERNAL_H

#include <stddef.h>

#include <lua.h>

#include "lua/bridge/lua_bridge.h"
#include "lua/drive/lua_parallel.h"

/* A callback's payload, the upvalue of its closure (a userdata of this
 * metatable, which the collector's walk looks for). */
#define DFLE_BRIDGE_HOST_FN "dfle.host_function"
typedef struct host_fn {
    dfle_bridge *b;
    dfle_bridge_fn fn;
    void *ud;
    void (*release)(void *ud);
} host_fn;

struct dfle_bridge {
    lua_State *main;
    lua_State *L; /* the frame being worked on: main, or a callback's */
    void (*warn)(void *ud, const char *msg);
    void *warn_ud;
    char *wbuf; /* a warning's pieces until its last one */
    size_t wlen, wcap;
    int wcont;
    int refs; /* registry key of the table of the host's references */
    /* Worker states of the parallel call running now (lua_bridge_workers.c). */
    dfle_lua_host host;
    char *worker_script;
    size_t worker_len;
    lua_Integer calls[DFLE_LUA_PAR_KINDS]; /* the main state's counts before it */
};

#endif
