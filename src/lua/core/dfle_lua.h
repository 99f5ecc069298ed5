/*
 * dfle_lua.h - internals shared by the Lua binding files (not installed).
 *
 * Conventions, after Lua's own liolib.c:
 *  - every C object is a full userdata holding one pointer, created in a
 *    valid empty state (pointer NULL) before anything can fail, with a
 *    named metatable ("dfle.channel", ...) whose __gc is idempotent;
 *  - constructors take one table of named parameters; unknown keys,
 *    wrong types and NaN are errors naming the parameter, and the C
 *    constructor's own range checks supply the rest of the message;
 *  - misuse raises (with the caller's file:line); expected failures,
 *    such as a fit that does not converge, return nil, message;
 *  - no malloc'd memory is held across a call that can raise: scratch
 *    arrays are userdata, collected if an error unwinds the stack.
 *
 * The core below every binding file: lua_type.c (object types),
 * lua_util.c (options, errors, numbers, tables), lua_params.c (a
 * router's or law's parameters), lua_state.c (what a lua_State keeps in
 * its registry), and lua_shell.h (components written in Lua).  The open
 * functions at the end are called from above only: by luaopen_dfle
 * (lua_module.c), the define ones by the file of their kind.
 */
#ifndef DFLE_LUA_INTERNAL_H
#define DFLE_LUA_INTERNAL_H

#include <signal.h>
#include <stddef.h>

#include <lauxlib.h>
#include <lua.h>

#include "dfle/channel.h"
#include "dfle/error.h"
#include "dfle/fluvial.h"
#include "dfle/law.h"
#include "dfle/model.h"
#include "dfle/plot.h"
#include "dfle/record.h"
#include "dfle/solver.h"
#include "dfle/router.h"

#define DFLE_LUA_CHANNEL "dfle.channel"
#define DFLE_LUA_FLUVIAL "dfle.fluvial"
#define DFLE_LUA_ROUTER "dfle.router"
#define DFLE_LUA_LAW "dfle.law"
#define DFLE_LUA_MODEL "dfle.model"

/* Userdata payloads: the C object, then how it is in use (lua_type.c).
 * Every payload has this layout, so generic code reads any of them as
 * a dfle_lua_object. */
#define DFLE_LUA_IN_USE                                                       \
    unsigned busy;    /* calls on it running now (they may run Lua code)  */ \
    unsigned holders; /* models that hold it                              */ \
    int doomed        /* __gc/__close came while in use: free when unused */
typedef struct dfle_lua_object { void *ptr; DFLE_LUA_IN_USE; } dfle_lua_object;
typedef struct { dfle_channel *ch; DFLE_LUA_IN_USE; } dfle_lua_channel;
typedef struct { dfle_fluvial *fl; DFLE_LUA_IN_USE; } dfle_lua_fluvial;
typedef struct { dfle_router *rt; DFLE_LUA_IN_USE; } dfle_lua_router;
typedef struct { dfle_law *law; DFLE_LUA_IN_USE; } dfle_lua_law;
typedef struct { dfle_model *m; DFLE_LUA_IN_USE; } dfle_lua_model;

/* --- lua_type.c: object types --- */

/* What an object type supplies; everything else (__gc, __close,
 * __tostring of a closed object, __index, the protected metatable) is
 * generic.  The descriptor must outlive every lua_State (a static). */
typedef struct dfle_lua_type {
    const char *name;                       /* metatable name, "dfle.channel" */
    void (*free)(void *obj);                /* release the C object         */
    /* Push the description tostring() gives of the live object obj (the
     * userdata is at index 1). */
    void (*describe)(lua_State *L, void *obj);
    const luaL_Reg *methods;                /* may be NULL                  */
    /* Read-only fields such as m.time: called as __index(obj, key), key
     * a string that is not a method.  May be NULL. */
    lua_CFunction property;
    const luaL_Reg *meta;                   /* more metamethods (__len), or NULL */
    int closable;                           /* __close frees it too (local x <close>) */
    /* After the C object is freed: let go of what it held (the userdata
     * is at index idx).  May be NULL. */
    void (*release)(lua_State *L, int idx);
    /* The read-only fields, for the message when a script reads one that
     * does not exist ("time, U, n"); NULL: the object's params() keys. */
    const char *fields;
    /* How to change what scripts may try to assign ("U: m:set_U(U)");
     * NULL: nothing can be changed after construction. */
    const char *setters;
} dfle_lua_type;

