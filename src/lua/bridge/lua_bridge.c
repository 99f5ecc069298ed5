/*
 * lua_bridge.c - the dfle module driven from a host that cannot see Lua
 * (lua_bridge.h): the state, its value stack, protected calls and
 * callbacks into the host.
 */
#include "lua/bridge/lua_bridge.h"

#include <stdlib.h>
#include <string.h>

#include <lauxlib.h>
#include <lualib.h>

#include "lua/core/dfle_lua.h"

#include "dfle/lua.h"

#include "lua/bridge/lua_bridge_internal.h"


static void on_warning(void *ud, const char *msg, int tocont)
{
    dfle_bridge *b = ud;
    size_t len = strlen(msg);
    if (!b->wcont && !tocont && msg[0] == '@')
        return; /* a control message ("@on", "@off") */
    if (b->wlen + len + 1 > b->wcap) {
        size_t cap = 2 * (b->wlen + len + 1);
        char *p = realloc(b->wbuf, cap);
        if (p == NULL) { /* drop this warning rather than fail the call */
            b->wlen = 0;
            b->wcont = tocont;
            return;
        }
        b->wbuf = p;
        b->wcap = cap;
    }
    memcpy(b->wbuf + b->wlen, msg, len + 1);
    b->wlen += len;
    b->wcont = tocont;
    if (!tocont) {
        if (b->warn != NULL)
            b->warn(b->warn_ud, b->wbuf);
        b->wlen = 0;
    }
}

static int host_fn_gc(lua_State *L);

static int open_p(lua_State *L)
{
    dfle_bridge *b = lua_touserdata(L, 1);
    lua_newtable(L);
    b->refs = luaL_ref(L, LUA_REGISTRYINDEX);
    luaL_openlibs(L);
    luaL_requiref(L, "dfle", luaopen_dfle, 1);
    lua_pop(L, 1);
    if (luaL_newmetatable(L, DFLE_BRIDGE_HOST_FN)) {
        lua_pushcfunction(L, host_fn_gc);
        lua_setfield(L, -2, "__gc");
    }
    lua_pop(L, 1);
    return 0;
}

dfle_bridge *dfle_bridge_new(const char **why)
{
    dfle_bridge *b = calloc(1, sizeof *b);
    const char *reason = "out of memory";
    if (b == NULL)
        goto fail;
    b->main = b->L = luaL_newstate();
    if (b->main == NULL)
        goto fail;
    lua_setwarnf(b->main, on_warning, b);
    lua_pushcfunction(b->main, open_p);
    lua_pushlightuserdata(b->main, b);
    if (lua_pcall(b->main, 1, 0, 0) != LUA_OK) {
        reason = "the dfle Lua module could not be opened";
        goto fail;
    }
    return b;
fail:
    if (why != NULL)
        *why = reason;
    dfle_bridge_free(b);
    return NULL;
}

void dfle_bridge_free(dfle_bridge *b)
{
    if (b == NULL)
        return;
    if (b->main != NULL)
        lua_close(b->main);
    free(b->worker_script);
    free(b->wbuf);
    free(b);
}

void dfle_bridge_set_warn(dfle_bridge *b, void (*fn)(void *ud, const char *msg), void *ud)
{
    b->warn = fn;
    b->warn_ud = ud;
}

void dfle_bridge_set_interrupt(dfle_bridge *b, const volatile sig_atomic_t *flag)
{
    dfle_lua_set_interrupt(b->main, flag);
}

int dfle_bridge_top(dfle_bridge *b) { return lua_gettop(b->L); }
void dfle_bridge_settop(dfle_bridge *b, int top) { lua_settop(b->L, top); }
int dfle_bridge_check(dfle_bridge *b, int n) { return lua_checkstack(b->L, n); }

void dfle_bridge_push_nil(dfle_bridge *b) { lua_pushnil(b->L); }
void dfle_bridge_push_boolean(dfle_bridge *b, int v) { lua_pushboolean(b->L, v); }
void dfle_bridge_push_number(dfle_bridge *b, double v) { lua_pushnumber(b->L, v); }
void dfle_bridge_push_integer(dfle_bridge *b, long long v)
{
    lua_pushinteger(b->L, (lua_Integer)v);
}
void dfle_bridge_push_string(dfle_bridge *b, const char *s, size_t len)
{
    lua_pushlstring(b->L, s, len);
}
void dfle_bridge_push_module(dfle_bridge *b) { dfle_lua_push_module(b->L); }
void dfle_bridge_push_value(dfle_bridge *b, int idx) { lua_pushvalue(b->L, idx); }

void dfle_bridge_push_doubles(dfle_bridge *b, const double *v, size_t n)
{
    dfle_lua_push_array(b->L, v, n);
}

void dfle_bridge_push_integers(dfle_bridge *b, const long long *iv, size_t n)
{
    lua_State *L = b->L;
    lua_createtable(L, (int)n, 0);
    for (size_t i = 0; i < n; i++) {
        lua_pushinteger(L, (lua_Integer)iv[i]);
        lua_rawseti(L, -2, (lua_Integer)i + 1);
    }
}

