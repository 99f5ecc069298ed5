/*
 * lua_trace.c - the tracer behind compiled Lua laws (lua_trace.h): one
 * trace of the user's function, and its record made into a program.
 *
 * The user's function is called once with "nodes" (a full userdata whose
 * arithmetic metamethods record an operation and return a new node) in
 * place of the flow fields, and with proxies in place of the tables it
 * reads (params, the global environment, `math`).  Lua itself then does
 * all the work of evaluating the function: constants fold as usual,
 * loops unroll, helper functions run; only operations that touch a node
 * are recorded, in the order Lua performs them.  The record is a DAG in
 * topological order, evaluated in C with the same IEEE operations Lua
 * uses (luai_numpow's a*a for ^2, luai_nummod's sign fix, lmathlib's
 * log bases), so compiled and interpreted values agree bit for bit.
 *
 * A record is faithful only if the function's result depends on the
 * inputs through arithmetic alone.  What could make it unfaithful, and
 * how each case is closed:
 *
 *  - ordering comparisons (<, <=) of a node raise through __lt/__le;
 *  - equality with a number does NOT reach a metamethod in Lua 5.4
 *    (`c.h == 0` is simply false for a userdata), so the bytecode of
 *    every function involved is scanned and any EQ/EQK/EQI refuses it;
 *  - side effects: writes to proxies raise, and SETUPVAL in the
 *    bytecode refuses the function (a counter in an upvalue);
 *  - values read from outside (params, globals, upvalues, math.pi) are
 *    recorded as guards the caller re-checks (lua_trace.h); a float param
 *    may instead be an input (T_PARAM) whose value each law binds, and is
 *    then opaque to the function: anything but arithmetic on it refuses;
 *  - what no guard could watch is refused: the length of a proxy (#p), a
 *    computed key (p[c.h]: another field for each value),
 *    string methods (strings' __index refuses during the trace), and any
 *    metatable debug.setmetatable gave nil, booleans, numbers or
 *    functions;
 *  - calls: only Lua functions (vetted the same way) and the pure math
 *    functions listed below, recognised by their C address as found in
 *    a fresh luaopen_math table, so a replaced math.sqrt is not trusted;
 *  - integer arithmetic: math.max(x, 0) may return the integer 0, so a
 *    node that may hold an integer cannot meet an integer in + - * // %.
 *
 * Everything the trace allocates is a Lua object (the tracer is a
 * userdata), so a raise leaks nothing; upvalues swapped for proxies
 * during the trace are listed before they are swapped and restored by
 * dfle_trace_compile after the protected call, whatever happened.
 *
 * This file makes the tracer, calls the function under lua_pcall and
 * stores the record; lua_trace_node.c records the arithmetic and math
 * calls on nodes; lua_trace_outside.c guards and stands in for what the
 * function reads from outside; lua_trace_eval.c runs a record and checks
 * its guards; lua_trace_bytecode.c does the bytecode scan;
 * lua_trace_release.c lists the Lua releases all this was checked
 * against (under any other nothing is compiled).
 */
#include "lua/trace/lua_trace_internal.h"

#include <lauxlib.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the call ---------------------------------------------------------- */

/* __index of c: a node per field, nil for fields the op does not have. */
static int c_index(lua_State *L)
{
    tracer *t = tracer_at(L, lua_upvalueindex(1));
    const dfle_trace_spec *s = t->spec;
    const char *key = lua_type(L, 2) == LUA_TSTRING ? lua_tostring(L, 2) : NULL;
    if (!t->active)
        return 0;
    for (int f = 0; key != NULL && f < s->n_inputs; f++) {
        if (strcmp(key, s->names[f]) != 0)
            continue;
        if (!(s->available & (1u << f)))
            break;
        if (t->field_node[f] < 0)
            t->field_node[f] = dfle_trace_add_node(L, t, T_IN, f, 0, 0.0, 0);
        dfle_trace_push_node(L, lua_upvalueindex(1), t->field_node[f]);
        return 1;
    }
    return 0;
}

