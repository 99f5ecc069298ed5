/*
 * lua_state.c - what the binding keeps per lua_State, in the registry:
 * the module table, the Lua epoch, the progress hooks, and the way other
 * files keep a C pointer there (the ensemble's host).
 *
 * It sits below every binding file: luaopen_dfle (lua_module.c) records
 * the module here, and the files it opens read it back from here, so no
 * binding file has to call into the file that opened it.
 */
#include "lua/core/dfle_lua.h"

#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <unistd.h>

/* Registry keys: their addresses are the keys. */
static const char module_key = 'm';
static const char progress_key = 'p';
static const char interrupt_key = 'i';
static const char interrupt_note_key = 'n';
static const char epoch_key = 'e';

void dfle_lua_set_module(lua_State *L, int idx)
{
    lua_pushvalue(L, idx);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &module_key);
}

void dfle_lua_push_module(lua_State *L)
{
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &module_key) != LUA_TTABLE)
        luaL_error(L, "dfle: module table missing (was luaopen_dfle called?)");
}

void dfle_lua_set_pointer(lua_State *L, const void *key, const void *p)
{
    if (p != NULL)
        lua_pushlightuserdata(L, (void *)p);
    else
        lua_pushnil(L);
    lua_rawsetp(L, LUA_REGISTRYINDEX, key);
}

void *dfle_lua_get_pointer(lua_State *L, const void *key)
{
    void *p;
    lua_rawgetp(L, LUA_REGISTRYINDEX, key);
    p = lua_touserdata(L, -1);
    lua_pop(L, 1);
    return p;
}

void dfle_lua_set_progress(lua_State *L, const dfle_lua_progress *p)
{
    dfle_lua_set_pointer(L, &progress_key, p);
}

const dfle_lua_progress *dfle_lua_get_progress(lua_State *L)
{
    return dfle_lua_get_pointer(L, &progress_key);
}

void dfle_lua_note(lua_State *L, int level, const char *fmt, ...)
{
    const dfle_lua_progress *p = dfle_lua_get_progress(L);
    char line[512];
    va_list ap;
    if (p == NULL || p->note == NULL)
        return;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    p->note(p->ud, level, line);
}

unsigned long *dfle_lua_epoch(lua_State *L)
{
    unsigned long *e;
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &epoch_key) == LUA_TUSERDATA) {
        e = lua_touserdata(L, -1);
        lua_pop(L, 1);
        return e;
    }
    lua_pop(L, 1);
    e = lua_newuserdatauv(L, sizeof *e, 0);
    *e = 1;
    lua_rawsetp(L, LUA_REGISTRYINDEX, &epoch_key);
    return e;
}

void dfle_lua_touch(lua_State *L) { ++*dfle_lua_epoch(L); }

int dfle_lua_cores(void)
{
    long c = sysconf(_SC_NPROCESSORS_ONLN);
    return c > 0 ? (int)c : 1;
}

void dfle_lua_set_interrupt(lua_State *L, const volatile sig_atomic_t *flag)
{
    dfle_lua_set_pointer(L, &interrupt_key, (const void *)flag);
}

const volatile sig_atomic_t *dfle_lua_get_interrupt(lua_State *L)
{
    return dfle_lua_get_pointer(L, &interrupt_key);
}

int dfle_lua_interrupted(lua_State *L)
{
    const volatile sig_atomic_t *f = dfle_lua_get_interrupt(L);
    return f != NULL ? (int)*f : 0;
}

void dfle_lua_check_interrupt(lua_State *L, const char *what)
{
    int sig = dfle_lua_interrupted(L);
    if (sig != 0)
        luaL_error(L, "dfle.%s: interrupted (%s): not started", what,
                   sig == SIGTERM ? "SIGTERM" : "SIGINT");
}

void dfle_lua_set_interrupt_note(lua_State *L, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    lua_pushvfstring(L, fmt, ap);
    va_end(ap);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &interrupt_note_key);
}

const char *dfle_lua_interrupt_note(lua_State *L)
{
    const char *s;
    lua_rawgetp(L, LUA_REGISTRYINDEX, &interrupt_note_key);
    s = lua_tostring(L, -1); /* the registry keeps it */
    lua_pop(L, 1);
    return s;
}
