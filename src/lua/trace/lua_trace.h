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
 * (dfle_lua_epoch) and compiles again if any changed.  Float params may
 * instead be inputs of the program (params_inputs), so that one program
 * serves every law built from the same function with other values: the
 * per-state cache (lua_trace_cache.c) hands a copy of it to each new law
 * whose function, upvalues, globals and other params match.
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
    int params_inputs;        /* 1: a float param is an input of the
                               * program, its value set per law (as a
                               * constant if the function is refused so) */
} dfle_trace_spec;

/* The release this build runs under, as LUA_VERSION_RELEASE_NUM gives
 * it (50404 for 5.4.4). */
long dfle_trace_release(void);

/* 1 if the tracer was checked against Lua release `release`; else 0,
 * with why it will not compile ("the tracer was not checked against Lua
 * 5.4.6").  dfle_trace_compile refuses everything under a release that
 * was not (lua_trace_release.c). */
int dfle_trace_release_checked(long release, char *why, size_t why_len);

/* The running Lua checked against the tracer (lua_trace_vm.c): a probe
 * function compiled and dumped by it must have the header and opcodes
 * the tracer reads.  dfle_trace_vm_check_dump checks a dump (1, or 0
 * with why); dfle_trace_vm_push_probe pushes the running Lua's dump of
 * the probe (nil if it gives none); dfle_trace_vm_verify records the
 * verdict for L's state, of that dump or (dump NULL) of the running
 * Lua's, warning once if it refuses; dfle_trace_vm_ok reads it back (1,
 * or 0 with why).  dfle_trace_compile refuses everything while the
 * verdict refuses. */
int dfle_trace_vm_check_dump(const char *dump, size_t len, char *why, size_t why_len);
void dfle_trace_vm_push_probe(lua_State *L);
void dfle_trace_vm_verify(lua_State *L, const char *dump, size_t len);
int dfle_trace_vm_ok(lua_State *L, char *why, size_t why_len);

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

/* Forward-mode derivative of the values dfle_trace_eval_n has just given
 * for the same n points: din[f] is the derivative of input f at every
 * point (NULL: 0, a constant).  Each node carries its derivative along
 * with its value, by the rule of its operation (a kink, as in abs at 0,
 * gives NaN; min and max follow the operand they chose; floor, ceil and
 * // are flat almost everywhere).  Returns the n derivatives of the
 * result (valid until the next call), NULL if out of memory.  The values
 * themselves are not touched. */
const double *dfle_trace_deriv_n(dfle_trace_prog *prog, size_t n, const double *const *din);
/* 1 when dfle_trace_deriv_n knows the rule of every operation in prog. */
int dfle_trace_differentiable(const dfle_trace_prog *prog);

/* 1 when every value the program baked in is still what it was (guard
 * table at gidx, from dfle_trace_compile).  Never raises. */
int dfle_trace_guards_hold(lua_State *L, int gidx, const dfle_trace_prog *prog);

/* ---- the per-state cache of programs (lua_trace_cache.c) ---- */

/* Create the cache of L's state (at luaopen_dfle; may raise). */
void dfle_trace_cache_open(lua_State *L);

/* A program for the function at fidx with the params table at pidx from
 * the cache of L's state: a copy of one traced earlier from the same code
 * (the same chunk, as lua_dump writes it, debug information included) for
 * the same spec, whose guards hold for this function and params, with
 * this law's param values bound.  Pushes the guard table of the copy (as
 * dfle_trace_compile does); NULL and nil when there is none.  Only
 * programs already checked against Lua are in the cache
 * (dfle_trace_cache_put).  Never raises. */
dfle_trace_prog *dfle_trace_cache_find(lua_State *L, int fidx, int pidx,
                                       const dfle_trace_spec *spec);

/* Keep a copy of prog, traced from the function at fidx with the params
 * at pidx and spec, guard table at gidx, for later laws of L's state.
 * Call it once prog has given what the function gives run as Lua.
 * Never raises (a program that cannot be kept is just not kept). */
void dfle_trace_cache_put(lua_State *L, int fidx, int pidx, const dfle_trace_spec *spec,
                          const dfle_trace_prog *prog, int gidx);

/* Whether the code of the function at fidx (its chunk, with spec) was
 * refused with float params as inputs and traced with them as constants
 * (it compares one, loops to one...); with `mark`, remember that it was.
 * A later law of the same code then traces once, with constants, not
 * twice.  Never raises (a mark that cannot be kept is not kept). */
int dfle_trace_cache_constants_only(lua_State *L, int fidx, const dfle_trace_spec *spec,
                                    int mark);

/* What the cache of L's state did: programs traced (dfle_trace_compile),
 * found (dfle_trace_cache_find), kept (dfle_trace_cache_put) and checked
 * against Lua (counted by the caller), the templates it holds, and the
 * traces refused with params as inputs and done again with constants. */
typedef struct dfle_trace_stats {
    unsigned long traced, found, kept, checked, held;
    unsigned long retraced; /* traced again with params as constants */
} dfle_trace_stats;
/* The counters of L's state (created on first use; NULL if out of
 * memory).  Never raises. */
dfle_trace_stats *dfle_trace_stats_of(lua_State *L);

#endif