static int c_newindex(lua_State *L)
{
    return dfle_trace_refuse(L, tracer_at(L, lua_upvalueindex(1)), "it assigns to a field of c");
}

/* fn(c, p) or fn(x_1, ..., x_n, p) with nodes: args 1 tracer, 2 fn, 3 p. */
static int trace_main(lua_State *L)
{
    tracer *t = tracer_at(L, 1);
    const dfle_trace_spec *s = t->spec;
    int nargs;

    dfle_trace_node_metatable(L);
    dfle_trace_math_map(L);
    lua_pop(L, 1);
    dfle_trace_close_shared_metatables(L, t, 1);
    dfle_trace_vet_function(L, t, 1, 2, "it");
    lua_pushvalue(L, 2);
    if (s->positional) {
        for (int f = 0; f < s->n_inputs; f++) {
            t->field_node[f] = dfle_trace_add_node(L, t, T_IN, f, 0, 0.0, 0);
            dfle_trace_push_node(L, 1, t->field_node[f]);
        }
        nargs = s->n_inputs + 1;
    } else {
        lua_createtable(L, 0, 0); /* c */
        lua_createtable(L, 0, 2);
        lua_pushvalue(L, 1);
        lua_pushcclosure(L, c_index, 1);
        lua_setfield(L, -2, "__index");
        lua_pushvalue(L, 1);
        lua_pushcclosure(L, c_newindex, 1);
        lua_setfield(L, -2, "__newindex");
        lua_setmetatable(L, -2);
        nargs = 2;
    }
    dfle_trace_push_proxy(L, 1, 3, PROXY_PARAMS); /* p: its reads are guarded too */
    lua_call(L, nargs, 1);
    return 1;
}

/* ---- compile ----------------------------------------------------------- */

/* One trace (dfle_trace_compile), with float params as inputs or as
 * constants; *n_params receives how many it read as inputs. */
static dfle_trace_prog *trace_once(lua_State *L, int fidx, int pidx, const dfle_trace_spec *spec,
                                   int symbolic, int *n_params, char *why, size_t why_len)
{
    tracer *t;
    dfle_trace_prog *p;
    int base, st, result = -1;

    base = lua_gettop(L);
    t = lua_newuserdatauv(L, sizeof *t, N_UV); /* base+1 */
    memset(t, 0, sizeof *t);
    t->spec = spec;
    t->active = 1;
    t->symbolic = symbolic;
    for (int f = 0; f < DFLE_TRACE_MAX_INPUTS; f++)
        t->field_node[f] = -1;
    for (int uv = UV_GUARDS; uv <= N_UV; uv++) {
        lua_createtable(L, 0, 0);
        lua_setiuservalue(L, -2, uv);
    }
    lua_pushcfunction(L, trace_main);
    lua_pushvalue(L, base + 1);
    lua_pushvalue(L, fidx);
    lua_pushvalue(L, pidx);
    st = lua_pcall(L, 3, 1, 0); /* result (or message) at base+2 */

    /* Undo the swaps, last first (a cell swapped twice ends as it began). */
    lua_getiuservalue(L, base + 1, UV_SWAPS);
    for (int j = t->n_swaps - 1; j >= 0; j--) {
        int i;
        lua_rawgeti(L, -1, 3 * j + 2);
        i = (int)lua_tointeger(L, -1);
        lua_pop(L, 1);
        lua_rawgeti(L, -1, 3 * j + 1); /* the function */
        lua_rawgeti(L, -2, 3 * j + 3); /* its original value */
        if (lua_setupvalue(L, -2, i) == NULL)
            lua_pop(L, 1);
        lua_pop(L, 1);
    }
    lua_pop(L, 1);
    dfle_trace_reopen_shared_metatables(L, base + 1);
    t->active = 0;
    *n_params = t->n_params;

    if (st == LUA_OK) {
        node_ud *u = luaL_testudata(L, base + 2, NODE_MT);
        if (u != NULL && u->t == t) {
            result = u->idx;
        } else if (lua_type(L, base + 2) == LUA_TNUMBER && t->n < MAX_NODES) {
            t->node[t->n] = (tnode){.op = T_K, .k = lua_tonumber(L, base + 2)};
            result = t->n++;
        } else {
            snprintf(why, why_len, "it returns a %s, not a number", luaL_typename(L, base + 2));
        }
    } else if (t->why[0] != '\0') {
        snprintf(why, why_len, "%s", t->why);
    } else {
        const char *msg = lua_tostring(L, -1);
        snprintf(why, why_len, "it raised an error when called with symbolic values (%s)",
                 msg != NULL ? msg : "?");
    }
    if (result < 0) {
        lua_settop(L, base);
        lua_pushnil(L);
        return NULL;
    }

    p = calloc(1, sizeof *p);
    if (p != NULL) {
        p->node = malloc((size_t)t->n * sizeof *p->node);
        p->val = malloc((size_t)t->n * sizeof *p->val);
        p->col = malloc((size_t)t->n * sizeof *p->col);
    }
    if (p == NULL || p->node == NULL || p->val == NULL || p->col == NULL) {
        dfle_trace_free(p);
        snprintf(why, why_len, "it could not be stored (out of memory)");
        lua_settop(L, base);
        lua_pushnil(L);
        return NULL;
    }
    p->n = t->n;
    p->result = result;
    p->n_guards = t->n_guards;
    memcpy(p->node, t->node, (size_t)t->n * sizeof *p->node);
    for (int f = 0; f < DFLE_TRACE_MAX_INPUTS; f++) {
        p->in_node[f] = t->field_node[f];
        if (p->in_node[f] >= 0)
            p->inputs |= 1u << f;
    }
    for (int k = 0; k < p->n; k++)
        p->val[k] = T_IS_CONST(p->node[k].op) ? p->node[k].k : 0.0;
    lua_getiuservalue(L, base + 1, UV_GUARDS);
    lua_replace(L, base + 1);
    lua_settop(L, base + 1);
    return p;
}

