/*
 * lua_trace_outside.c - what a traced function reads besides its
 * arguments: params, globals, upvalues, math and the functions it calls.
 *
 * Each value read from outside is recorded as a guard the caller checks
 * again before the program runs (lua_trace.h), then replaced by what the
 * trace must see instead (stand_in): a number or string as itself, a
 * table through a proxy whose reads are guarded in turn, a math function
 * by its recording wrapper (lua_trace_node.c), a Lua function after its
 * bytecode is vetted (lua_trace_bytecode.c) and its upvalues are pointed
 * at stand-ins.  Anything no guard could watch is refused: writes, the
 * length of a proxy, a computed key, string methods, a metatable on nil,
 * booleans, numbers or functions.  Every swap is listed before it is
 * made, so that dfle_trace_compile (lua_trace.c) undoes them all.
 */
#include "lua/trace/lua_trace_internal.h"

#include <lauxlib.h>
#include <lualib.h>
#include <stdio.h>
#include <string.h>

#define MAX_GUARDS 256 /* outside values it may read                   */
#define MAX_DEPTH 8    /* helper functions calling helper functions    */

/* ---- outside values ---------------------------------------------------- */

static void add_guard(lua_State *L, tracer *t, int tidx, int kind, int container, int key,
                      int value)
{
    int n;
    if (t->n_guards == MAX_GUARDS)
        dfle_trace_refuse(L, t, "it reads more than %d outside values", MAX_GUARDS);
    container = lua_absindex(L, container), key = lua_absindex(L, key);
    value = lua_absindex(L, value);
    lua_getiuservalue(L, tidx, UV_GUARDS);
    n = t->n_guards;
    lua_pushinteger(L, kind);
    lua_rawseti(L, -2, 4 * n + 1);
    lua_pushvalue(L, container);
    lua_rawseti(L, -2, 4 * n + 2);
    lua_pushvalue(L, key);
    lua_rawseti(L, -2, 4 * n + 3);
    if (lua_isnil(L, value))
        lua_pushlightuserdata(L, (void *)&dfle_trace_nil);
    else
        lua_pushvalue(L, value);
    lua_rawseti(L, -2, 4 * n + 4);
    lua_pop(L, 1);
    t->n_guards++;
}

/* orig[stand-in at `standin`] = the value at `original`. */
static void remember_original(lua_State *L, int tidx, int standin, int original)
{
    standin = lua_absindex(L, standin), original = lua_absindex(L, original);
    lua_getiuservalue(L, tidx, UV_ORIG);
    lua_pushvalue(L, standin);
    lua_pushvalue(L, original);
    lua_rawset(L, -3);
    lua_pop(L, 1);
}
static void push_table_proxy(lua_State *L, int tidx, int real, int is_math);

static int is_loaded_math(lua_State *L, int idx)
{
    int same;
    idx = lua_absindex(L, idx);
    lua_getfield(L, LUA_REGISTRYINDEX, LUA_LOADED_TABLE);
    lua_getfield(L, -1, LUA_MATHLIBNAME);
    same = lua_istable(L, -1) && lua_rawequal(L, -1, idx);
    lua_pop(L, 2);
    return same;
}

/* Replace the value at idx (read as `what`) by what the trace must see
 * instead: itself (a constant), a proxy (math, a vetted environment), a
 * math wrapper, or a vetted Lua function.  Raises (refuses) otherwise. */
static void stand_in(lua_State *L, tracer *t, int tidx, int idx, const char *what)
{
    luaL_checkstack(L, 12, "dfle: tracing a law");
    idx = lua_absindex(L, idx);
    switch (lua_type(L, idx)) {
    case LUA_TNIL:
    case LUA_TBOOLEAN:
    case LUA_TNUMBER:
    case LUA_TSTRING:
        return;
    case LUA_TTABLE:
        if (!is_loaded_math(L, idx))
            dfle_trace_refuse(L, t, "it reads the table %s (only numbers, strings, booleans, "
                                    "math and functions can be compiled)", what);
        push_table_proxy(L, tidx, idx, 1);
        lua_replace(L, idx);
        return;
    case LUA_TFUNCTION:
        if (lua_iscfunction(L, idx)) {
            int op = dfle_trace_math_op_of(L, idx);
            if (op == 0)
                dfle_trace_refuse(L, t, "it calls %s, a C function other than the math ones", what);
            lua_pushinteger(L, op);
            lua_pushvalue(L, idx);
            lua_pushcclosure(L, dfle_trace_math_wrapper, 2);
            remember_original(L, tidx, -1, idx);
            lua_replace(L, idx);
        } else {
            dfle_trace_vet_function(L, t, tidx, idx, what);
        }
        return;
    default:
        dfle_trace_refuse(L, t, "it reads %s, a %s", what, luaL_typename(L, idx));
    }
}

