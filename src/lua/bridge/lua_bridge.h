/*
 * lua_bridge.h - the Lua binding for a host that cannot see Lua (not
 * installed): the Python extension (src/python/) drives the same `dfle`
 * module a script does, through this header, which names no Lua type.
 *
 * Why through Lua: the binding is where every object's keyword names,
 * defaults, units, checks and messages live.  A second binding written
 * against the C library would have to repeat all of them and would
 * drift; calling the Lua one gives the host the same objects, the same
 * messages and the same numbers, bit for bit, because the same code runs.
 *
 * The interface is a small value stack after Lua's own: the host pushes
 * values (numbers, strings, arrays of doubles, tables, references to
 * values it keeps, callbacks into its own code), calls a function in
 * protected mode and reads the results.  Indices are positive stack
 * slots of the current frame (1 is the bottom); inside a callback the
 * frame is the callback's own, its arguments at 1..nargs.
 *
 * A bridge is not thread-safe: its host serialises every call on it
 * (the Python extension holds a lock).  Work the binding does outside
 * Lua (a run's steps) runs on the calling thread.
 */
#ifndef DFLE_LUA_BRIDGE_H
#define DFLE_LUA_BRIDGE_H

#include <signal.h>
#include <stddef.h>

typedef struct dfle_bridge dfle_bridge;

/* Value types, as Lua's (an OBJECT is a userdata: dfle.model, ...). */
enum {
    DFLE_BRIDGE_NIL = 0,
    DFLE_BRIDGE_BOOLEAN,
    DFLE_BRIDGE_NUMBER,
    DFLE_BRIDGE_STRING,
    DFLE_BRIDGE_TABLE,
    DFLE_BRIDGE_FUNCTION,
    DFLE_BRIDGE_OBJECT,
    DFLE_BRIDGE_OTHER
};

/* A callback into the host: its arguments are at 1..nargs of the
 * current frame.  Returns how many results it pushed, or -1 after
 * pushing one string: the error the Lua caller sees. */
typedef int (*dfle_bridge_fn)(dfle_bridge *b, void *ud, int nargs);

/* A new Lua state with the standard libraries and the dfle module, as
 * the dfle command opens it (the module also as the global `dfle`, for
 * Lua source the host loads).  NULL if memory runs out or the module
 * cannot be opened; *why (may be NULL) then points at a static reason. */
dfle_bridge *dfle_bridge_new(const char **why);
void dfle_bridge_free(dfle_bridge *b);

/* Lua warnings (lua_warning), one whole message at a time ("@on" and
 * the other control messages are not passed on). */
void dfle_bridge_set_warn(dfle_bridge *b, void (*fn)(void *ud, const char *msg), void *ud);
/* The interrupt flag runs watch (dfle_lua_set_interrupt): a signal
 * number there stops a run at its next step. */
void dfle_bridge_set_interrupt(dfle_bridge *b, const volatile sig_atomic_t *flag);

/* --- the stack --- */
int dfle_bridge_top(dfle_bridge *b);
void dfle_bridge_settop(dfle_bridge *b, int top);
/* Room for n more values; 0 if the stack cannot grow. */
int dfle_bridge_check(dfle_bridge *b, int n);

void dfle_bridge_push_nil(dfle_bridge *b);
void dfle_bridge_push_boolean(dfle_bridge *b, int v);
void dfle_bridge_push_number(dfle_bridge *b, double v);
void dfle_bridge_push_integer(dfle_bridge *b, long long v);
void dfle_bridge_push_string(dfle_bridge *b, const char *s, size_t len);
/* A copy of the value at idx. */
void dfle_bridge_push_value(dfle_bridge *b, int idx);
/* The dfle module table. */
void dfle_bridge_push_module(dfle_bridge *b);
/* An array (1-based table) of the n doubles v, or of the n integers iv. */
void dfle_bridge_push_doubles(dfle_bridge *b, const double *v, size_t n);
void dfle_bridge_push_integers(dfle_bridge *b, const long long *iv, size_t n);
void dfle_bridge_new_table(dfle_bridge *b, int narr, int nrec);
/* Pop the value on top into table t under string key k / index i. */
void dfle_bridge_set_field(dfle_bridge *b, int t, const char *k);
void dfle_bridge_set_index(dfle_bridge *b, int t, long long i);
/* A Lua function calling fn(ud); release(ud) when Lua collects it. */
void dfle_bridge_push_callback(dfle_bridge *b, dfle_bridge_fn fn, void *ud,
                               void (*release)(void *ud));

/* References: pop the top value into the registry and return its key;
 * push it again; let it go (a value nothing else holds is collected). */
int dfle_bridge_ref(dfle_bridge *b);
void dfle_bridge_push_ref(dfle_bridge *b, int ref);
void dfle_bridge_unref(dfle_bridge *b, int ref);

/* --- reading values --- */
int dfle_bridge_type(dfle_bridge *b, int idx);
int dfle_bridge_is_integer(dfle_bridge *b, int idx);
int dfle_bridge_to_boolean(dfle_bridge *b, int idx);
double dfle_bridge_to_number(dfle_bridge *b, int idx);
long long dfle_bridge_to_integer(dfle_bridge *b, int idx);
/* The string at idx (a string value only; NULL otherwise). */
const char *dfle_bridge_to_string(dfle_bridge *b, int idx, size_t *len);
/* What a user calls the value: the __name of its metatable ("dfle.model")
 * or the Lua type name. */
const char *dfle_bridge_typename(dfle_bridge *b, int idx);
/* Whether the table at idx has a metatable (a result with methods or
 * strict fields: the host keeps it as a reference). */