/* Lifetime while in use (C objects point at each other, and Lua code
 * runs in the middle of C calls: U(t), laws and routers written in Lua).
 * An object is freed only when nothing uses it: __gc and __close of an
 * object that a model holds, or that a running call uses, only mark it
 * ("doomed").  The last holder to let go frees it; an object a call was
 * using is closed when the call ends its use, but freed only by its next
 * __gc (the collector's, once unreachable), because the call may still
 * read it (a model's field values, a router's report) after end_use.
 * __close of a busy object raises (a model closed from inside its own
 * U(t) or law).
 *
 * dfle_lua_begin_use marks the object at idx busy for a call that may run
 * Lua code, raising if it is busy already (re-entry: m:run inside its own
 * U(t)) or closed; `what` names the call in that message.
 * dfle_lua_end_use undoes it (never raises, never frees).  Between the
 * two, nothing may raise: collect the error status and raise after
 * end_use. */
dfle_lua_object *dfle_lua_begin_use(lua_State *L, int idx, const char *what);
void dfle_lua_end_use(lua_State *L, int idx);
/* The C object of the dfle object at idx, or NULL if it is closed. */
void *dfle_lua_object_ptr(lua_State *L, int idx);
/* The n values of field `field` of the model at idx, evaluated if need
 * be (which may run Lua laws and routers: the model is in use meanwhile);
 * raises on error, naming `what`. */
const double *dfle_lua_model_field(lua_State *L, int idx, int field, const char *what);

/* A model takes/leaves component idx. */
void dfle_lua_hold(lua_State *L, int idx);
void dfle_lua_unhold(lua_State *L, int idx);

/* Create the metatable of type t (once per lua_State). */
void dfle_lua_register(lua_State *L, const dfle_lua_type *t);

/* New userdata of `size` bytes, zeroed (its pointer NULL: valid and
 * empty), with metatable `tname` and `nuv` user values. */
void *dfle_lua_newobject(lua_State *L, size_t size, const char *tname, int nuv);

/* The pointer of object arg of type tname; raises a type error if arg is
 * not one, or was already closed. */
void *dfle_lua_check_object(lua_State *L, int arg, const char *tname);
dfle_channel *dfle_lua_check_channel(lua_State *L, int arg);
dfle_fluvial *dfle_lua_check_fluvial(lua_State *L, int arg);
dfle_router *dfle_lua_check_router(lua_State *L, int arg);
dfle_law *dfle_lua_check_law(lua_State *L, int arg);
dfle_model *dfle_lua_check_model(lua_State *L, int arg);

/* The type of the value at idx as a user would name it: the __name of
 * its metatable ("dfle.law") if it has one, else the Lua type. */
const char *dfle_lua_typename(lua_State *L, int idx);

/* --- lua_util.c: options, errors, numbers, tables --- */

/* A numeric parameter read from an options table into *dst. */
typedef struct dfle_lua_param {
    const char *name;
    double *dst;
} dfle_lua_param;

/* Check that idx is a table (or absent: then nothing is read) whose keys
 * are all among `params` or `other_keys` (NULL-terminated, may be NULL),
 * and read each numeric parameter present: it must be a finite number.
 * Raises "dfle.<fn>: ..." naming the parameter otherwise. */
void dfle_lua_read_params(lua_State *L, int idx, const char *fn,
                          const dfle_lua_param *params, size_t nparams,
                          const char *const *other_keys);

/* Warn (lua_warning, once per state for each fn and name) when a value
 * is far outside its physically sensible range, naming the likely unit
 * mistake (dfle/plausible.h).  dfle_lua_read_params calls it for every
 * value it reads. */
void dfle_lua_warn_implausible(lua_State *L, const char *fn, const char *name, double v);
/* Push and return the provenance line of files dfle writes: the UTC
 * time and the command (the global `arg`: program, options, script and
 * its arguments), e.g. "2026-12-01T19:50:00Z: dfle -j 2 run.lua --quick". */