/* How names read from a proxy of each PROXY_ kind are reported. */
static const char *const proxy_prefix[] = {"the global '", "math.", "p."};
static const char *const proxy_table[] = {"the global table", "math", "p"};
static const char *const proxy_suffix[] = {"'", "", ""};

/* A float param read as an input (the value at 3, its key at 2, in a
 * proxy_index call): one T_PARAM node per key and trace, guarded as
 * G_PARAM with that node's index.  The program then serves every law
 * whose param is a float, whatever its value (lua_trace_cache.c); a
 * function that does more with the value than arithmetic (compares it,
 * loops to it) is refused, and dfle_trace_compile traces it again with
 * the value as a constant. */
static int param_input(lua_State *L, tracer *t)
{
    int node;
    lua_getiuservalue(L, lua_upvalueindex(1), UV_PARAMS); /* 4 */
    lua_pushvalue(L, 2);
    if (lua_rawget(L, 4) == LUA_TNUMBER) { /* 5 */
        node = (int)lua_tointeger(L, 5);
    } else {
        node = dfle_trace_add_node(L, t, T_PARAM, t->n_params, 0, lua_tonumber(L, 3), 0);
        lua_pushinteger(L, node); /* 6 */
        add_guard(L, t, lua_upvalueindex(1), G_PARAM, lua_upvalueindex(2), 2, 6);
        lua_pushvalue(L, 2);
        lua_pushinteger(L, node);
        lua_rawset(L, 4);
        t->n_params++;
    }
    dfle_trace_push_node(L, lua_upvalueindex(1), node);
    return 1;
}

/* __index of a proxy: upvalues 1 = tracer, 2 = the real table, 3 = its
 * PROXY_ kind.  The value read is guarded, then replaced by its stand-in. */
static int proxy_index(lua_State *L)
{
    tracer *t = tracer_at(L, lua_upvalueindex(1));
    const int kind = (int)lua_tointeger(L, lua_upvalueindex(3));
    char what[96];
    if (!t->active)
        return luaL_error(L, "dfle: a compiled law's environment was used after its trace");
    lua_settop(L, 2);
    /* A key computed from a flow field or a param input (p[c.h]) names a
     * different field for each value, and no guard could watch which. */
    if (luaL_testudata(L, 2, NODE_MT) != NULL)
        return dfle_trace_refuse(L, t, "it indexes %s with a computed value", proxy_table[kind]);
    lua_pushvalue(L, 2);
    lua_rawget(L, lua_upvalueindex(2)); /* 3: the real value */
    snprintf(what, sizeof what, "%s%s%s", proxy_prefix[kind],
             lua_type(L, 2) == LUA_TSTRING ? lua_tostring(L, 2) : "?", proxy_suffix[kind]);
    /* A metatable (strict.lua, say) is consulted only for absent keys,
     * so a present value is what the function reads; an absent one may
     * not be nil for it. */
    if (lua_isnil(L, 3) && lua_getmetatable(L, lua_upvalueindex(2)))
        return dfle_trace_refuse(L, t,
                                 "it reads %s, which is not set, from a table with a metatable",
                                 what);
    if (kind == PROXY_PARAMS && t->symbolic && lua_type(L, 3) == LUA_TNUMBER &&
        !lua_isinteger(L, 3))
        return param_input(L, t);
    add_guard(L, t, lua_upvalueindex(1), G_FIELD, lua_upvalueindex(2), 2, 3);
    stand_in(L, t, lua_upvalueindex(1), 3, what);
    lua_settop(L, 3);
    return 1;
}

/* __newindex of a proxy: upvalues 1 = tracer, 2 = its PROXY_ kind. */
static int proxy_newindex(lua_State *L)
{
    tracer *t = tracer_at(L, lua_upvalueindex(1));
    const int kind = (int)lua_tointeger(L, lua_upvalueindex(2));
    return dfle_trace_refuse(L, t, "it assigns to %s%s%s (a side effect)", proxy_prefix[kind],
                             lua_type(L, 2) == LUA_TSTRING ? lua_tostring(L, 2) : "?",
                             proxy_suffix[kind]);
}

/* __len of a proxy: upvalues 1 = tracer, 2 = its PROXY_ kind.  The proxy
 * itself is empty, and the real table's length is a value no guard would
 * watch. */
