/*
 * lua_trace_cache.c - compiled programs shared between laws (lua_trace.h).
 *
 * An ensemble builds a new law for every sample, usually from the same
 * functions with other params.  Tracing a function and checking the
 * program against Lua costs about half a millisecond, as much as a whole
 * direct steady state, so each lua_State keeps the programs it has traced
 * and checked, and hands a copy to a later law when that is valid.
 *
 * When is it valid?  A trace is a deterministic replay of the function:
 * what it records depends only on the function's code, the spec it was
 * traced for, and the values it read from outside, every one of which is
 * in its guard table (upvalues, globals, math, params; lua_trace.c closes
 * the routes around them: string methods, shared metatables, the length
 * of a proxy).  So a program traced for one law serves another when
 *
 *  - the code is the same: the key is the chunk lua_dump writes for the
 *    function, with its debug information (so two functions from
 *    different lines never share, while the closures one `function`
 *    expression makes each time it runs do), and the spec;
 *  - every guard holds for the new law, with the marks dfle_trace_root
 *    and dfle_trace_params standing for its own function and params
 *    table: the same upvalue values (functions and tables by identity),
 *    the same globals, the same integer, string and boolean params;
 *  - every float param the program reads as an input (G_PARAM) is a float
 *    in the new law too; its value is bound into the copy.
 *
 * Only programs that have been checked against the function run as Lua
 * are kept (the caller calls dfle_trace_cache_put after the check), so a
 * copy needs no check of its own: its operations are those of a checked
 * program, and a param value is an operand like a node's slope (the
 * replay of every operation against Lua, over operands of every class, is
 * in tests/lua/test_compile.lua).
 *
 * Layout: registry[&cache_key] is a userdata holding the counters, whose
 * user values are the map chunk -> spec -> bucket (an array of templates,
 * newest last) and a memo function -> chunk with weak keys (dumping a
 * function costs more than the rest of a lookup).  A template is a userdata owning a program (freed by __gc) whose
 * user value is its guard table, marks in place of the law's function
 * and params.  At most PER_KEY templates per key and HELD in all: past
 * that the oldest of a key goes, or the whole map (an ensemble that keeps
 * making new helper closures would otherwise fill it).  All Lua work runs
 * under lua_pcall, so nothing here raises into the model.
 */
#include "lua/core/dfle_lua.h"
#include "lua/trace/lua_trace_internal.h"

#include <stdio.h>
#include <string.h>

#define PER_KEY 8
#define HELD 256

/* Registry keys (their addresses): the cache, the templates' metatable.
 * Not names: a second copy of the binding in the same state (dfle.so
 * required by a host that has it built in) keeps a cache of its own. */
static const char cache_key = 0, template_mt_key = 0;

typedef struct cache_state {
    dfle_trace_stats stats;
} cache_state;

typedef struct template_ud {
    dfle_trace_prog *prog;
} template_ud;

static int template_gc(lua_State *L)
{
    template_ud *u = lua_touserdata(L, 1);
    dfle_trace_free(u->prog);
    u->prog = NULL;
    return 0;
}

/* The cache state of L, or NULL (the module was not opened). */
static cache_state *state_of(lua_State *L)
{
    cache_state *c = NULL;
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &cache_key) == LUA_TUSERDATA)
        c = lua_touserdata(L, -1);
    lua_pop(L, 1);
    return c;
}

dfle_trace_stats *dfle_trace_stats_of(lua_State *L)
{
    cache_state *c = state_of(L);
    return c != NULL ? &c->stats : NULL;
}

/* A new, empty map as the cache's user value 1. */
static void new_map(lua_State *L, int cidx)
{
    lua_newtable(L);
    lua_setiuservalue(L, cidx, 1);
    ((cache_state *)lua_touserdata(L, cidx))->stats.held = 0;
}