const char *dfle_lua_push_history(lua_State *L);
/* A warning "file:line: dfle.<fn>: <msg>" through lua_warning. */
void dfle_lua_warn(lua_State *L, const char *fn, const char *msg);

/* The string at idx (a string or a number, as luaL_checkstring takes),
 * refusing embedded NUL bytes: C would end it there without a word
 * ("nul\0.csv" would write "nul", "direct\0junk" would select
 * "direct").  `fn` and `what` name it in the error ("dfle.<fn>: <what>
 * contains a NUL byte"). */
const char *dfle_lua_check_string(lua_State *L, int idx, const char *fn, const char *what);
/* The unit, in dfle's style, of a parameter or output name dfle knows
 * ("U": "m/yr", "gamma": "-"), or NULL for a user's own (and for k_df,
 * whose unit depends on the law's exponents). */
const char *dfle_lua_known_unit(const char *name);
/* The index in `choices` (NULL-terminated) of the string at idx; any
 * other value raises "dfle.<fn>: <what> must be 'a', 'b' or 'c' (got
 * 'x')" (luaL_checkoption names a field read onto the stack as
 * "bad argument #-2"). */
int dfle_lua_check_option(lua_State *L, int idx, const char *fn, const char *what,
                          const char *const *choices);
/* The solver method (enum dfle_method) named by the string at idx,
 * looked up by dfle_method_lookup; anything else raises "dfle.<fn>:
 * method must be 'explicit', 'implicit', 'direct' or 'auto' (got 'x')". */
int dfle_lua_check_method(lua_State *L, int idx, const char *fn);
/* Push `s` (len bytes) as it can be shown in a message: at most 60
 * characters, NUL and control bytes as \ddd, "..." and the length after
 * a cut; returns the pushed string. */
const char *dfle_lua_shown(lua_State *L, const char *s, size_t len);

/* Push, as one string, the string keys of the table at idx, sorted
 * ("a, b, c"); returns it. */
const char *dfle_lua_push_sorted_keys(lua_State *L, int idx);

/* Make the result table at idx strict: reading a key it does not have
 * raises, naming `what` and the keys it has (fit.Adf for fit.A_df would
 * otherwise be nil, and fail later, far from the mistake). */
void dfle_lua_strict_table(lua_State *L, int idx, const char *what);

/* Raise err's message as "dfle.<message>" at the caller's file:line. */
int dfle_lua_raise(lua_State *L, const dfle_error *err);

/* Push and return v as text: "NaN", "inf", or the number. */
const char *dfle_lua_number_text(lua_State *L, double v);

/* Copy every key and value of the table at src into the table at dst
 * (a shallow copy: raw, metatables ignored). */
void dfle_lua_copy_table(lua_State *L, int src, int dst);

/* Push a Lua array (1-based) of n doubles. */
void dfle_lua_push_array(lua_State *L, const double *v, size_t n);

/* Read a Lua array of numbers at idx into a scratch userdata left on the
 * stack; *n receives its length.  `what` names it in errors. */
double *dfle_lua_check_array(lua_State *L, int idx, const char *what, size_t *n);

/* v as a whole number in [lo, hi], or raise naming `name`. */
lua_Integer dfle_lua_check_whole(lua_State *L, double v, const char *fn, const char *name,
                                 double lo, double hi);

/* Text built from pieces: a table of strings on the stack joined at the
 * end (a luaL_Buffer cannot have other values pushed above it, and the
 * pieces come from calls that push).  init pushes the table; add pops
 * the string on top into it; finish replaces the table by the joined
 * string and drops anything above it. */
typedef struct dfle_lua_text {
    int t;
    lua_Integer k;
} dfle_lua_text;
void dfle_lua_text_init(lua_State *L, dfle_lua_text *p);
void dfle_lua_text_add(lua_State *L, dfle_lua_text *p);
void dfle_lua_text_str(lua_State *L, dfle_lua_text *p, const char *s);
void dfle_lua_text_finish(lua_State *L, dfle_lua_text *p);

/* Option `key` of the options table at idx as a string (NULL when the
 * table or the key is absent; the table holds the string); raises
 * naming dfle.<fn> for another type. */
const char *dfle_lua_opt_string(lua_State *L, int idx, const char *key, const char *fn);

