/*
 * lua_trace.c - the tracer behind compiled Lua laws (lua_trace.h).
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
 * lua_trace_eval.c runs a record and checks its guards;
 * lua_trace_bytecode.c does the bytecode scan; lua_trace_release.c
 * lists the Lua releases all this was checked against (under any other
 * nothing is compiled).
 */
#include "lua/trace/lua_trace_internal.h"

#include <lauxlib.h>
#include <lualib.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_NODES 1024 /* operations a compiled function may record    */
#define MAX_GUARDS 256 /* outside values it may read                   */
#define MAX_DEPTH 8    /* helper functions calling helper functions    */

/* The trace in progress: a userdata with user values 1 = guards table,
 * 2 = swaps table, 3 = cache (vetted functions, proxies), 4 = the original
 * of each stand-in (an upvalue cell shared by two functions already holds
 * one when the second is vetted), 5 = the node of each param read as an
 * input (key -> node index). */
typedef struct tracer {
    int active;
    int n;
    int n_guards, n_swaps, depth;
    int symbolic; /* float params are inputs (T_PARAM), not constants */
    int n_params; /* params read as inputs                           */
    const dfle_trace_spec *spec;
    int field_node[DFLE_TRACE_MAX_INPUTS];
    char why[160];
    tnode node[MAX_NODES];
} tracer;

enum { UV_GUARDS = 1, UV_SWAPS, UV_CACHE, UV_ORIG, UV_PARAMS, N_UV = UV_PARAMS };

typedef struct { tracer *t; int idx; } node_ud;

static const char NODE_MT[] = "dfle.trace.node";
static const char mathfn_key = 0; /* registry: C address -> T_ op     */

/* The math functions a compiled law may call. */
static const struct { const char *name; int op; } math_fns[] = {
    {"sqrt", T_SQRT}, {"exp", T_EXP}, {"log", T_LOG}, {"abs", T_ABS}, {"floor", T_FLOOR},
    {"ceil", T_CEIL}, {"fmod", T_FMOD}, {"max", T_MAX}, {"min", T_MIN}, {"sin", T_SIN},
    {"cos", T_COS}, {"tan", T_TAN}, {"asin", T_ASIN}, {"acos", T_ACOS}, {"atan", T_ATAN},
    {"deg", T_DEG}, {"rad", T_RAD},
};
#define N_MATH_FNS (sizeof math_fns / sizeof math_fns[0])

/* ---- recording --------------------------------------------------------- */

static tracer *tracer_at(lua_State *L, int idx) { return lua_touserdata(L, idx); }

/* Refuse to compile: remember the first reason and unwind the trace. */
static int refuse(lua_State *L, tracer *t, const char *fmt, ...)
{
    if (t->why[0] == '\0') {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(t->why, sizeof t->why, fmt, ap);
        va_end(ap);
    }
    return luaL_error(L, "dfle: not compilable: %s", t->why);
}

static int add_node(lua_State *L, tracer *t, int op, int a, int b, double k, int maybe_int)
{
    tnode *n;
    if (t->n == MAX_NODES)
        return refuse(L, t, "it records more than %d operations", MAX_NODES);
    n = &t->node[t->n];
    n->op = (unsigned char)op;
    n->maybe_int = (unsigned char)maybe_int;
    n->a = a, n->b = b, n->k = k;
    return t->n++;
}

/* Push a node object for node `idx`.  Its user value keeps the tracer
 * alive, so a node that outlived its trace still points at memory. */
static void push_node(lua_State *L, int tidx, int idx)
{
    node_ud *u = lua_newuserdatauv(L, sizeof *u, 1);
    u->t = tracer_at(L, tidx);
    u->idx = idx;
    lua_pushvalue(L, tidx);
    lua_setiuservalue(L, -2, 1);
    luaL_setmetatable(L, NODE_MT);
}

