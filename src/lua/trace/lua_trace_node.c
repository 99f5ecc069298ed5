/*
 * lua_trace_node.c - what the tracer records: the nodes that stand for
 * the flow fields during a trace, whose arithmetic metamethods record an
 * operation and return a new node, and the math functions a compiled
 * law may call, recorded the same way.
 *
 * Every other metamethod of a node refuses the function with the reason
 * (an ordering comparison, indexing, concatenation, ...), and integer
 * arithmetic is refused where a node may hold an integer, since the
 * program computes in doubles (lua_trace.c lists why each case must
 * be closed).  The math functions are recognised by their C address in
 * a fresh luaopen_math table, so a replaced math.sqrt is not trusted.
 */
#include "lua/trace/lua_trace_internal.h"

#include <lauxlib.h>
#include <lualib.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>

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

/* Refuse to compile: remember the first reason and unwind the trace. */
int dfle_trace_refuse(lua_State *L, tracer *t, const char *fmt, ...)
{
    if (t->why[0] == '\0') {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(t->why, sizeof t->why, fmt, ap);
        va_end(ap);
    }
    return luaL_error(L, "dfle: not compilable: %s", t->why);
}

int dfle_trace_add_node(lua_State *L, tracer *t, int op, int a, int b, double k, int maybe_int)
{
    tnode *n;
    if (t->n == MAX_NODES)
        return dfle_trace_refuse(L, t, "it records more than %d operations", MAX_NODES);
    n = &t->node[t->n];
    n->op = (unsigned char)op;
    n->maybe_int = (unsigned char)maybe_int;
    n->a = a, n->b = b, n->k = k;
    return t->n++;
}

/* Push a node object for node `idx`.  Its user value keeps the tracer
 * alive, so a node that outlived its trace still points at memory. */
void dfle_trace_push_node(lua_State *L, int tidx, int idx)
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
            return dfle_trace_refuse(L, t, "it keeps a value from an earlier call");
        return u->idx;
    }
    if (lua_type(L, i) == LUA_TNUMBER) {
        if (lua_isinteger(L, i)) {
            lua_Integer v = lua_tointeger(L, i);
            return dfle_trace_add_node(L, t, T_K, 0, 0, (double)v, 1);
        }
        return dfle_trace_add_node(L, t, T_K, 0, 0, lua_tonumber(L, i), 0);
    }
    return dfle_trace_refuse(L, t, "it uses a %s in %s", luaL_typename(L, i), what);
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
        return dfle_trace_refuse(L, t,
                                 "it may do integer arithmetic ('%s' on the result of math.%s)",
                                 arith_names[op - T_ADD], "max/min/floor/ceil/abs");
    lua_getiuservalue(L, at, 1);
    tidx = lua_gettop(L);
    dfle_trace_push_node(L, tidx, dfle_trace_add_node(L, t, op, a, b, 0.0, 0));
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
    return dfle_trace_refuse(L, t, "%s", what);
}

void dfle_trace_node_metatable(lua_State *L)
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
void dfle_trace_math_map(lua_State *L)
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
int dfle_trace_math_op_of(lua_State *L, int idx)
{
    lua_CFunction fn = lua_tocfunction(L, idx);
    int op;
    if (fn == NULL)
        return 0;
    dfle_trace_math_map(L);
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
int dfle_trace_math_wrapper(lua_State *L)
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
        return dfle_trace_refuse(L, t, "it calls math.%s without arguments", math_name(op));
    a = operand(L, t, 1, "a math function");
    switch (op) {
    case T_LOG:
        if (nargs >= 2 && !lua_isnil(L, 2))
            r = dfle_trace_add_node(L, t, T_LOGB, a, operand(L, t, 2, "math.log"), 0, 0);
        else
            r = dfle_trace_add_node(L, t, T_LOG, a, a, 0, 0);
        break;
    case T_ATAN:
        b = nargs >= 2 && !lua_isnil(L, 2) ? operand(L, t, 2, "math.atan")
                                            : dfle_trace_add_node(L, t, T_K, 0, 0, 1.0, 0);
        r = dfle_trace_add_node(L, t, T_ATAN, a, b, 0, 0);
        break;
    case T_FMOD:
        b = operand(L, t, 2, "math.fmod");
        if (t->node[a].maybe_int && t->node[b].maybe_int)
            return dfle_trace_refuse(L, t, "it may do integer arithmetic (math.fmod)");
        r = dfle_trace_add_node(L, t, T_FMOD, a, b, 0, 0);
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
                return dfle_trace_refuse(L, t, "it compares with an integer beyond 2^53");
            mi |= t->node[b].maybe_int;
            r = dfle_trace_add_node(L, t, op, r, b, 0, mi);
        }
        break;
    case T_FLOOR:
    case T_CEIL:
        r = dfle_trace_add_node(L, t, op, a, a, 0, 1); /* an integer when it fits */
        break;
    case T_ABS:
        r = dfle_trace_add_node(L, t, op, a, a, 0, t->node[a].maybe_int);
        break;
    default:
        r = dfle_trace_add_node(L, t, op, a, a, 0, 0);
        break;
    }
    lua_getiuservalue(L, at, 1);
    tidx = lua_gettop(L);
    dfle_trace_push_node(L, tidx, r);
    return 1;
}
