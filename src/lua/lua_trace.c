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
 *    recorded as guards the caller re-checks (lua_trace.h);
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
 */
#include "lua_trace.h"

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

/* Node operations.  T_IN and T_K hold values set before evaluation. */
enum {
    T_IN, T_K,
    T_ADD, T_SUB, T_MUL, T_DIV, T_MOD, T_IDIV, T_POW, T_UNM,
    T_SQRT, T_EXP, T_LOG, T_LOGB, T_ABS, T_FLOOR, T_CEIL, T_FMOD, T_MAX, T_MIN,
    T_SIN, T_COS, T_TAN, T_ASIN, T_ACOS, T_ATAN, T_DEG, T_RAD
};

typedef struct tnode {
    unsigned char op;
    unsigned char maybe_int; /* may hold a Lua integer (see above) */
    int a, b;                /* operand nodes; for T_IN, a is the input */
    double k;                /* T_K's value */
} tnode;

struct dfle_trace_prog {
    int n, result, n_guards;
    unsigned inputs;
    int in_node[DFLE_TRACE_MAX_INPUTS];
    tnode *node;
    double *val;          /* dfle_trace_eval's values, one per node    */
    const double **col;   /* dfle_trace_eval_n's columns, one per node */
    double *work;         /* their storage: (n + 1) x cap              */
    size_t cap;
};

/* The trace in progress: a userdata with user values 1 = guards table,
 * 2 = swaps table, 3 = cache (vetted functions, proxies), 4 = the original
 * of each stand-in (an upvalue cell shared by two functions already holds
 * one when the second is vetted). */
typedef struct tracer {
    int active;
    int n;
    int n_guards, n_swaps, depth;
    const dfle_trace_spec *spec;
    int field_node[DFLE_TRACE_MAX_INPUTS];
    char why[160];
    tnode node[MAX_NODES];
} tracer;

enum { UV_GUARDS = 1, UV_SWAPS, UV_CACHE, UV_ORIG, N_UV = UV_ORIG };
enum { G_FIELD = 1, G_UPVALUE = 2 };

typedef struct { tracer *t; int idx; } node_ud;

static const char NODE_MT[] = "dfle.trace.node";
static const char nil_marker = 0; /* a guard's nil value, by address */
static const char mathfn_key = 0; /* registry: C address -> T_ op     */

/* The math functions a compiled law may call. */
static const struct { const char *name; int op; } math_fns[] = {
    {"sqrt", T_SQRT}, {"exp", T_EXP}, {"log", T_LOG}, {"abs", T_ABS}, {"floor", T_FLOOR},
    {"ceil", T_CEIL}, {"fmod", T_FMOD}, {"max", T_MAX}, {"min", T_MIN}, {"sin", T_SIN},
    {"cos", T_COS}, {"tan", T_TAN}, {"asin", T_ASIN}, {"acos", T_ACOS}, {"atan", T_ATAN},
    {"deg", T_DEG}, {"rad", T_RAD},
};
#define N_MATH_FNS (sizeof math_fns / sizeof math_fns[0])

/* lmathlib's PI, so deg/rad scale exactly as Lua does. */
#define LUA_PI 3.141592653589793238462643383279502884

/* ---- evaluation -------------------------------------------------------- */

static double apply(int op, double a, double b)
{
    double m;
    switch (op) {
    case T_ADD: return a + b;
    case T_SUB: return a - b;
    case T_MUL: return a * b;
    case T_DIV: return a / b;
    case T_MOD: /* luai_nummod: the result takes the divisor's sign */
        m = fmod(a, b);
        if ((m > 0) ? b < 0 : (m < 0 && b != m))
            m += b;
        return m;
    case T_IDIV: return floor(a / b);
    case T_POW: /* luai_numpow; x^1 is x exactly in any pow within an ulp */
        return b == 2 ? a * a : b == 1 ? a : pow(a, b);
    case T_UNM: return -a;
    case T_SQRT: return sqrt(a);
    case T_EXP: return exp(a);
    case T_LOG: return log(a);
    case T_LOGB: return b == 2.0 ? log2(a) : b == 10.0 ? log10(a) : log(a) / log(b);
    case T_ABS: return fabs(a);
    case T_FLOOR: return floor(a);
    case T_CEIL: return ceil(a);
    case T_FMOD: return fmod(a, b);
    case T_MAX: return a < b ? b : a; /* math.max keeps the first of equals */
    case T_MIN: return b < a ? b : a;
    case T_SIN: return sin(a);
    case T_COS: return cos(a);
    case T_TAN: return tan(a);
    case T_ASIN: return asin(a);
    case T_ACOS: return acos(a);
    case T_ATAN: return atan2(a, b);
    case T_DEG: return a * (180.0 / LUA_PI);
    case T_RAD: return a * (LUA_PI / 180.0);
    default: return NAN;
    }
}