/* The node index of operand `i`: a node, or a number made a constant. */
static int operand(lua_State *L, tracer *t, int i, const char *what)
{
    node_ud *u = luaL_testudata(L, i, NODE_MT);
    if (u != NULL) {
        if (u->t != t || !t->active)
            return refuse(L, t, "it keeps a value from an earlier call");
        return u->idx;
    }
    if (lua_type(L, i) == LUA_TNUMBER) {
        if (lua_isinteger(L, i)) {
            lua_Integer v = lua_tointeger(L, i);
            return add_node(L, t, T_K, 0, 0, (double)v, 1);
        }
        return add_node(L, t, T_K, 0, 0, lua_tonumber(L, i), 0);
    }
    return refuse(L, t, "it uses a %s in %s", luaL_typename(L, i), what);
}

/* The tracer of whichever argument in [1, n] is a node, or NULL. */
static int first_node_arg(lua_State *L, int n)
{
    for (int i = 1; i <= n; i++)
        if (luaL_testudata(L, i, NODE_MT) != NULL)
            return i;
    return 0;
}

static const char *const arith_names[] = {"+", "-", "*", "/", "%", "//", "^", "unary -"};

/* __add and friends: upvalue 1 is the T_ op. */
static int node_arith(lua_State *L)
{
    const int op = (int)lua_tointeger(L, lua_upvalueindex(1));
    const int at = first_node_arg(L, 2);
    node_ud *u;
    tracer *t;
    int a;
    if (at == 0) /* only if someone dug the metatable out of the registry */
        return luaL_error(L, "dfle: not a traced value");
    u = lua_touserdata(L, at);
    t = u->t;
    a = operand(L, t, 1, arith_names[op - T_ADD]);
    int b = op == T_UNM ? a : operand(L, t, 2, arith_names[op - T_ADD]);
    int tidx;
    /* + - * // % and unary minus are integer operations when both sides
     * are integers; a node that may hold one (math.max(x, 0)) must not
     * meet another here, since the program computes in doubles. */
    if (op != T_DIV && op != T_POW && t->node[a].maybe_int && t->node[b].maybe_int)
        return refuse(L, t, "it may do integer arithmetic ('%s' on the result of math.%s)",
                      arith_names[op - T_ADD], "max/min/floor/ceil/abs");
    lua_getiuservalue(L, at, 1);
    tidx = lua_gettop(L);
    push_node(L, tidx, add_node(L, t, op, a, b, 0.0, 0));
    return 1;
}

/* Every other metamethod: a node cannot be compared, indexed, ... */
static int node_refuse(lua_State *L)
{
    const char *what = lua_tostring(L, lua_upvalueindex(1));
    const int at = first_node_arg(L, lua_gettop(L) < 2 ? lua_gettop(L) : 2);
    tracer *t = at ? ((node_ud *)lua_touserdata(L, at))->t : NULL;
    if (t == NULL)
        return luaL_error(L, "dfle: not compilable: %s", what);
    return refuse(L, t, "%s", what);
}

static void node_metatable(lua_State *L)
{
    static const char *const arith_events[] = {"__add", "__sub", "__mul", "__div",
                                               "__mod", "__idiv", "__pow", "__unm"};
    static const int arith_ops[] = {T_ADD, T_SUB, T_MUL, T_DIV, T_MOD, T_IDIV, T_POW, T_UNM};
    static const char *const other[][2] = {
        {"__lt", "it compares a flow field with '<', '<=', '>' or '>='"},
        {"__le", "it compares a flow field with '<', '<=', '>' or '>='"},
        {"__eq", "it compares two flow fields with '=='"},
        {"__concat", "it uses a flow field as a string"},
        {"__len", "it takes the length of a flow field"},
        {"__call", "it calls a flow field"},
        {"__index", "it indexes a flow field"},
        {"__newindex", "it indexes a flow field"},
        {"__band", "it uses a flow field in a bitwise operation"},
        {"__bor", "it uses a flow field in a bitwise operation"},
        {"__bxor", "it uses a flow field in a bitwise operation"},
        {"__shl", "it uses a flow field in a bitwise operation"},
        {"__shr", "it uses a flow field in a bitwise operation"},
        {"__bnot", "it uses a flow field in a bitwise operation"},
        {"__close", "it uses a flow field as a to-be-closed variable"},
    };
    if (!luaL_newmetatable(L, NODE_MT))
        return;
    for (size_t i = 0; i < sizeof arith_ops / sizeof arith_ops[0]; i++) {
        lua_pushinteger(L, arith_ops[i]);
        lua_pushcclosure(L, node_arith, 1);
        lua_setfield(L, -2, arith_events[i]);
    }
    for (size_t i = 0; i < sizeof other / sizeof other[0]; i++) {
        lua_pushstring(L, other[i][1]);
        lua_pushcclosure(L, node_refuse, 1);
        lua_setfield(L, -2, other[i][0]);
    }
    lua_pop(L, 1);
}

