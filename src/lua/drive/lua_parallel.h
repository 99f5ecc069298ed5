/*
 * lua_parallel.h - what the parallel calls of the binding share
 * (not installed): dfle.ensemble (src/lua/ensemble/) and dfle.invert
 * (src/lua/invert/) on top, this folder below them:
 *
 *   lua_replay.c     the host of a state, the count of parallel calls
 *                    that decides where a worker's replay stops, the
 *                    replay itself
 *   lua_evaluator.c  the Lua evaluator (dfle/evaluator.h) both calls
 *                    hand their driver: worker 0 is the calling state,
 *                    every other worker a state that replayed the
 *                    script; and the one opened from a key (MPI)
 *
 * A worker state runs the script up to the k-th call of its kind; that
 * call, instead of running, hands its table over and stops the script
 * (earlier calls of the kind return their finished results, read from
 * their files).  The kind then reads the table into a context table in
 * the worker's state, checks that it identifies the same call as the
 * main state's (its file's first lines), and evaluates samples with it.
 */
#ifndef DFLE_LUA_PARALLEL_H
#define DFLE_LUA_PARALLEL_H

#include <stddef.h>

#include "dfle/evaluator.h"
#include "lua/core/dfle_lua.h"
#include "lua/drive/lua_drive.h"

/* The kinds of parallel call; each counts its calls separately. */
enum { DFLE_LUA_PAR_ENSEMBLE, DFLE_LUA_PAR_INVERT, DFLE_LUA_PAR_KINDS };

/* What a worker state replays to: the target-th call of `kind`.  Once
 * that call's table is handed over, `serving` is set: parallel calls
 * made while serving (inside a sample's build or measure) run in the
 * worker's own state, one after the other. */
typedef struct worker_mode {
    int kind;
    lua_Integer target;
    int serving;
} worker_mode;

/* What dfle_lua_par_enter decides for a parallel call. */
enum {
    DFLE_LUA_PAR_RUN,     /* run it here, on worker threads if it likes      */
    DFLE_LUA_PAR_NESTED,  /* run it here, in this state only (inside another) */
    DFLE_LUA_PAR_EARLIER  /* a replaying worker passes an earlier call: return
                           * that call's finished result                      */
};

/* --- lua_replay.c --- */

/* Count a parallel call of `kind` (its table at arg) and decide what to
 * do with it (above); *call receives its number among the calls of its
 * kind (0 for a nested call, which is not counted).  When it is the
 * target of a replaying worker, the table is handed over and the script
 * stopped: this does not return. */
int dfle_lua_par_enter(lua_State *L, int kind, int arg, lua_Integer *call);
/* The calls of `kind` counted in L so far, and setting that count: for
 * a host whose workers run a script of their own, which makes one call,
 * the one the main state makes next (the Python package's bridge). */
lua_Integer dfle_lua_par_calls(lua_State *L, int kind);
void dfle_lua_par_set_calls(lua_State *L, int kind, lua_Integer n);
/* Parallel calls in progress in this state (a sample being run, an
 * inversion evaluating): calls made meanwhile are nested. */
void dfle_lua_par_depth(lua_State *L, int delta);
/* 1 while this state runs inside a parallel call (a sample of an
 * ensemble, an inversion's model): the cores are taken already. */
int dfle_lua_par_inside(lua_State *L);
/* The name of a kind in messages: "dfle.ensemble", "dfle.invert". */
const char *dfle_lua_par_name(int kind);
const dfle_lua_host *dfle_lua_host_of(lua_State *L);
/* Whether L is a worker replaying the script or serving its call. */
int dfle_lua_is_worker(lua_State *L);
/* Seconds on a monotonic clock (progress, the calls' elapsed times). */
double dfle_lua_now(void);

/* A worker state from the host (one thread at a time, as the host
 * requires), and the replay in it: run the script (the chunk and nargs
 * arguments on L's stack) in worker mode *wm up to the target-th call of
 * wm->kind, and leave that call's table alone on the stack, wm serving
 * from then on (wm must outlive L's use as a worker).  DFLE_OK, or a
 * status with err ("worker: the script failed before reaching ..."). */
lua_State *dfle_lua_par_open(const dfle_lua_host *host, int *nargs, dfle_error *err);
int dfle_lua_par_replay(lua_State *L, int nargs, worker_mode *wm, const dfle_lua_host *host,
                        dfle_error *err);

/* --- lua_evaluator.c --- */

/* What a kind gives the Lua evaluator. */
typedef struct dfle_lua_kind {
    int kind;            /* DFLE_LUA_PAR_ENSEMBLE, ...                    */
    const char *name;    /* the evaluator's name: "lua.ensemble"          */
    /* prepare(table): in a worker's state, the call's table read into
     * its context table, returned; its field `identity` (the file's
     * first lines) must be the main state's. */
    lua_CFunction prepare;
    const char *what;    /* in messages: "ensemble", "inversion"        */
    /* sample(ctx, job): one evaluation (job: a light userdata
     * dfle_lua_job) into job->out; may raise: the sample is then an
     * error, its reason the error value. */
    lua_CFunction sample;
    int raw_numbers;     /* an error value that is a number is a reason
                          * written as a number (DFLE_EVAL_REASON_NUMBER) */
    int gc_step;         /* a collector step after each sample          */
} dfle_lua_kind;

typedef struct dfle_lua_job {
    size_t index;
    const double *x;
    dfle_eval_out *out;
} dfle_lua_job;

/* The Lua evaluator of one parallel call, set up by the call in the
 * calling state: the kind, the host, the calling state and its context
 * table (worker 0, or NULL: every worker replays), the call's number
 * and identity.  Fill it with dfle_lua_evaluator_init, then hand
 * dfle_lua_evaluator_of to the driver. */
typedef struct dfle_lua_eval_spec {
    const dfle_lua_kind *kind;
    const dfle_lua_host *host;
    lua_State *main;
    int main_ctx;
    lua_Integer call;
    char *identity;     /* malloc'd */
    char *key;          /* malloc'd: "dfle.lua <kind> <call>\n<identity>" */
    dfle_evaluator ev;
} dfle_lua_eval_spec;

/* Fill *s (identity copied); DFLE_ENOMEM.  Free with
 * dfle_lua_evaluator_release. */
int dfle_lua_evaluator_init(dfle_lua_eval_spec *s, const dfle_lua_kind *kind,
                            const dfle_lua_host *host, lua_State *main, int main_ctx,
                            lua_Integer call, const char *identity, dfle_error *err);
void dfle_lua_evaluator_release(dfle_lua_eval_spec *s);

/* The text of a field value: integers as integers, floats with 17
 * digits, other values as text, quoted when `quote` (quotes doubled;
 * line breaks become spaces either way). */
void dfle_lua_push_field_text(lua_State *L, int idx, int quote);

/* The evaluator of `kind` another process opens from the key a Lua
 * evaluator of that kind sent (dfle_lua_eval_spec.key): no calling
 * state, every worker replays.  *s is released with
 * dfle_lua_evaluator_release.  DFLE_EINVAL for a key that is not one of
 * this kind's. */
int dfle_lua_evaluator_from_key(dfle_lua_eval_spec *s, const dfle_lua_kind *kind,
                                const dfle_lua_host *host, const char *key, dfle_error *err);

#endif