double dfle_trace_eval(dfle_trace_prog *p, const double *in)
{
    double *v = p->val;
    for (int f = 0; f < DFLE_TRACE_MAX_INPUTS; f++)
        if (p->in_node[f] >= 0)
            v[p->in_node[f]] = in[f];
    for (int k = 0; k < p->n; k++) {
        const tnode *t = &p->node[k];
        if (t->op > T_K)
            v[k] = apply(t->op, v[t->a], v[t->b]);
    }
    return v[p->result];
}

/* Column by column: each operation runs as one tight loop over the
 * points, which is what makes a whole sweep cost about what a built-in
 * law costs.  K columns are filled when the workspace grows. */
const double *dfle_trace_eval_n(dfle_trace_prog *p, size_t n, const double *const *in)
{
    const double **col = p->col;
    if (n > p->cap) {
        size_t cap = n > 2 * p->cap ? n : 2 * p->cap;
        double *w = malloc((size_t)(p->n + 1) * cap * sizeof *w);
        if (w == NULL)
            return NULL;
        free(p->work);
        p->work = w;
        p->cap = cap;
        for (int k = 0; k < p->n; k++)
            if (p->node[k].op == T_K)
                for (size_t i = 0; i < cap; i++)
                    w[(size_t)k * cap + i] = p->node[k].k;
        for (size_t i = 0; i < cap; i++)
            w[(size_t)p->n * cap + i] = 0.0; /* the column of an absent input */
    }
    for (int k = 0; k < p->n; k++) {
        const tnode *t = &p->node[k];
        double *r = p->work + (size_t)k * p->cap;
        const double *a, *b;
        if (t->op == T_IN) {
            col[k] = in[t->a] != NULL ? in[t->a] : p->work + (size_t)p->n * p->cap;
            continue;
        }
        col[k] = r;
        if (t->op == T_K)
            continue;
        a = col[t->a], b = col[t->b];
        switch (t->op) {
        case T_ADD: for (size_t i = 0; i < n; i++) r[i] = a[i] + b[i]; break;
        case T_SUB: for (size_t i = 0; i < n; i++) r[i] = a[i] - b[i]; break;
        case T_MUL: for (size_t i = 0; i < n; i++) r[i] = a[i] * b[i]; break;
        case T_DIV: for (size_t i = 0; i < n; i++) r[i] = a[i] / b[i]; break;
        default: for (size_t i = 0; i < n; i++) r[i] = apply(t->op, a[i], b[i]); break;
        }
    }
    return col[p->result];
}

unsigned dfle_trace_inputs(const dfle_trace_prog *p) { return p->inputs; }

void dfle_trace_free(dfle_trace_prog *p)
{
    if (p == NULL)
        return;
    free(p->node);
    free(p->val);
    free(p->col);
    free(p->work);
    free(p);
}

/* ---- guards ------------------------------------------------------------ */

/* Same value, as a compiled program sees it: numbers must agree in
 * subtype and bits (NaN equals itself), others must be the same object. */
static int same_value(lua_State *L, int a, int b)
{
    if (lua_type(L, a) == LUA_TNUMBER && lua_type(L, b) == LUA_TNUMBER) {
        double x, y;
        if (lua_isinteger(L, a) != lua_isinteger(L, b))
            return 0;
        if (lua_isinteger(L, a))
            return lua_tointeger(L, a) == lua_tointeger(L, b);
        x = lua_tonumber(L, a), y = lua_tonumber(L, b);
        return memcmp(&x, &y, sizeof x) == 0;
    }
    if (lua_touserdata(L, b) == (void *)&nil_marker)
        return lua_isnil(L, a);
    return lua_rawequal(L, a, b);
}