/* Slope-area pairs of argument `arg`: a dfle.model (its nodes above the
 * outlet) or a table {A = {...}, S = {...}} (copied to scratch userdata
 * left on the stack).  Returns the number of pairs. */
size_t dfle_lua_slope_area(lua_State *L, int arg, const char *fn, const double **A,
                           const double **S);

/* --- lua_plot_opts.c (analysis/): the options every dfle.plot function
 * shares, read in one place --- */

/* Which of the shared keys a function takes: the page (title, size,
 * dpi, font) always; DFLE_LUA_PLOT_AXES adds the axes (x/y/c label,
 * range, log, ticks, format) and the legend. */
enum { DFLE_LUA_PLOT_PAGE = 0, DFLE_LUA_PLOT_AXES = 1 };

/* Read the options table at idx (absent: defaults) into *o: the shared
 * keys of `which`, the function's numeric `params` and its other keys
 * `own` (NULL-terminated, may be NULL; the caller reads them); any other
 * key raises, listing the known ones.  Checks the values
 * (dfle_plot_opts_check) and raises "dfle.<fn>: ..." naming the option.
 * Strings stay held by the table; tick lists go to scratch userdata
 * pushed on the stack, which must stay until the figure is drawn. */
void dfle_lua_plot_opts(lua_State *L, int idx, const char *fn, unsigned which,
                        const dfle_lua_param *params, size_t np, const char *const *own,
                        dfle_plot_opts *o);
/* The axis keys <axis>label, <axis>range, <axis>log, <axis>ticks,
 * <axis>format of the table at idx into *a (axis 'x', 'y' or 'c'). */
void dfle_lua_plot_axis(lua_State *L, int idx, const char *fn, char axis, dfle_plot_axis *a);
/* Series `k` (from 1, for messages) of a figure, the table at idx:
 * x, y (or lo, hi), label, style, lines, color, rgb, dash, width,
 * marker, marker_size.  Arrays go to scratch userdata on the stack. */
void dfle_lua_plot_series(lua_State *L, int idx, const char *fn, size_t k, dfle_plot_series *s);
/* (lua_plot.c) The data of a slope-area figure of dfle.<fn>: the pairs of
 * the source at src (as dfle_lua_slope_area), their nbins bins (release
 * them; nothing raises after they are made) and the fit: the table at
 * fit_idx (a dfle.fit_slope_area result), nil (fitted now: a fit that
 * fails leaves the curve out) or false (none).  Returns the fit or NULL. */
const dfle_eq2_fit *dfle_lua_plot_slope_area_data(lua_State *L, int src, int fit_idx,
                                                  const char *fn, size_t nbins, size_t *n,
                                                  const double **A, const double **S,
                                                  dfle_bins *bins, dfle_eq2_fit *fit);
/* Raise err (a message from dfle/plot.h, "plot: ...") as "dfle.<fn>: ...". */
int dfle_lua_plot_raise(lua_State *L, const char *fn, const dfle_error *err);

/* --- lua_params.c: a router's or law's parameters in Lua --- */

/* The params op of a kind of component (dfle_router_params,
 * dfle_law_params) behind one signature. */
typedef size_t (*dfle_lua_params_fn)(const void *component, dfle_param *out, size_t cap);

/* Push x:params() of the component object at obj (pointer comp): a new
 * table from its params op, a switch as a boolean and any other value a
 * number; or, when it has no params op, a copy of the table its object
 * keeps as user value 2 (a component written in Lua). */
void dfle_lua_push_params(lua_State *L, int obj, dfle_lua_params_fn fn, const void *comp);

/* The __index property of a component (the object at 1, a string key
 * at 2): x.name, else x.<param> (nil if it has none); returns 1. */
int dfle_lua_push_param_field(lua_State *L, const char *name, dfle_lua_params_fn fn,
                              const void *comp);

/* Push tostring(x): "<prefix>.<name>(k = v unit, ...)", the parameters
 * in the params op's order, or sorted by key for a Lua component's own
 * table. */
void dfle_lua_push_described(lua_State *L, int obj, const char *prefix, const char *name,
                             dfle_lua_params_fn fn, const void *comp);

/* --- lua_record.c: records of what produced an output --- */

/* The command line that runs the script (argv[script] the script), set
 * by the host before the script runs; without it records take the
 * global `arg` (dfle loaded into a plain lua). */