dfle_trace_prog *dfle_trace_compile(lua_State *L, int fidx, int pidx, const dfle_trace_spec *spec,
                                    char *why, size_t why_len)
{
    dfle_trace_prog *p;
    int n_params = 0, symbolic;

    if (!dfle_trace_release_checked(dfle_trace_release(), why, why_len) ||
        !dfle_trace_vm_ok(L, why, why_len)) {
        lua_pushnil(L); /* this Lua's opcodes and arithmetic are unknown */
        return NULL;
    }
    fidx = lua_absindex(L, fidx);
    pidx = lua_absindex(L, pidx);
    if (!lua_checkstack(L, 40) || spec->n_inputs > DFLE_TRACE_MAX_INPUTS ||
        lua_type(L, fidx) != LUA_TFUNCTION || lua_iscfunction(L, fidx)) {
        snprintf(why, why_len, "it is not a Lua function");
        lua_pushnil(L);
        return NULL;
    }
    /* Code refused with params as inputs before goes straight to
     * constants: one trace per law, not two. */
    symbolic = spec->params_inputs && !dfle_trace_cache_constants_only(L, fidx, spec, 0);
    p = trace_once(L, fidx, pidx, spec, symbolic, &n_params, why, why_len);
    if (p == NULL && n_params > 0) {
        /* Refused with params as inputs, perhaps for what it does with
         * one (compares it, loops to it): params as constants, as they
         * were before programs were shared. */
        lua_pop(L, 1);
        p = trace_once(L, fidx, pidx, spec, 0, &n_params, why, why_len);
        if (p != NULL) {
            dfle_trace_stats *st = dfle_trace_stats_of(L);
            (void)dfle_trace_cache_constants_only(L, fidx, spec, 1);
            if (st != NULL)
                st->retraced++;
        }
    }
    if (p != NULL) {
        dfle_trace_stats *st = dfle_trace_stats_of(L);
        if (st != NULL)
            st->traced++;
    }
    return p;
}