void dfle_bridge_new_table(dfle_bridge *b, int narr, int nrec) { lua_createtable(b->L, narr, nrec); }

void dfle_bridge_set_field(dfle_bridge *b, int t, const char *k)
{
    lua_State *L = b->L;
    t = lua_absindex(L, t);
    lua_pushstring(L, k);
    lua_insert(L, -2);
    lua_rawset(L, t);
}

void dfle_bridge_set_index(dfle_bridge *b, int t, long long i)
{
    lua_rawseti(b->L, t, (lua_Integer)i);
}

/* The closure of a callback: the host's code, with this frame current. */
static int call_host(lua_State *L)
{
    host_fn *h = lua_touserdata(L, lua_upvalueindex(1));
    lua_State *saved = h->b->L;
    int n;
    h->b->L = L;
    n = h->fn(h->b, h->ud, lua_gettop(L));
    h->b->L = saved;
    if (n < 0)
        return lua_error(L);
    return n;
}

static int host_fn_gc(lua_State *L)
{
    host_fn *h = lua_touserdata(L, 1);
    if (h->release != NULL)
        h->release(h->ud);
    h->release = NULL;
    return 0;
}

void dfle_bridge_push_callback(dfle_bridge *b, dfle_bridge_fn fn, void *ud,
                               void (*release)(void *ud))
{
    lua_State *L = b->L;
    host_fn *h = lua_newuserdatauv(L, sizeof *h, 0);
    h->b = b;
    h->fn = fn;
    h->ud = ud;
    h->release = release;
    luaL_setmetatable(L, DFLE_BRIDGE_HOST_FN);
    lua_pushcclosure(L, call_host, 1);
}

/* The host's references live in a table of their own (b->refs in the
 * registry), so that lua_bridge_gc.c can tell them from the binding's. */
int dfle_bridge_ref(dfle_bridge *b)
{
    int ref;
    lua_rawgeti(b->L, LUA_REGISTRYINDEX, b->refs);
    lua_insert(b->L, -2);
    ref = luaL_ref(b->L, -2);
    lua_pop(b->L, 1);
    return ref;
}

void dfle_bridge_push_ref(dfle_bridge *b, int ref)
{
    lua_rawgeti(b->L, LUA_REGISTRYINDEX, b->refs);
    lua_rawgeti(b->L, -1, ref);
    lua_remove(b->L, -2);
}

void dfle_bridge_unref(dfle_bridge *b, int ref)
{
    lua_rawgeti(b->L, LUA_REGISTRYINDEX, b->refs);
    luaL_unref(b->L, -1, ref);
    lua_pop(b->L, 1);
}

int dfle_bridge_type(dfle_bridge *b, int idx)
{
    switch (lua_type(b->L, idx)) {
    case LUA_TNIL:
    case LUA_TNONE: return DFLE_BRIDGE_NIL;
    case LUA_TBOOLEAN: return DFLE_BRIDGE_BOOLEAN;
    case LUA_TNUMBER: return DFLE_BRIDGE_NUMBER;
    case LUA_TSTRING: return DFLE_BRIDGE_STRING;
    case LUA_TTABLE: return DFLE_BRIDGE_TABLE;
    case LUA_TFUNCTION: return DFLE_BRIDGE_FUNCTION;
    case LUA_TUSERDATA: return DFLE_BRIDGE_OBJECT;
    default: return DFLE_BRIDGE_OTHER;
    }
}

int dfle_bridge_is_integer(dfle_bridge *b, int idx) { return lua_isinteger(b->L, idx); }
int dfle_bridge_to_boolean(dfle_bridge *b, int idx) { return lua_toboolean(b->L, idx); }
double dfle_bridge_to_number(dfle_bridge *b, int idx) { return lua_tonumber(b->L, idx); }
long long dfle_bridge_to_integer(dfle_bridge *b, int idx) { return lua_tointeger(b->L, idx); }

const char *dfle_bridge_to_string(dfle_bridge *b, int idx, size_t *len)
{
    if (lua_type(b->L, idx) != LUA_TSTRING)
        return NULL;
    return lua_tolstring(b->L, idx, len);
}

const char *dfle_bridge_typename(dfle_bridge *b, int idx) { return dfle_lua_typename(b->L, idx); }

int dfle_bridge_has_metatable(dfle_bridge *b, int idx)
{
    if (!lua_getmetatable(b->L, idx))
        return 0;
    lua_pop(b->L, 1);
    return 1;
}

size_t dfle_bridge_len(dfle_bridge *b, int idx) { return (size_t)lua_rawlen(b->L, idx); }