/* ---- math functions ---------------------------------------------------- */

/* registry[mathfn_key]: light userdata (C address) -> T_ op, from a fresh
 * math table, so only the genuine functions are recognised. */
static void math_map(lua_State *L)
{
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &mathfn_key) == LUA_TTABLE)
        return;
    lua_pop(L, 1);
    lua_newtable(L);
    lua_pushcfunction(L, luaopen_math);
    lua_call(L, 0, 1);
    for (size_t i = 0; i < N_MATH_FNS; i++) {
        lua_CFunction fn;
        lua_getfield(L, -1, math_fns[i].name);
        fn = lua_tocfunction(L, -1);
        lua_pop(L, 1);
        if (fn == NULL)
            continue;
        lua_pushinteger(L, math_fns[i].op);
        lua_rawsetp(L, -3, (void *)(uintptr_t)fn);
    }
    lua_pop(L, 1);
    lua_pushvalue(L, -1);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &mathfn_key);
}

/* The T_ op of the C function at idx, or 0. */
static int math_op_of(lua_State *L, int idx)
{
    lua_CFunction fn = lua_tocfunction(L, idx);
    int op;
    if (fn == NULL)
        return 0;
    math_map(L);
    lua_rawgetp(L, -1, (void *)(uintptr_t)fn);
    op = (int)lua_tointeger(L, -1);
    lua_pop(L, 2);
    return op;
}

static const char *math_name(int op)
{
    for (size_t i = 0; i < N_MATH_FNS; i++)
        if (math_fns[i].op == op)
            return math_fns[i].name;
    return "?";
}

/* A math function during a trace: upvalue 1 = the T_ op, 2 = the real
 * function (called as is when no argument is a node). */
static int math_wrapper(lua_State *L)
{
    const int op = (int)lua_tointeger(L, lua_upvalueindex(1));
    const int nargs = lua_gettop(L);
    const int at = first_node_arg(L, nargs);
    tracer *t;
    int a, b = 0, tidx, r, mi = 0;

    if (at == 0) { /* constants only: exactly what Lua does */
        lua_pushvalue(L, lua_upvalueindex(2));
        lua_insert(L, 1);
        lua_call(L, nargs, LUA_MULTRET);
        return lua_gettop(L);
    }
    t = ((node_ud *)lua_touserdata(L, at))->t;
    if (nargs < 1)
        return refuse(L, t, "it calls math.%s without arguments", math_name(op));
    a = operand(L, t, 1, "a math function");
    switch (op) {
    case T_LOG:
        if (nargs >= 2 && !lua_isnil(L, 2))
            r = add_node(L, t, T_LOGB, a, operand(L, t, 2, "math.log"), 0, 0);
        else
            r = add_node(L, t, T_LOG, a, a, 0, 0);
        break;
    case T_ATAN:
        b = nargs >= 2 && !lua_isnil(L, 2) ? operand(L, t, 2, "math.atan")
                                            : add_node(L, t, T_K, 0, 0, 1.0, 0);
        r = add_node(L, t, T_ATAN, a, b, 0, 0);
        break;
    case T_FMOD:
        b = operand(L, t, 2, "math.fmod");
        if (t->node[a].maybe_int && t->node[b].maybe_int)
            return refuse(L, t, "it may do integer arithmetic (math.fmod)");
        r = add_node(L, t, T_FMOD, a, b, 0, 0);
        break;
    case T_MAX:
    case T_MIN:
        /* Left to right, as math.max/min compare; an integer bound may be
         * the result, so the node may hold an integer. */
        r = a;
        mi = t->node[a].maybe_int;
        for (int i = 2; i <= nargs; i++) {
            b = operand(L, t, i, op == T_MAX ? "math.max" : "math.min");
            if (t->node[b].op == T_K && t->node[b].maybe_int && fabs(t->node[b].k) > 9007199254740992.0)
                return refuse(L, t, "it compares with an integer beyond 2^53");
            mi |= t->node[b].maybe_int;
            r = add_node(L, t, op, r, b, 0, mi);
        }
        break;
    case T_FLOOR:
    case T_CEIL:
        r = add_node(L, t, op, a, a, 0, 1); /* an integer when it fits */
        break;
    case T_ABS:
        r = add_node(L, t, op, a, a, 0, t->node[a].maybe_int);
        break;
    default:
        r = add_node(L, t, op, a, a, 0, 0);
        break;
    }
    lua_getiuservalue(L, at, 1);
    tidx = lua_gettop(L);
    push_node(L, tidx, r);
    return 1;
}