void dfle_lua_set_command(lua_State *L, char **argv, int argc, int script);

/* Push a new record (a userdata that frees it) stamped with the version,
 * the date, `about` (may be NULL), the command, the script and the
 * working directory; returns it.  Raises if memory runs out. */
dfle_record *dfle_lua_push_record(lua_State *L, const char *about);
/* The same without a stamp: an empty record. */
dfle_record *dfle_lua_push_empty_record(lua_State *L);

/* Add the entries of the table at t to rec's current section, sorted by
 * key (as parameters if `params`): numbers, booleans and strings as
 * they are, anything else as its type name. */
void dfle_lua_record_table(lua_State *L, dfle_record *rec, int t, int params);
/* The value at v as entry `key` of rec's current section, as
 * dfle_lua_record_table does it. */
void dfle_lua_record_value(lua_State *L, dfle_record *rec, const char *key, int v, int params);
/* The params a component written in Lua keeps (user value 2 of its
 * object at obj), as parameters of rec's current section. */
void dfle_lua_record_own_params(lua_State *L, dfle_record *rec, int obj);
/* The params of a router and a law written in Lua (their params live in
 * Lua, not in the C component): user values uv_router and uv_law of the
 * object at obj, into sections "router" and "law". */
void dfle_lua_record_lua_parts(lua_State *L, dfle_record *rec, int obj, int uv_router,
                               int uv_law);

/* Remember that the script wrote `path` (records list the files). */
void dfle_lua_note_file(lua_State *L, const char *path);

/* Where the JSON record of the output `path` goes, from the option
 * `record` of the table at opts (absent or true: beside it, "p.csv" ->
 * "p.json", anything else + ".json", none beside a device or a pipe;
 * false: none; a string: there), pushed (or nil) and returned; when
 * there is one, rec names it at the top level ("record").  Raises for a
 * `record` of another type, naming `fn`. */
const char *dfle_lua_record_path(lua_State *L, dfle_record *rec, int opts, const char *path,
                                 const char *fn);
/* After `output` was written with rec: write the JSON record at jpath
 * (NULL: none) with the output and the files written so far; note the
 * files.  Raises if the record cannot be written. */
void dfle_lua_record_done(lua_State *L, dfle_record *rec, const char *output, const char *jpath);
void dfle_lua_write_record(lua_State *L, dfle_record *rec, const char *output, const char *jpath);

/* (lua_model.c) The model at idx into rec (dfle_model_describe, the params
 * of components written in Lua, a U(t) function, and the last run since
 * the state was last set: section "run"). */
void dfle_lua_record_model(lua_State *L, dfle_record *rec, int idx);

/* --- lua_state.c: what the binding keeps per lua_State --- */

/* A C pointer (host data that outlives the state) in the registry under
 * key (the address of a static); NULL removes it, and reads as NULL. */
void dfle_lua_set_pointer(lua_State *L, const void *key, const void *p);
void *dfle_lua_get_pointer(lua_State *L, const void *key);

/* Progress reporting, installed by the CLI (library users get none):
 * the bar of a run (update, finish; either may be NULL), and notes, one
 * line each, about what happened: DFLE_LUA_NOTE for what a user should
 * know (an ensemble resumed from its file), DFLE_LUA_DETAIL for the
 * story of the run (each run, each file written), which the CLI shows
 * with --verbose. */