void dfle_trace_cache_open(lua_State *L)
{
    if (state_of(L) != NULL)
        return;
    lua_createtable(L, 0, 1);
    lua_pushcfunction(L, template_gc);
    lua_setfield(L, -2, "__gc");
    lua_rawsetp(L, LUA_REGISTRYINDEX, &template_mt_key);
    memset(lua_newuserdatauv(L, sizeof(cache_state), 3), 0, sizeof(cache_state));
    new_map(L, lua_gettop(L));
    lua_newtable(L); /* the memo of chunks, weak keys */
    lua_createtable(L, 0, 1);
    lua_pushliteral(L, "k");
    lua_setfield(L, -2, "__mode");
    lua_setmetatable(L, -2);
    lua_setiuservalue(L, -2, 2);
    lua_newtable(L); /* code traced with params as constants only */
    lua_setiuservalue(L, -2, 3);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &cache_key);
}

/* Push the chunk of the function at fidx (nil if lua_dump gives none),
 * from the memo if it is there, and the spec as a short string. */
static void push_key(lua_State *L, int fidx, const dfle_trace_spec *spec)
{
    luaL_Buffer b;
    char head[96];
    fidx = lua_absindex(L, fidx);
    lua_rawgetp(L, LUA_REGISTRYINDEX, &cache_key);
    lua_getiuservalue(L, -1, 2);
    lua_pushvalue(L, fidx);
    if (lua_rawget(L, -2) == LUA_TNIL) {
        lua_pop(L, 1);
        dfle_trace_push_dump(L, fidx);
        lua_pushvalue(L, fidx);
        lua_pushvalue(L, -2);
        lua_rawset(L, -4); /* a nil chunk stores nothing */
    }
    lua_replace(L, -3);
    lua_pop(L, 1);
    luaL_buffinit(L, &b);
    snprintf(head, sizeof head, "%d %d %x %d", spec->n_inputs, spec->positional,
             spec->available, spec->params_inputs);
    luaL_addstring(&b, head);
    for (int f = 0; f < spec->n_inputs; f++) {
        luaL_addchar(&b, ' ');
        luaL_addstring(&b, spec->names[f]);
    }
    luaL_pushresult(&b);
}

/* Push the bucket of the key at kidx, kidx + 1 (chunk, spec), creating it
 * if `create`; else nil if there is none. */
static void push_bucket(lua_State *L, int kidx, int create)
{
    kidx = lua_absindex(L, kidx);
    lua_rawgetp(L, LUA_REGISTRYINDEX, &cache_key);
    lua_getiuservalue(L, -1, 1);
    for (int level = 0; level < 2; level++) {
        lua_pushvalue(L, kidx + level);
        if (lua_rawget(L, -2) == LUA_TNIL) {
            lua_pop(L, 1);
            if (!create) {
                lua_pop(L, 2);
                lua_pushnil(L);
                return;
            }
            lua_newtable(L);
            lua_pushvalue(L, kidx + level);
            lua_pushvalue(L, -2);
            lua_rawset(L, -4);
        }
        lua_replace(L, -2);
    }
    lua_replace(L, -2);
}

/* Copy the guard table at gidx, putting `to_a` in place of `from_a` and
 * `to_b` in place of `from_b` (wherever they are: container, key, value). */
static void copy_guards(lua_State *L, int gidx, int from_a, int to_a, int from_b, int to_b)
{
    const lua_Integer n = (lua_Integer)lua_rawlen(L, gidx);
    lua_createtable(L, (int)n, 0);
    for (lua_Integer i = 1; i <= n; i++) {
        lua_rawgeti(L, gidx, i);
        if (lua_rawequal(L, -1, from_a)) {
            lua_pop(L, 1);
            lua_pushvalue(L, to_a);
        } else if (lua_rawequal(L, -1, from_b)) {
            lua_pop(L, 1);
            lua_pushvalue(L, to_b);
        }
        lua_rawseti(L, -2, i);
    }
}

/* find: args 1 function, 2 params, 3 spec (light userdata).  Returns the
 * template and the guard table for this law, or nothing. */
