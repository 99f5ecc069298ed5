/*
 * lua_trace_internal.h - what the tracer's files share: lua_trace.c
 * (recording a function's arithmetic), lua_trace_eval.c (evaluating the
 * record, checking its guards) and lua_trace_bytecode.c (the bytecode
 * scan for what a record cannot see).  Internal to the binding.
 */
#ifndef DFLE_LUA_TRACE_INTERNAL_H
#define DFLE_LUA_TRACE_INTERNAL_H

#include "lua/trace/lua_trace.h"

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

/* A guard is 4 entries of the guard table: kind, container (a table or
 * a function), key (a field name or an upvalue index), value; a nil value
 * is stored as a light userdata pointing at dfle_trace_nil. */
enum { G_FIELD = 1, G_UPVALUE = 2 };
extern const char dfle_trace_nil;

/* What the scan of a function's bytecode (and its nested functions')
 * found: an equality test, an upvalue assignment, or a chunk it could
 * not read (another Lua version). */
enum { FOUND_EQ = 1, FOUND_SETUPVAL = 2, FOUND_BAD = 4 };
unsigned dfle_trace_scan(lua_State *L, int fidx);

#endif