enum { DFLE_LUA_NOTE = 1, DFLE_LUA_DETAIL = 2 };
typedef struct dfle_lua_progress {
    dfle_progress_fn update;
    void (*finish)(void *ud);
    void (*note)(void *ud, int level, const char *line);
    void *ud;
} dfle_lua_progress;
void dfle_lua_set_progress(lua_State *L, const dfle_lua_progress *p);
/* A note (printf format) to the host, if it listens. */
void dfle_lua_note(lua_State *L, int level, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Interruption (SIGINT/SIGTERM), installed by the CLI: `flag` holds the
 * signal number once one arrived (0 before).  A run in progress stops at
 * its next step and returns what it has (reason "interrupted"); starting
 * a run or an ensemble afterwards raises; the note says what was kept,
 * for the host's last line. */
void dfle_lua_set_interrupt(lua_State *L, const volatile sig_atomic_t *flag);
const volatile sig_atomic_t *dfle_lua_get_interrupt(lua_State *L);
/* The signal number if interrupted, else 0. */
int dfle_lua_interrupted(lua_State *L);
/* Raise "dfle.<what>: interrupted (SIGINT) ..." if interrupted. */
void dfle_lua_check_interrupt(lua_State *L, const char *what);
/* Record / read what the interrupted work kept (one sentence). */
void dfle_lua_set_interrupt_note(lua_State *L, const char *fmt, ...);
const char *dfle_lua_interrupt_note(lua_State *L);
const dfle_lua_progress *dfle_lua_get_progress(lua_State *L);

/* The dfle module table: recorded by luaopen_dfle, pushed by the
 * binding files, so it is found even if a script replaced the global or
 * package.loaded. */
void dfle_lua_set_module(lua_State *L, int idx);
void dfle_lua_push_module(lua_State *L);

/* The Lua epoch: a counter per lua_State that goes up whenever Lua code
 * may have run (a binding given a model, a callback returned), so a
 * compiled law (lua_trace.h) re-checks the values it baked in only then.
 * Created by luaopen_dfle; dfle_lua_touch never allocates after that. */
unsigned long *dfle_lua_epoch(lua_State *L);
void dfle_lua_touch(lua_State *L);

/* Processors online (at least 1): the default number of ensemble workers
 * and PAWN bootstrap threads. */
int dfle_lua_cores(void);

/* Each binding file adds its functions to the module table on the stack. */
void dfle_lua_open_channel(lua_State *L);
void dfle_lua_open_fluvial(lua_State *L);
void dfle_lua_open_router(lua_State *L);
void dfle_lua_open_router_define(lua_State *L);
/* dfle.router.population, .moment, .quadrature (lua_population.c), into
 * the table on the top of the stack. */
void dfle_lua_open_router_population(lua_State *L);
/* m:run_events{...} (lua_population.c). */
int dfle_lua_model_run_events(lua_State *L);
void dfle_lua_open_law(lua_State *L);
void dfle_lua_open_law_define(lua_State *L); /* dfle.law.define, into the law table */
/* law:compiled() of a dfle.law.define law: push { factor =, rate =,
 * integrand = } (true: compiled; false: not used yet; a string: why it
 * runs as Lua) and return 1; return 0 for any other law. */
int dfle_lua_law_compiled(lua_State *L, dfle_law *law);
void dfle_lua_open_model(lua_State *L);
/* dfle.model{ network = <dem:network{...}>, k_w =, b = } (lua_dem_network.c):
 * when the options table at opts has a network, push the model's network
 * object built from it (widths k_w A^b), set *out and return 1; else
 * return 0 (raising on k_w or b without a network).  After the model is
 * made, dfle_lua_model_network_z starts it from the DEM's elevations. */
void dfle_lua_open_network(lua_State *L);
int dfle_lua_model_network(lua_State *L, int opts, const dfle_network **out);
int dfle_lua_model_network_z(lua_State *L, int opts, dfle_model *m);
void dfle_lua_open_analysis(lua_State *L);
void dfle_lua_open_plot(lua_State *L);
void dfle_lua_open_chi(lua_State *L); /* after plot: dfle.chi, dfle.concavity, their plots */
void dfle_lua_open_sampling(lua_State *L);
void dfle_lua_open_args(lua_State *L); /* dfle.args, dfle.mkdir (lua_args.c) */
/* Whether msg is the error dfle.args raised last for a mistake on the
 * command line (an unknown option...): a host reports it without a
 * traceback, as a command-line error. */
int dfle_lua_is_usage_error(lua_State *L, const char *msg);
void dfle_lua_open_write_csv(lua_State *L); /* dfle.write_csv (lua_write_csv.c) */
void dfle_lua_open_dem(lua_State *L);
void dfle_lua_open_landscape(lua_State *L);
void dfle_lua_open_ensemble(lua_State *L); /* after sampling: wraps dfle.pawn */
void dfle_lua_open_invert(lua_State *L);   /* after plot: adds dfle.plot.corner, ... */
void dfle_lua_open_trace_hook(lua_State *L); /* the cache of compiled laws; test hooks */

#endif