static int find_main(lua_State *L)
{
    const dfle_trace_spec *spec = lua_touserdata(L, 3);
    lua_Integer n;
    push_key(L, 1, spec); /* 4, 5 */
    if (lua_isnil(L, 4))
        return 0;
    push_bucket(L, 4, 0); /* 6 */
    if (!lua_istable(L, 6))
        return 0;
    lua_pushlightuserdata(L, (void *)&dfle_trace_root);   /* 7 */
    lua_pushlightuserdata(L, (void *)&dfle_trace_params); /* 8 */
    n = (lua_Integer)lua_rawlen(L, 6);
    for (lua_Integer i = n; i >= 1; i--) { /* newest first */
        lua_rawgeti(L, 6, i);        /* 9: template */
        lua_getiuservalue(L, 9, 1); /* 10: its guards */
        if (dfle_trace_guards_check(L, 10, NULL, 1, 2)) {
            copy_guards(L, 10, 7, 1, 8, 2);
            lua_remove(L, 10);
            return 2;
        }
        lua_pop(L, 2);
    }
    return 0;
}

/* constants_only: args 1 function, 2 spec (light userdata), 3 mark.
 * Returns whether the code is marked. */
static int constants_only_main(lua_State *L)
{
    const dfle_trace_spec *spec = lua_touserdata(L, 2);
    const int mark = lua_toboolean(L, 3);
    push_key(L, 1, spec); /* 4 chunk, 5 spec */
    if (lua_isnil(L, 4)) {
        lua_pushboolean(L, 0);
        return 1;
    }
    lua_concat(L, 2); /* 4: the key */
    lua_rawgetp(L, LUA_REGISTRYINDEX, &cache_key);
    lua_getiuservalue(L, -1, 3); /* 6 */
    if (mark) {
        lua_pushvalue(L, 4);
        lua_pushboolean(L, 1);
        lua_rawset(L, 6);
    }
    lua_pushvalue(L, 4);
    lua_rawget(L, 6);
    return 1;
}

int dfle_trace_cache_constants_only(lua_State *L, int fidx, const dfle_trace_spec *spec,
                                    int mark)
{
    const int top = lua_gettop(L);
    int marked = 0;
    if (state_of(L) == NULL || !lua_checkstack(L, 24))
        return 0;
    fidx = lua_absindex(L, fidx);
    lua_pushcfunction(L, constants_only_main);
    lua_pushvalue(L, fidx);
    lua_pushlightuserdata(L, (void *)spec);
    lua_pushboolean(L, mark);
    if (lua_pcall(L, 3, 1, 0) == LUA_OK)
        marked = lua_toboolean(L, -1);
    lua_settop(L, top);
    return marked;
}

/* Set the copy's param nodes from the law's params (pidx), as its guard
 * table (gidx) lists them.  No allocation: reads only. */
static void bind_params(lua_State *L, int gidx, int pidx, dfle_trace_prog *p)
{
    const lua_Integer n = (lua_Integer)lua_rawlen(L, gidx) / 4;
    for (lua_Integer j = 0; j < n; j++) {
        lua_rawgeti(L, gidx, 4 * j + 1);
        if (lua_tointeger(L, -1) == G_PARAM) {
            int idx;
            lua_rawgeti(L, gidx, 4 * j + 4);
            idx = (int)lua_tointeger(L, -1);
            lua_rawgeti(L, gidx, 4 * j + 3);
            lua_rawget(L, pidx);
            if (idx >= 0 && idx < p->n && p->node[idx].op == T_PARAM)
                p->node[idx].k = p->val[idx] = lua_tonumber(L, -1);
            lua_pop(L, 2);
        }
        lua_pop(L, 1);
    }
}