int dfle_bridge_number_array(dfle_bridge *b, int idx, double *out, size_t n, int *all_int)
{
    lua_State *L = b->L;
    size_t count = 0;
    int ints = 1;
    idx = lua_absindex(L, idx);
    /* Every key must be one of 1..n: count the pairs. */
    lua_pushnil(L);
    while (lua_next(L, idx) != 0) {
        if (!lua_isinteger(L, -2) || lua_type(L, -1) != LUA_TNUMBER) {
            lua_pop(L, 2);
            return 0;
        }
        lua_Integer k = lua_tointeger(L, -2);
        if (k < 1 || (size_t)k > n) {
            lua_pop(L, 2);
            return 0;
        }
        ints = ints && lua_isinteger(L, -1);
        out[k - 1] = lua_tonumber(L, -1);
        count++;
        lua_pop(L, 1);
    }
    if (all_int != NULL)
        *all_int = ints;
    return count == n;
}

int dfle_bridge_next(dfle_bridge *b, int t) { return lua_next(b->L, t); }
void dfle_bridge_rawgeti(dfle_bridge *b, int t, long long i) { lua_rawgeti(b->L, t, (lua_Integer)i); }

/* An error object as the message the host shows. */
static void error_text(lua_State *L)
{
    if (lua_type(L, -1) != LUA_TSTRING) {
        const char *t = luaL_typename(L, -1);
        lua_pop(L, 1);
        lua_pushfstring(L, "(error object is a %s value)", t);
    }
}

/* obj[key] and whether it is a method: (obj, key) -> value, method. */
static int index_p(lua_State *L)
{
    int method = 0;
    if (lua_type(L, 1) == LUA_TTABLE) {
        lua_pushvalue(L, 2);
        if (lua_rawget(L, 1) == LUA_TNIL) {
            lua_pop(L, 1);
            lua_gettable(L, 1);
            method = lua_type(L, -1) == LUA_TFUNCTION;
        }
    } else {
        lua_pushvalue(L, 2);
        lua_gettable(L, 1);
        method = lua_type(L, -1) == LUA_TFUNCTION;
    }
    lua_pushboolean(L, method);
    return 2;
}

int dfle_bridge_index(dfle_bridge *b, int obj, const char *key, int *method)
{
    lua_State *L = b->L;
    obj = lua_absindex(L, obj);
    lua_pushcfunction(L, index_p);
    lua_pushvalue(L, obj);
    lua_pushstring(L, key);
    if (lua_pcall(L, 2, 2, 0) != LUA_OK) {
        error_text(L);
        return -1;
    }
    if (method != NULL)
        *method = lua_toboolean(L, -1);
    lua_pop(L, 1);
    return 0;
}

int dfle_bridge_call(dfle_bridge *b, int nargs, int *nres)
{
    lua_State *L = b->L;
    int base = lua_gettop(L) - nargs - 1;
    if (lua_pcall(L, nargs, LUA_MULTRET, 0) != LUA_OK) {
        error_text(L);
        return -1;
    }
    *nres = lua_gettop(L) - base;
    return 0;
}

int dfle_bridge_load(dfle_bridge *b, const char *src, size_t len, const char *name)
{
    lua_State *L = b->L;
    int st;
    luaL_Buffer buf;
    luaL_buffinit(L, &buf);
    luaL_addstring(&buf, "return ");
    luaL_addlstring(&buf, src, len);
    luaL_pushresult(&buf);
    st = luaL_loadbufferx(L, lua_tostring(L, -1), lua_rawlen(L, -1), name, "t");
    lua_remove(L, -2);
    if (st != LUA_OK) {
        error_text(L);
        return -1;
    }
    if (lua_pcall(L, 0, 1, 0) != LUA_OK) {
        error_text(L);
        return -1;
    }
    if (lua_type(L, -1) != LUA_TFUNCTION) {
        const char *t = luaL_typename(L, -1);
        lua_pop(L, 1);
        lua_pushfstring(L, "dfle.lua: the source of %s must be a function (got %s)", name, t);
        return -1;
    }
    return 0;
}

static int tostring_p(lua_State *L)
{
    luaL_tolstring(L, 1, NULL);
    return 1;
}

/* fn(value at idx) in protected mode, leaving its nresults results; on an
 * error, its text (error_text) and -1.  Metamethods (__tostring,
 * __close) may raise, so every call through one goes this way. */
static int protected_on(dfle_bridge *b, int idx, lua_CFunction fn, int nresults)
{
    lua_State *L = b->L;
    idx = lua_absindex(L, idx);
    lua_pushcfunction(L, fn);
    lua_pushvalue(L, idx);
    if (lua_pcall(L, 1, nresults, 0) != LUA_OK) {
        error_text(L);
        return -1;
    }
    return 0;
}

int dfle_bridge_tostring(dfle_bridge *b, int idx)
{
    return protected_on(b, idx, tostring_p, 1);
}

static int close_p(lua_State *L)
{
    if (luaL_getmetafield(L, 1, "__close") == LUA_TNIL)
        return 0;
    lua_pushvalue(L, 1);
    lua_pushnil(L);
    lua_call(L, 2, 0);
    return 0;
}

int dfle_bridge_close(dfle_bridge *b, int idx)
{
    return protected_on(b, idx, close_p, 0);
}
