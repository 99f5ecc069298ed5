/*
 * lua_trace_internal.h - what the tracer's files share: lua_trace.c (one
 * trace of a function, made into a program), lua_trace_node.c (recording
 * the arithmetic and math calls on nodes), lua_trace_outside.c (guards
 * and stand-ins for what the function reads from outside),
 * lua_trace_eval.c (evaluating the record, checking its guards),
 * lua_trace_bytecode.c (the bytecode scan for what a record cannot see)
 * and lua_trace_cache.c (the per-state cache of programs).  Internal to
 * the binding.
 */
#ifndef DFLE_LUA_TRACE_INTERNAL_H
#define DFLE_LUA_TRACE_INTERNAL_H

#include "lua/trace/lua_trace.h"

/* Node operations.  T_IN, T_K and T_PARAM hold values set before
 * evaluation: T_PARAM is a float param read as an input of the program
 * (lua_trace.h), whose k is the value of the law it is bound to. */
enum {
    T_IN, T_K, T_PARAM,
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
    /* dfle_trace_deriv_n's tangent columns, one per node, and their
     * storage: (n + 1) x dcap (the last column is zeros). */
    const double **dcol;
    double *dwork;
    size_t dcap;
};

/* A guard is 4 entries of the guard table: kind, container (a table or
 * a function), key (a field name or an upvalue index), value; a nil value
 * is stored as a light userdata pointing at dfle_trace_nil.  G_PARAM is a
 * float param the program reads as an input: its value entry is the
 * index of its T_PARAM node, and the guard holds while the param is a
 * float equal to that node's k (in a cached template, while it is any
 * float: lua_trace_cache.c). */
enum { G_FIELD = 1, G_UPVALUE = 2, G_PARAM = 3 };
extern const char dfle_trace_nil;

/* Whether a node holds a value set before evaluation (T_K, T_PARAM). */
#define T_IS_CONST(op) ((op) == T_K || (op) == T_PARAM)

/* How the guards at gidx are checked.  For a law's own program (fidx =
 * pidx = 0) every value must be what the program baked in.  For a cached
 * template (lua_trace_cache.c) the marks dfle_trace_root and
 * dfle_trace_params stand for the function at fidx and the params table
 * at pidx, and a G_PARAM guard holds for any float.  Never raises. */
extern const char dfle_trace_root, dfle_trace_params;
int dfle_trace_guards_check(lua_State *L, int gidx, const dfle_trace_prog *prog, int fidx,
                            int pidx);

/* Push the chunk lua_dump makes of the Lua function at fidx (with its
 * debug information), or nil if it makes none.  May raise (memory). */
void dfle_trace_push_dump(lua_State *L, int fidx);

/* A copy of prog with workspaces of its own (NULL if out of memory). */
dfle_trace_prog *dfle_trace_clone(const dfle_trace_prog *prog);

/* What the scan of a function's bytecode (and its nested functions')
 * found: an equality test, an upvalue assignment, or a chunk it could
 * not read (another Lua version). */
enum { FOUND_EQ = 1, FOUND_SETUPVAL = 2, FOUND_BAD = 4 };
unsigned dfle_trace_scan(lua_State *L, int fidx);
/* The opcodes of the first function of a chunk (lua_dump's), up to cap
 * into ops (*nops: how many it has), after checking the chunk's header:
 * 0, or -1 with why (lua_trace_vm.c checks the running Lua with it). */
int dfle_trace_chunk_opcodes(const char *chunk, size_t len, unsigned char *ops, size_t cap,
                             size_t *nops, char *why, size_t why_len);

/* ---- during a trace: lua_trace.c, lua_trace_node.c, lua_trace_outside.c */

#define MAX_NODES 1024 /* operations a compiled function may record    */

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

/* The registry name of the nodes' metatable. */
#define NODE_MT "dfle.trace.node"

/* What a proxy stands for (lua_trace_outside.c). */
enum { PROXY_ENV, PROXY_MATH, PROXY_PARAMS };

static inline tracer *tracer_at(lua_State *L, int idx) { return lua_touserdata(L, idx); }

/* lua_trace_node.c: nodes and the math functions a trace records. */

/* Refuse to compile: remember the first reason and unwind the trace. */
int dfle_trace_refuse(lua_State *L, tracer *t, const char *fmt, ...);
/* Record a node; its index (refuses past MAX_NODES). */
int dfle_trace_add_node(lua_State *L, tracer *t, int op, int a, int b, double k, int maybe_int);
/* Push a node object for node `idx` of the tracer at tidx. */
void dfle_trace_push_node(lua_State *L, int tidx, int idx);
/* Create NODE_MT, the metatable of nodes, if it is not there yet. */
void dfle_trace_node_metatable(lua_State *L);
/* Push the map of the genuine math functions (C address -> T_ op). */
void dfle_trace_math_map(lua_State *L);
/* The T_ op of the C function at idx, or 0. */
int dfle_trace_math_op_of(lua_State *L, int idx);
/* A math function during a trace: upvalue 1 = the T_ op, 2 = the real
 * function. */
int dfle_trace_math_wrapper(lua_State *L);

/* lua_trace_outside.c: what the function reads besides its arguments. */

/* Check that the Lua function at fidx can be traced, and point its
 * upvalues at stand-ins for the trace. */
void dfle_trace_vet_function(lua_State *L, tracer *t, int tidx, int fidx, const char *what);
/* Push a new proxy of the table at `real`, of PROXY_ kind `kind`. */
void dfle_trace_push_proxy(lua_State *L, int tidx, int real, int kind);
/* Refuse metatables shared by non-table values, and swap strings'
 * __index for one that refuses; reopen puts it back (no allocation). */
void dfle_trace_close_shared_metatables(lua_State *L, tracer *t, int tidx);
void dfle_trace_reopen_shared_metatables(lua_State *L, int tidx);

#endif