dfle_trace_prog *dfle_trace_cache_find(lua_State *L, int fidx, int pidx,
                                       const dfle_trace_spec *spec)
{
    cache_state *c = state_of(L);
    const template_ud *u;
    dfle_trace_prog *p;
    char why[8];
    int top;

    fidx = lua_absindex(L, fidx);
    pidx = lua_absindex(L, pidx);
    top = lua_gettop(L);
    /* no program of a Lua the tracer does not read, however it got here */
    if (c == NULL || !lua_checkstack(L, 24) || !dfle_trace_vm_ok(L, why, sizeof why)) {
        lua_pushnil(L);
        return NULL;
    }
    lua_pushcfunction(L, find_main);
    lua_pushvalue(L, fidx);
    lua_pushvalue(L, pidx);
    lua_pushlightuserdata(L, (void *)spec);
    if (lua_pcall(L, 3, 2, 0) != LUA_OK || lua_isnil(L, top + 1)) {
        lua_settop(L, top);
        lua_pushnil(L);
        return NULL;
    }
    /* top+1: the template (it stays alive on the stack), top+2: the
     * guards.  C only from here: the copy is not owned by Lua. */
    u = lua_touserdata(L, top + 1);
    if (u->prog == NULL || (p = dfle_trace_clone(u->prog)) == NULL) {
        lua_settop(L, top);
        lua_pushnil(L);
        return NULL;
    }
    bind_params(L, top + 2, pidx, p);
    lua_remove(L, top + 1);
    c->stats.found++;
    return p;
}

/* put: args 1 function, 2 params, 3 spec, 4 program (light userdata),
 * 5 its guard table. */
static int put_main(lua_State *L)
{
    const dfle_trace_spec *spec = lua_touserdata(L, 3);
    const dfle_trace_prog *prog = lua_touserdata(L, 4);
    cache_state *c = state_of(L);
    template_ud *u;
    lua_Integer n;

    push_key(L, 1, spec); /* 6, 7 */
    if (lua_isnil(L, 6) || c == NULL)
        return 0;
    u = lua_newuserdatauv(L, sizeof *u, 1); /* 8 */
    u->prog = NULL;
    lua_rawgetp(L, LUA_REGISTRYINDEX, &template_mt_key);
    lua_setmetatable(L, -2);
    if ((u->prog = dfle_trace_clone(prog)) == NULL)
        return luaL_error(L, "out of memory");
    lua_pushlightuserdata(L, (void *)&dfle_trace_root);   /* 9 */
    lua_pushlightuserdata(L, (void *)&dfle_trace_params); /* 10 */
    copy_guards(L, 5, 1, 9, 2, 10);
    lua_setiuservalue(L, 8, 1);
    if (c->stats.held >= HELD) { /* start afresh rather than grow */
        lua_rawgetp(L, LUA_REGISTRYINDEX, &cache_key);
        new_map(L, lua_gettop(L));
        lua_pop(L, 1);
    }
    push_bucket(L, 6, 1); /* 11 */
    n = (lua_Integer)lua_rawlen(L, 11);
    if (n >= PER_KEY) { /* the oldest goes */
        for (lua_Integer i = 1; i < n; i++) {
            lua_rawgeti(L, 11, i + 1);
            lua_rawseti(L, 11, i);
        }
        lua_pushnil(L);
        lua_rawseti(L, 11, n);
        n--;
        c->stats.held--;
    }
    lua_pushvalue(L, 8);
    lua_rawseti(L, 11, n + 1);
    c->stats.held++;
    c->stats.kept++;
    return 0;
}

void dfle_trace_cache_put(lua_State *L, int fidx, int pidx, const dfle_trace_spec *spec,
                          const dfle_trace_prog *prog, int gidx)
{
    const int top = lua_gettop(L);
    if (prog == NULL || !lua_checkstack(L, 24))
        return;
    fidx = lua_absindex(L, fidx);
    pidx = lua_absindex(L, pidx);
    gidx = lua_absindex(L, gidx);
    lua_pushcfunction(L, put_main);
    lua_pushvalue(L, fidx);
    lua_pushvalue(L, pidx);
    lua_pushlightuserdata(L, (void *)spec);
    lua_pushlightuserdata(L, (void *)prog);
    lua_pushvalue(L, gidx);
    (void)lua_pcall(L, 5, 0, 0); /* a failure keeps nothing, which is fine */
    lua_settop(L, top);
}