int dfle_trace_guards_hold(lua_State *L, int gidx, const dfle_trace_prog *p)
{
    int ok = 1;
    gidx = lua_absindex(L, gidx);
    if (!lua_checkstack(L, 8) || !lua_istable(L, gidx))
        return 0;
    for (int j = 0; ok && j < p->n_guards; j++) {
        int top = lua_gettop(L);
        lua_rawgeti(L, gidx, 4 * j + 1); /* kind      top+1 */
        lua_rawgeti(L, gidx, 4 * j + 2); /* container top+2 */
        lua_rawgeti(L, gidx, 4 * j + 3); /* key       top+3 */
        lua_rawgeti(L, gidx, 4 * j + 4); /* value     top+4 */
        if (lua_tointeger(L, top + 1) == G_FIELD) {
            lua_pushvalue(L, top + 3);
            lua_rawget(L, top + 2);
        } else if (lua_getupvalue(L, top + 2, (int)lua_tointeger(L, top + 3)) == NULL) {
            lua_pushnil(L);
        }
        ok = same_value(L, top + 5, top + 4);
        lua_settop(L, top);
    }
    return ok;
}

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
        lua_pushlightuserdata(L, (void *)&nil_marker);
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
static const char *const proxy_suffix[] = {"'", "", ""};

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
    lua_pushvalue(L, 2);
    lua_rawget(L, lua_upvalueindex(2)); /* 3: the real value */
    snprintf(what, sizeof what, "%s%s%s", proxy_prefix[kind],
             lua_type(L, 2) == LUA_TSTRING ? lua_tostring(L, 2) : "?", proxy_suffix[kind]);
    /* A metatable (strict.lua, say) is consulted only for absent keys,
     * so a present value is what the function reads; an absent one may
     * not be nil for it. */
    if (lua_isnil(L, 3) && lua_getmetatable(L, lua_upvalueindex(2)))
        return refuse(L, t, "it reads %s, which is not set, from a table with a metatable", what);
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

