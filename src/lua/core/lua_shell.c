/*
 * lua_shell.c - the scaffold of the Lua-defined component types
 * (lua_shell.h): building a shell object and its thread, and the one
 * protected call through which every op reaches the user's functions.
 */
#include "lua/core/lua_shell.h"

#include <stdio.h>
#include <string.h>

/* Message handler of the shells' calls: the message and a traceback. */
static int traceback(lua_State *T)
{
    const char *msg = lua_tostring(T, 1);
    if (msg == NULL)
        msg = lua_pushfstring(T, "(error object is a %s value)", luaL_typename(T, 1));
    luaL_traceback(T, T, msg, 1);
    return 1;
}

void *dfle_lua_shell_new(lua_State *L, const dfle_lua_shell_def *def)
{
    const char *name = "lua";
    dfle_lua_shell *sh;
    lua_State *T;
    int t;

    luaL_checktype(L, 1, LUA_TTABLE);
    lua_settop(L, 1);
    lua_pushfstring(L, "%s.define", def->kind);
    dfle_lua_read_params(L, 1, lua_tostring(L, -1), NULL, 0, def->keys);
    lua_pop(L, 1);
    if ((t = lua_getfield(L, 1, "name")) != LUA_TNIL) {
        if (t != LUA_TSTRING)
            luaL_error(L, "dfle.%s.define: 'name' must be a string, got %s", def->kind,
                       dfle_lua_typename(L, -1));
        lua_pushfstring(L, "%s.define", def->kind);
        name = dfle_lua_check_string(L, -2, lua_tostring(L, -1), "name"); /* the table keeps it */
        lua_pop(L, 1);
    }
    lua_pop(L, 1);

    /* The object first (valid and empty), then the thread as its user
     * value: nothing can leak if a check below raises. */
    dfle_lua_newobject(L, def->object_size, def->tname, 2); /* index 2 */
    T = lua_newthread(L);
    lua_setiuservalue(L, 2, 1);
    if (!lua_checkstack(T, def->stack + 8))
        luaL_error(L, "dfle.%s.define: out of memory", def->kind);
    /* params: the component's own shallow copy, so later edits of the
     * script's table cannot change a component a model already runs. */
    lua_newtable(L);
    if ((t = lua_getfield(L, 1, "params")) != LUA_TNIL) {
        if (t != LUA_TTABLE)
            luaL_error(L, "dfle.%s.define: 'params' must be a table, got %s", def->kind,
                       dfle_lua_typename(L, -1));
        dfle_lua_copy_table(L, -1, -2);
    }
    lua_pop(L, 1);
    lua_pushvalue(L, -1);
    lua_setiuservalue(L, 2, 2);              /* for x.<param> and x:params() */
    lua_xmove(L, T, 1);                      /* DFLE_SHELL_PARAMS */
    lua_pushcfunction(T, traceback);         /* DFLE_SHELL_MSGH */
    sh = lua_newuserdatauv(T, def->state_size, 0); /* DFLE_SHELL_STATE */
    memset(sh, 0, def->state_size);
    sh->T = T;
    snprintf(sh->name, sizeof sh->name, "%s", name);
    snprintf(sh->who, sizeof sh->who, "%s.%s", def->kind, sh->name);
    return sh;
}

int dfle_lua_shell_enter(dfle_lua_shell *sh, const char *functions, dfle_error *err)
{
    if (sh->running)
        return dfle_error_set(err, DFLE_ECALLBACK, "%s: used again from inside its own %s "
                              "(directly, or through a model or routing they started)",
                              sh->who, functions);
    sh->running = 1;
    return DFLE_OK;
}

void dfle_lua_shell_leave(dfle_lua_shell *sh) { sh->running = 0; }

void dfle_lua_shell_close(lua_State *T, lua_CFunction sweep)
{
    const int n = lua_gettop(T);
    for (int k = 1; k <= n; k++)
        lua_pushvalue(T, k);
    lua_pushcclosure(T, sweep, n);
}

int dfle_lua_shell_call(const dfle_lua_shell *sh, int top, int nargs, int nres,
                        const char *fallback, dfle_error *err)
{
    lua_State *T = sh->T;
    int st = lua_pcall(T, nargs, nres, DFLE_SHELL_MSGH);
    dfle_lua_touch(T);
    if (st != LUA_OK) {
        const char *msg = lua_tostring(T, -1);
        dfle_error_set(err, DFLE_ECALLBACK, "%s: %s", sh->who, msg != NULL ? msg : fallback);
        lua_settop(T, top);
        return DFLE_ECALLBACK;
    }
    return DFLE_OK;
}

int dfle_lua_shell_sweep(const dfle_lua_shell *sh, int top, int sweep, const char *fallback,
                         dfle_error *err)
{
    lua_State *T = sh->T;
    int st;
    lua_settop(T, top);
    lua_pushvalue(T, sweep);
    lua_pushlightuserdata(T, (void *)sh);
    st = dfle_lua_shell_call(sh, top, 1, 0, fallback, err);
    lua_settop(T, top);
    return st;
}
