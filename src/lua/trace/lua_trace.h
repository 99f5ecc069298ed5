/*
 * lua_trace.h - compile a pure Lua function of numbers into a
 * straight-line program that C evaluates per node (lua_trace.c).
 *
 * A Lua law is called once per node and evaluation; most laws are a
 * formula.  The tracer calls the user's function ONCE with symbolic
 * values in place of the node's numbers and records the arithmetic it
 * does; the model then evaluates that record in C, at the speed of a
 * built-in law, and gets bit-for-bit the numbers Lua would have given.
 * A function that does anything a record cannot capture (branches on a
 * flow field, side effects, calls that are not in `math`, ...) is
 * refused with a reason and keeps running as Lua.  doc/laws.md lists
 * the rules.
 *
 * What a compiled function read besides its arguments (params, globals,
 * upvalues) is baked in as constants and listed in a guard table; the
 * caller checks the guards whenever Lua code may have run since
 * (dfle_lua_epoch) and compiles again if any changed.
 */
#ifndef DFLE_LUA_TRACE_H
#define DFLE_LUA_TRACE_H

#include <lua.h>
#include <stddef.h>

#define DFLE_TRACE_MAX_INPUTS 16

typedef struct dfle_trace_prog dfle_trace_prog;

/* How the function is called and what it may read. */
typedef struct dfle_trace_spec {
    int n_inputs;             /* <= DFLE_TRACE_MAX_INPUTS               */
    const char *const *names; /* input names (fields of c, or arguments) */
    unsigned available;       /* fn(c, p): bit f set when c[names[f]] is
                               * defined (others read as nil)           */
    int positional;           /* 1: fn(x_1, ..., x_n, p); 0: fn(c, p)   */
} dfle_trace_spec;

/* The release this build runs under, as LUA_VERSION_RELEASE_NUM gives
 * it (50404 for 5.4.4). */
long dfle_trace_release(void);

/* 1 if the tracer was checked against Lua release `release`; else 0,
 * with why it will not compile ("the tracer was not checked against Lua
 * 5.4.6").  dfle_trace_compile refuses everything under a release that
 * was not (lua_trace_release.c). */
int dfle_trace_release_checked(long release, char *why, size_t why_len);

/* Trace the function at index fidx, with the params table at pidx.
 * Returns the program and pushes its guard table, or returns NULL,
 * pushes nil and writes the reason (a sentence fragment such as
 * "compares a flow field with '<'") into why.  Never raises: the user's
 * function runs under lua_pcall, and everything it touched is restored. */
dfle_trace_prog *dfle_trace_compile(lua_State *L, int fidx, int pidx, const dfle_trace_spec *spec,
                                    char *why, size_t why_len);
void dfle_trace_free(dfle_trace_prog *prog);

/* Bit f set when the program reads input f. */
unsigned dfle_trace_inputs(const dfle_trace_prog *prog);

/* The function's value for inputs in[0..n_inputs) (unread ones ignored). */
double dfle_trace_eval(dfle_trace_prog *prog, const double *in);

/* Its values at n points: in[f] is input f at every point (NULL: zeros).
 * Returns the n values (valid until the next call), NULL if out of memory. */
const double *dfle_trace_eval_n(dfle_trace_prog *prog, size_t n, const double *const *in);

/* 1 when every value the program baked in is still what it was (guard
 * table at gidx, from dfle_trace_compile).  Never raises. */
int dfle_trace_guards_hold(lua_State *L, int gidx, const dfle_trace_prog *prog);

#endif