static int proxy_len(lua_State *L)
{
    tracer *t = tracer_at(L, lua_upvalueindex(1));
    return dfle_trace_refuse(L, t, "it takes the length of %s",
                             proxy_table[lua_tointeger(L, lua_upvalueindex(2))]);
}

/* Push a new proxy of the table at `real`. */
void dfle_trace_push_proxy(lua_State *L, int tidx, int real, int kind)
{
    real = lua_absindex(L, real);
    lua_createtable(L, 0, 0);
    lua_createtable(L, 0, 3);
    lua_pushvalue(L, tidx);
    lua_pushvalue(L, real);
    lua_pushinteger(L, kind);
    lua_pushcclosure(L, proxy_index, 3);
    lua_setfield(L, -2, "__index");
    lua_pushvalue(L, tidx);
    lua_pushinteger(L, kind);
    lua_pushcclosure(L, proxy_newindex, 2);
    lua_setfield(L, -2, "__newindex");
    lua_pushvalue(L, tidx);
    lua_pushinteger(L, kind);
    lua_pushcclosure(L, proxy_len, 2);
    lua_setfield(L, -2, "__len");
    lua_setmetatable(L, -2);
}

/* Push the proxy of the table at `real` (an environment or math), one per
 * real table and trace. */
static void push_table_proxy(lua_State *L, int tidx, int real, int is_math)
{
    real = lua_absindex(L, real);
    lua_getiuservalue(L, tidx, UV_CACHE);
    lua_pushvalue(L, real);
    if (lua_rawget(L, -2) == LUA_TTABLE) {
        lua_remove(L, -2);
        return;
    }
    lua_pop(L, 1);
    dfle_trace_push_proxy(L, tidx, real, is_math ? PROXY_MATH : PROXY_ENV);
    lua_pushvalue(L, real);
    lua_pushvalue(L, -2);
    lua_rawset(L, -4); /* cache[real] = proxy */
    lua_remove(L, -2);
    remember_original(L, tidx, -1, real);
}

/* ---- functions --------------------------------------------------------- */

/* Record a swap of upvalue i of the function at fidx to the value on top
 * (popped), listed first so that dfle_trace_compile can undo it. */
static void swap_upvalue(lua_State *L, tracer *t, int tidx, int fidx, int i)
{
    lua_getiuservalue(L, tidx, UV_SWAPS);
    lua_pushvalue(L, fidx);
    lua_rawseti(L, -2, 3 * t->n_swaps + 1);
    lua_pushinteger(L, i);
    lua_rawseti(L, -2, 3 * t->n_swaps + 2);
    lua_getupvalue(L, fidx, i);
    lua_rawseti(L, -2, 3 * t->n_swaps + 3);
    t->n_swaps++;
    lua_pop(L, 1);
    lua_setupvalue(L, fidx, i);
}

/* Check that the Lua function at fidx can be traced, and point its
 * upvalues at stand-ins for the trace. */
void dfle_trace_vet_function(lua_State *L, tracer *t, int tidx, int fidx, const char *what)
{
    unsigned found;
    luaL_checkstack(L, 12, "dfle: tracing a law"); /* helpers nest: C stack frames do not */
    fidx = lua_absindex(L, fidx);
    lua_getiuservalue(L, tidx, UV_CACHE);
    lua_pushvalue(L, fidx);
    if (lua_rawget(L, -2) != LUA_TNIL) { /* vetted already */
        lua_pop(L, 2);
        return;
    }
    lua_pushvalue(L, fidx);
    lua_pushboolean(L, 1);
    lua_rawset(L, -4);
    lua_pop(L, 2);
    if (++t->depth > MAX_DEPTH)
        dfle_trace_refuse(L, t, "it calls functions nested more than %d deep", MAX_DEPTH);
    found = dfle_trace_scan(L, fidx);
    if (found & FOUND_EQ)
        dfle_trace_refuse(L, t, "%s uses '==' or '~=' (an equality test on a flow field cannot be "
                                "recorded)", what);
    if (found & FOUND_SETUPVAL)
        dfle_trace_refuse(L, t, "%s assigns to an upvalue (a side effect)", what);
    if (found & FOUND_BAD)
        dfle_trace_refuse(L, t, "%s has bytecode this build does not know", what);
    for (int i = 1;; i++) {
        const char *name = lua_getupvalue(L, fidx, i);
        char uwhat[96];
        if (name == NULL)
            break;
        lua_getiuservalue(L, tidx, UV_ORIG);
        lua_pushvalue(L, -2);
        if (lua_rawget(L, -2) != LUA_TNIL) {
            /* A cell swapped while vetting another function: guard its
             * original value, and leave the stand-in in place. */
            lua_pushinteger(L, i);
            add_guard(L, t, tidx, G_UPVALUE, fidx, -1, -2);
            lua_pop(L, 4);
            continue;
        }
        lua_pop(L, 2);
        if (strcmp(name, "_ENV") == 0) {
            if (!lua_istable(L, -1))
                dfle_trace_refuse(L, t, "%s has an _ENV that is not a table", what);
            lua_pushinteger(L, i);
            add_guard(L, t, tidx, G_UPVALUE, fidx, -1, -2);
            lua_pop(L, 1);
            push_table_proxy(L, tidx, -1, 0);
            swap_upvalue(L, t, tidx, fidx, i);
            lua_pop(L, 1);
            continue;
        }
        snprintf(uwhat, sizeof uwhat, "the upvalue '%s'", name[0] ? name : "?");
        lua_pushinteger(L, i);
        add_guard(L, t, tidx, G_UPVALUE, fidx, -1, -2);
        lua_pop(L, 1);
        lua_pushvalue(L, -1);
        stand_in(L, t, tidx, -1, uwhat);
        if (lua_rawequal(L, -1, -2))
            lua_pop(L, 1);
        else
            swap_upvalue(L, t, tidx, fidx, i);
        lua_pop(L, 1);
    }
    t->depth--;
}