/* Push a new proxy of the table at `real`. */
static void push_proxy(lua_State *L, int tidx, int real, int kind)
{
    real = lua_absindex(L, real);
    lua_createtable(L, 0, 0);
    lua_createtable(L, 0, 2);
    lua_pushvalue(L, tidx);
    lua_pushvalue(L, real);
    lua_pushinteger(L, kind);
    lua_pushcclosure(L, proxy_index, 3);
    lua_setfield(L, -2, "__index");
    lua_pushvalue(L, tidx);
    lua_pushinteger(L, kind);
    lua_pushcclosure(L, proxy_newindex, 2);
    lua_setfield(L, -2, "__newindex");
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

/* ---- bytecode ---------------------------------------------------------- */

/* Lua 5.4 opcodes the scan refuses (lopcodes.h order, stable in 5.4). */
enum { OP_SETUPVAL = 10, OP_EQ = 57, OP_EQK = 60, OP_EQI = 61 };
enum { FOUND_EQ = 1, FOUND_SETUPVAL = 2, FOUND_BAD = 4 };

typedef struct { const unsigned char *p, *end; int bad; } reader;

static size_t rd_size(reader *r)
{
    size_t x = 0;
    for (int i = 0; i < 10; i++) {
        unsigned b;
        if (r->p >= r->end)
            break;
        b = *r->p++;
        x = (x << 7) | (b & 0x7f);
        if (b & 0x80)
            return x;
    }
    r->bad = 1;
    return 0;
}

static void rd_skip(reader *r, size_t n)
{
    if ((size_t)(r->end - r->p) < n) {
        r->bad = 1;
        r->p = r->end;
    } else {
        r->p += n;
    }
}

static void rd_string(reader *r)
{
    size_t n = rd_size(r);
    if (n > 0)
        rd_skip(r, n - 1);
}

/* One function of a binary chunk (ldump.c's layout) and its nested ones. */
static unsigned scan_function(reader *r, int depth)
{
    unsigned found = 0;
    size_t n;
    if (depth > 64)
        return FOUND_BAD;
    rd_string(r); /* source */
    rd_size(r);   /* linedefined */
    rd_size(r);   /* lastlinedefined */
    rd_skip(r, 3); /* numparams, is_vararg, maxstacksize */
    n = rd_size(r);
    for (size_t i = 0; i < n && !r->bad; i++) {
        uint32_t ins;
        if (r->end - r->p < 4) {
            r->bad = 1;
            break;
        }
        memcpy(&ins, r->p, 4);
        r->p += 4;
        switch (ins & 0x7f) {
        case OP_EQ: case OP_EQK: case OP_EQI: found |= FOUND_EQ; break;
        case OP_SETUPVAL: found |= FOUND_SETUPVAL; break;
        default: break;
        }
    }
    n = rd_size(r); /* constants */
    for (size_t i = 0; i < n && !r->bad; i++) {
        unsigned tag = r->p < r->end ? *r->p++ : (r->bad = 1, 0u);
        if (tag == 0x03 || tag == 0x13)
            rd_skip(r, 8);
        else if (tag == 0x04 || tag == 0x14)
            rd_string(r);
        else if (tag != 0x00 && tag != 0x01 && tag != 0x11)
            r->bad = 1;
    }
    rd_skip(r, 3 * rd_size(r)); /* upvalue descriptions */
    n = rd_size(r);             /* nested functions */
    for (size_t i = 0; i < n && !r->bad; i++)
        found |= scan_function(r, depth + 1);
    rd_skip(r, rd_size(r)); /* line info */
    n = rd_size(r);         /* absolute line info */
    for (size_t i = 0; i < n && !r->bad; i++)
        rd_size(r), rd_size(r);
    n = rd_size(r); /* local variables */
    for (size_t i = 0; i < n && !r->bad; i++)
        rd_string(r), rd_size(r), rd_size(r);
    n = rd_size(r); /* upvalue names */
    for (size_t i = 0; i < n && !r->bad; i++)
        rd_string(r);
    return r->bad ? found | FOUND_BAD : found;
}

typedef struct { luaL_Buffer b; int init; } dump_state;

static int dump_writer(lua_State *L, const void *p, size_t sz, void *ud)
{
    dump_state *d = ud;
    if (!d->init) { /* after lua_dump has the function: the buffer may push */
        d->init = 1;
        luaL_buffinit(L, &d->b);
    }
    luaL_addlstring(&d->b, p, sz);
    return 0;
}

/* Scan the Lua function at fidx. */
static unsigned scan_bytecode(lua_State *L, int fidx)
{
    static const unsigned char header[] = {0x1b, 'L', 'u', 'a', 0x54, 0x00, 0x19, 0x93,
                                           '\r', '\n', 0x1a, '\n', 4};
    dump_state d;
    reader r;
    size_t len;
    unsigned found;

    d.init = 0;
    lua_pushvalue(L, fidx);
    lua_dump(L, dump_writer, &d, 0);
    if (!d.init) {
        lua_pop(L, 1);
        return FOUND_BAD;
    }
    luaL_pushresult(&d.b);
    r.p = (const unsigned char *)lua_tolstring(L, -1, &len);
    r.end = r.p + len;
    r.bad = 0;
    if (len < sizeof header + 2 || memcmp(r.p, header, sizeof header) != 0) {
        lua_pop(L, 2);
        return FOUND_BAD;
    }
    r.p += sizeof header;
    rd_skip(&r, 2);                              /* sizes of lua_Integer, lua_Number */
    rd_skip(&r, (size_t)r.p[-2] + r.p[-1] + 1); /* LUAC_INT, LUAC_NUM, sizeupvalues */
    found = scan_function(&r, 0);
    lua_pop(L, 2);
    return found;
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
    found = scan_bytecode(L, fidx);
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

/* fn(c, p) or fn(x_1, ..., x_n, p) with nodes: args 1 tracer, 2 fn, 3 p. */
static int trace_main(lua_State *L)
{
    tracer *t = tracer_at(L, 1);
    const dfle_trace_spec *s = t->spec;
    int nargs;

    node_metatable(L);
    math_map(L);
    lua_pop(L, 1);
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

dfle_trace_prog *dfle_trace_compile(lua_State *L, int fidx, int pidx, const dfle_trace_spec *spec,
                                    char *why, size_t why_len)
{
    tracer *t;
    dfle_trace_prog *p;
    int base, st, result = -1;

    fidx = lua_absindex(L, fidx);
    pidx = lua_absindex(L, pidx);
    if (!lua_checkstack(L, 40) || spec->n_inputs > DFLE_TRACE_MAX_INPUTS ||
        lua_type(L, fidx) != LUA_TFUNCTION || lua_iscfunction(L, fidx)) {
        snprintf(why, why_len, "it is not a Lua function");
        lua_pushnil(L);
        return NULL;
    }
    base = lua_gettop(L);
    t = lua_newuserdatauv(L, sizeof *t, N_UV); /* base+1 */
    memset(t, 0, sizeof *t);
    t->spec = spec;
    t->active = 1;
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
    t->active = 0;

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
        p->val[k] = p->node[k].op == T_K ? p->node[k].k : 0.0;
    lua_getiuservalue(L, base + 1, UV_GUARDS);
    lua_replace(L, base + 1);
    lua_settop(L, base + 1);
    return p;
}