int dfle_bridge_has_metatable(dfle_bridge *b, int idx);
/* The raw length of the table at idx, and whether it is an array of
 * numbers 1..n and nothing else: then the values go to out (n of them;
 * *all_int says whether every one is an integer).  Returns 0 for any
 * other table. */
size_t dfle_bridge_len(dfle_bridge *b, int idx);
int dfle_bridge_number_array(dfle_bridge *b, int idx, double *out, size_t n, int *all_int);
/* As lua_next on table t (raw): pushes key and value, or nothing at the
 * end (then returns 0). */
int dfle_bridge_next(dfle_bridge *b, int t);
void dfle_bridge_rawgeti(dfle_bridge *b, int t, long long i);

/* --- protected calls: 0, or -1 with the error message (a string) on
 * top in place of what was asked --- */

/* Push obj[key] (which may run __index and raise); *method (may be
 * NULL) is set when the value is a function the object's metatable
 * supplies, i.e. a method called with the object first. */
int dfle_bridge_index(dfle_bridge *b, int obj, const char *key, int *method);
/* Call the function below the nargs values on top; its results replace
 * them, and *nres receives their count. */
int dfle_bridge_call(dfle_bridge *b, int nargs, int *nres);
/* Push the function the Lua source src evaluates to ("function(c, p)
 * return ... end"), loaded as chunk `name`. */
int dfle_bridge_load(dfle_bridge *b, const char *src, size_t len, const char *name);
/* tostring(v) of the value at idx, pushed. */
int dfle_bridge_tostring(dfle_bridge *b, int idx);
/* Close the object at idx (its __close: what `local x <close>` does). */
int dfle_bridge_close(dfle_bridge *b, int idx);

/* --- parallel calls (lua_bridge_workers.c) --- */

/* Worker states for the next dfle.ensemble or dfle.invert call, which
 * the host makes between begin and end: each runs `script` (Lua source
 * of a chunk that makes the same call, with a spec that must identify
 * the same run: the workers check), in a state of its own on a thread
 * of the driver's pool.  The call counts of the main state are carried
 * over, so the script's call is taken for the main state's next one.
 * Without begin, a call runs in the main state only (its build or
 * measure may be host code, which no other state can call).
 * begin: 0, or -1 if memory runs out. */
int dfle_bridge_begin_parallel(dfle_bridge *b, const char *script, size_t len);
void dfle_bridge_end_parallel(dfle_bridge *b);

/* --- the host's collector (lua_bridge_gc.c) --- */

/* fn(ud, owners, n, callback_ud) for each host callback (its ud as
 * given to dfle_bridge_push_callback) that only host references keep
 * alive: Lua's roots do not reach it, the n references `owners` do, so
 * it goes once all of them are let go of and the state collected.
 * Returns how many callbacks, or -1 when it cannot tell (inside a
 * callback, a coroutine, no memory): then none is anyone's.  Call it
 * with nothing running. */
typedef void (*dfle_bridge_owned_fn)(void *ud, const int *owners, int n, void *callback_ud);
int dfle_bridge_owned_callbacks(dfle_bridge *b, dfle_bridge_owned_fn fn, void *ud);
/* Stop (pause 1) or restart Lua's collector: while the host's collector
 * works from what dfle_bridge_owned_callbacks said, no callback may go. */
void dfle_bridge_gc_pause(dfle_bridge *b, int pause);
/* A full collection: the callbacks of values let go of are released. */
void dfle_bridge_collect(dfle_bridge *b);

/* --- fields read where they lie (lua_bridge_field.c) --- */

/* A field of a dfle.model (n values along the channel) or a
 * dfle.landscape (ny rows of nx, row 0 at the north). */
typedef struct dfle_bridge_field {
    const double *v;
    size_t n, nx, ny;
    int ndim; /* 1: a model's, 2: a landscape's                          */
    /* 1: v is the object's own memory, always current (a model's x, A,
     * w, z; a landscape's z): valid while the object lives, which the
     * host that keeps it ensures by holding the object.  0: the field
     * evaluated now, valid until the host changes the stack: copy it. */
    int live;
} dfle_bridge_field;

/* The field `name` of the object at idx, as its get() would evaluate it
 * (the same checks and messages).  Pushes one value in every case (what
 * keeps a copy valid, or the message).  Returns 1 with f filled, 0 when
 * the object or the name is not one this reads (the host calls the
 * object's get, which says why), -1 on an error (message on top). */
int dfle_bridge_get_field(dfle_bridge *b, int idx, const char *name, dfle_bridge_field *f);
/* The unit dfle's files give a parameter or output of that name
 * ("m/yr" for U), or NULL when it has none it knows. */
const char *dfle_bridge_known_unit(const char *name);
/* Hold the model or landscape at idx while a view of its memory lives:
 * closing or collecting it only dooms it until the last unhold.
 * Anything else is ignored.  0, or -1 if Lua ran out of memory. */
int dfle_bridge_hold(dfle_bridge *b, int idx);
void dfle_bridge_unhold(dfle_bridge *b, int idx);

/* --- what an object's files say (lua_bridge_record.c) --- */

/* The record a dfle.model's or dfle.landscape's NetCDF files carry as
 * global attributes, as a table of the same names and values (booleans
 * as 0 and 1, units per section in "<section>_units"), then its CRS as
 * WKT (a landscape's; nil when it has none).  Returns 1 with the two
 * values pushed, 0 with nothing pushed for any other value, -1 on an
 * error (a closed object; message on top). */
int dfle_bridge_push_attrs(dfle_bridge *b, int idx);
/* The labels the files give a model's (landscape 0) or a landscape's
 * field `name`: its unit as dfle writes it, long name and CF standard
 * name (each may be NULL).  0 for a name that is no field. */
int dfle_bridge_field_label(int landscape, const char *name, const char **unit,
                            const char **long_name, const char **standard_name);

#endif