/* ---- outside values ---------------------------------------------------- */

static void add_guard(lua_State *L, tracer *t, int tidx, int kind, int container, int key,
                      int value)
{
    int n;
    if (t->n_guards == MAX_GUARDS)
        refuse(L, t, "it reads more than %d outside values", MAX_GUARDS);
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

static void vet_function(lua_State *L, tracer *t, int tidx, int fidx, const char *what);

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
            refuse(L, t, "it reads the table %s (only numbers, strings, booleans, math and "
                         "functions can be compiled)", what);
        push_table_proxy(L, tidx, idx, 1);
        lua_replace(L, idx);
        return;
    case LUA_TFUNCTION:
        if (lua_iscfunction(L, idx)) {
            int op = math_op_of(L, idx);
            if (op == 0)
                refuse(L, t, "it calls %s, a C function other than the math ones", what);
            lua_pushinteger(L, op);
            lua_pushvalue(L, idx);
            lua_pushcclosure(L, math_wrapper, 2);
            remember_original(L, tidx, -1, idx);
            lua_replace(L, idx);
        } else {
            vet_function(L, t, tidx, idx, what);
        }
        return;
    default:
        refuse(L, t, "it reads %s, a %s", what, luaL_typename(L, idx));
    }
}

/* What a proxy stands for, and how names read from it are reported. */
enum { PROXY_ENV, PROXY_MATH, PROXY_PARAMS };
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
        node = add_node(L, t, T_PARAM, t->n_params, 0, lua_tonumber(L, 3), 0);
        lua_pushinteger(L, node); /* 6 */
        add_guard(L, t, lua_upvalueindex(1), G_PARAM, lua_upvalueindex(2), 2, 6);
        lua_pushvalue(L, 2);
        lua_pushinteger(L, node);
        lua_rawset(L, 4);
        t->n_params++;
    }
    push_node(L, lua_upvalueindex(1), node);
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
        return refuse(L, t, "it indexes %s with a computed value", proxy_table[kind]);
    lua_pushvalue(L, 2);
    lua_rawget(L, lua_upvalueindex(2)); /* 3: the real value */
    snprintf(what, sizeof what, "%s%s%s", proxy_prefix[kind],
             lua_type(L, 2) == LUA_TSTRING ? lua_tostring(L, 2) : "?", proxy_suffix[kind]);
    /* A metatable (strict.lua, say) is consulted only for absent keys,
     * so a present value is what the function reads; an absent one may
     * not be nil for it. */
    if (lua_isnil(L, 3) && lua_getmetatable(L, lua_upvalueindex(2)))
        return refuse(L, t, "it reads %s, which is not set, from a table with a metatable", what);
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
    return refuse(L, t, "it assigns to %s%s%s (a side effect)", proxy_prefix[kind],
                  lua_type(L, 2) == LUA_TSTRING ? lua_tostring(L, 2) : "?", proxy_suffix[kind]);
}

