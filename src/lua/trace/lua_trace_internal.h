/*
 * lua_trace_internal.h - what the tracer's files share: lua_trace.c
 * (recording a function's arithmetic), lua_trace_eval.c (evaluating the
 * record, checking its guards) and lua_trace_bytecode.c (the bytecode
 * scan for what a record cannot see).  Internal to the binding.
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

#endif
