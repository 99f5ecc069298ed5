/*
 * lua_shell.h - what the Lua-defined component types share
 * (dfle.law.define, lua_law_define.c; dfle.router.define,
 * lua_router_define.c): a "shell" ops table whose state calls the
 * user's Lua functions.
 *
 * A shell's object (a dfle.law or dfle.router userdata) has two user
 * values: 1, a Lua thread of its own, created in the lua_State that
 * defined it, and 2, the component's own shallow copy of `params` (what
 * x:params() and x.<param> read).  The thread's stack holds everything
 * the calls need, in fixed slots: the params copy, the traceback
 * handler and the state (a userdata, so the collector owns it and
 * nothing leaks whatever raises), then the type's own slots, then a
 * sweep closure whose upvalues are all of those.  Each op is one
 * protected call of that closure; a Lua error becomes the op's
 * dfle_error.  Internal to the binding.
 */
#ifndef DFLE_LUA_SHELL_H
#define DFLE_LUA_SHELL_H

#include "lua/core/dfle_lua.h"

/* The slots every shell thread starts with. */
enum {
    DFLE_SHELL_PARAMS = 1, /* p: the component's copy of params       */
    DFLE_SHELL_MSGH,       /* message handler (appends a traceback)    */
    DFLE_SHELL_STATE,      /* the state userdata                       */
    DFLE_SHELL_SLOTS = DFLE_SHELL_STATE
};

/* The head of every shell's state. */
typedef struct dfle_lua_shell {
    lua_State *T; /* the component's own thread */
    char name[64];
    char who[80]; /* "<kind>.<name>": the prefix of its error messages */
    int running;  /* an op is in progress (dfle_lua_shell_enter) */
} dfle_lua_shell;

/* How dfle.<kind>.define builds its object. */
typedef struct dfle_lua_shell_def {
    const char *kind;         /* "law", "router"                            */
    const char *tname;        /* the object's metatable (DFLE_LUA_LAW, ...)  */
    size_t object_size;       /* its payload: the component's pointer      */
    size_t state_size;        /* the state, which begins with a dfle_lua_shell */
    const char *const *keys;  /* the keys a definition may have (NULL-ended) */
    int stack;                /* slots the thread will hold at most        */
} dfle_lua_shell_def;

/* dfle.<kind>.define with the definition table at index 1 of L: check
 * its keys, read `name` (default "lua"), push the object (payload
 * zeroed) at index 2 with its thread and params copy as user values,
 * and fill the thread's first DFLE_SHELL_SLOTS slots.  Returns the
 * state: zeroed but for its dfle_lua_shell head.  Raises on a bad
 * definition; nothing is leaked then. */
void *dfle_lua_shell_new(lua_State *L, const dfle_lua_shell_def *def);

/* Every op that touches the thread runs between these two.  An op
 * started while another runs (a law used by another model from inside
 * its own integrand, a router from inside its own flow()) would
 * rearrange the stack under the running call and overwrite the state it
 * is using (the channel, the flow arrays), so enter refuses it:
 * DFLE_ECALLBACK, "<who>: used again from inside its own <functions>".
 * Nothing may be touched before enter succeeds. */
int dfle_lua_shell_enter(dfle_lua_shell *sh, const char *functions, dfle_error *err);
void dfle_lua_shell_leave(dfle_lua_shell *sh);

/* Push the sweep closure over every slot of T so far (they become its
 * upvalues 1, 2, ...: lua_upvalueindex(slot) inside it). */
void dfle_lua_shell_close(lua_State *T, lua_CFunction sweep);

/* Call the function and nargs arguments pushed above `top` on the
 * shell's thread, protected by its message handler.  On success the
 * nres results are left above `top` for the caller (who then resets the
 * top).  A Lua error becomes DFLE_ECALLBACK with "<who>: message" (or
 * `fallback` if the error is not a string) and T's top returns to `top`.
 * Either way Lua code has run: the Lua epoch moves. */
int dfle_lua_shell_call(const dfle_lua_shell *sh, int top, int nargs, int nres,
                        const char *fallback, dfle_error *err);

/* One op: the sweep closure at slot `sweep`, called with the state as
 * its argument (dfle_lua_shell_call); T's top returns to `top`. */
int dfle_lua_shell_sweep(const dfle_lua_shell *sh, int top, int sweep, const char *fallback,
                         dfle_error *err);

#endif