/* __len of a proxy: upvalues 1 = tracer, 2 = its PROXY_ kind.  The proxy
 * itself is empty, and the real table's length is a value no guard would
 * watch. */
static int proxy_len(lua_State *L)
{
    tracer *t = tracer_at(L, lua_upvalueindex(1));
    return refuse(L, t, "it takes the length of %s",
                  proxy_table[lua_tointeger(L, lua_upvalueindex(2))]);
}

/* Push a new proxy of the table at `real`. */
static void push_proxy(lua_State *L, int tidx, int real, int kind)
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
    push_proxy(L, tidx, real, is_math ? PROXY_MATH : PROXY_ENV);
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
static void vet_function(lua_State *L, tracer *t, int tidx, int fidx, const char *what)
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
        refuse(L, t, "it calls functions nested more than %d deep", MAX_DEPTH);
    found = dfle_trace_scan(L, fidx);
    if (found & FOUND_EQ)
        refuse(L, t, "%s uses '==' or '~=' (an equality test on a flow field cannot be "
                     "recorded)", what);
    if (found & FOUND_SETUPVAL)
        refuse(L, t, "%s assigns to an upvalue (a side effect)", what);
    if (found & FOUND_BAD)
        refuse(L, t, "%s has bytecode this build does not know", what);
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
                refuse(L, t, "%s has an _ENV that is not a table", what);
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
            t->field_node[f] = add_node(L, t, T_IN, f, 0, 0.0, 0);
        push_node(L, lua_upvalueindex(1), t->field_node[f]);
        return 1;
    }
    return 0;
}

static int c_newindex(lua_State *L)
{
    return refuse(L, tracer_at(L, lua_upvalueindex(1)), "it assigns to a field of c");
}

/* Strings' __index during a trace: upvalue 1 = the tracer. */
static int string_method(lua_State *L)
{
    return refuse(L, tracer_at(L, lua_upvalueindex(1)),
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

static void close_shared_metatables(lua_State *L, tracer *t, int tidx)
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
            refuse(L, t, "%s have a metatable (debug.setmetatable), which a trace cannot follow",
                   what[k]);
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
static void reopen_shared_metatables(lua_State *L, int tidx)
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

/* fn(c, p) or fn(x_1, ..., x_n, p) with nodes: args 1 tracer, 2 fn, 3 p. */
static int trace_main(lua_State *L)
{
    tracer *t = tracer_at(L, 1);
    const dfle_trace_spec *s = t->spec;
    int nargs;

    node_metatable(L);
    math_map(L);
    lua_pop(L, 1);
    close_shared_metatables(L, t, 1);
    vet_function(L, t, 1, 2, "it");
    lua_pushvalue(L, 2);
    if (s->positional) {
        for (int f = 0; f < s->n_inputs; f++) {
            t->field_node[f] = add_node(L, t, T_IN, f, 0, 0.0, 0);
            push_node(L, 1, t->field_node[f]);
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
    push_proxy(L, 1, 3, PROXY_PARAMS); /* p: its reads are guarded too */
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
    reopen_shared_metatables(L, base + 1);
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
    int n_params = 0;

    if (!dfle_trace_release_checked(dfle_trace_release(), why, why_len)) {
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
    p = trace_once(L, fidx, pidx, spec, spec->params_inputs, &n_params, why, why_len);
    if (p == NULL && n_params > 0) {
        /* Refused with params as inputs, perhaps for what it does with
         * one (compares it, loops to it): params as constants, as they
         * were before programs were shared. */
        lua_pop(L, 1);
        p = trace_once(L, fidx, pidx, spec, 0, &n_params, why, why_len);
    }
    if (p != NULL) {
        dfle_trace_stats *st = dfle_trace_stats_of(L);
        if (st != NULL)
            st->traced++;
    }
    return p;
}