/* Strings' __index during a trace: upvalue 1 = the tracer. */
static int string_method(lua_State *L)
{
    return dfle_trace_refuse(L, tracer_at(L, lua_upvalueindex(1)),
                             "it calls a string method (the string library is not compiled)");
}

/* Values other than tables and full userdata share one metatable per
 * type, through which a function could reach code the trace never vets
 * and values no guard watches: a string method (("ab"):len() calls
 * string.len, which a script may replace), or whatever debug.setmetatable
 * gave numbers, booleans, nil or functions.  A metatable on those refuses
 * the function; strings' __index is swapped for one that refuses (the
 * metatable and the original are kept in the cache table under
 * string_mt_key and string_index_key, and put back by trace_once
 * whatever happens). */
static const char string_mt_key = 0, string_index_key = 0;

void dfle_trace_close_shared_metatables(lua_State *L, tracer *t, int tidx)
{
    static const char *const what[] = {"nil", "booleans", "numbers", "functions"};
    for (int k = 0; k < 4; k++) {
        switch (k) {
        case 0: lua_pushnil(L); break;
        case 1: lua_pushboolean(L, 0); break;
        case 2: lua_pushinteger(L, 0); break;
        default: lua_pushcfunction(L, string_method); break;
        }
        if (lua_getmetatable(L, -1))
            dfle_trace_refuse(L, t,
                              "%s have a metatable (debug.setmetatable), which a trace cannot "
                              "follow", what[k]);
        lua_pop(L, 1);
    }
    lua_pushliteral(L, "");
    if (!lua_getmetatable(L, -1)) {
        lua_pop(L, 1);
        return;
    }
    lua_pushliteral(L, "__index");
    if (lua_rawget(L, -2) == LUA_TNIL) { /* indexing a string fails anyway */
        lua_pop(L, 3);
        return;
    }
    lua_getiuservalue(L, tidx, UV_CACHE);
    lua_insert(L, -2);
    lua_rawsetp(L, -2, &string_index_key);
    lua_pushvalue(L, -2);
    lua_rawsetp(L, -2, &string_mt_key);
    lua_pop(L, 1);
    lua_pushliteral(L, "__index");
    lua_pushvalue(L, tidx);
    lua_pushcclosure(L, string_method, 1);
    lua_rawset(L, -3);
    lua_pop(L, 2);
}

/* Put strings' __index back.  No allocation (it runs outside the
 * protected call): the metatable comes from the cache table, and
 * "__index" is one of Lua's fixed strings, already a key there. */
void dfle_trace_reopen_shared_metatables(lua_State *L, int tidx)
{
    const int top = lua_gettop(L);
    lua_getiuservalue(L, tidx, UV_CACHE);                       /* top+1 */
    if (lua_rawgetp(L, top + 1, &string_mt_key) == LUA_TTABLE &&  /* top+2 */
        lua_rawgetp(L, top + 1, &string_index_key) != LUA_TNIL) { /* top+3 */
        lua_pushliteral(L, "__index");
        lua_insert(L, top + 3);
        lua_rawset(L, top + 2);
    }
    lua_settop(L, top);
}
