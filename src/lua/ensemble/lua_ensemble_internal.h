/*
 * lua_ensemble_internal.h - what the files of the dfle.ensemble binding
 * share (not installed): lua_ensemble.c (the Lua entry points and the
 * box of C resources they hold), lua_ensemble_spec.c (the ensemble's
 * table checked, the file's meta, comment and header lines),
 * lua_ensemble_sample.c (one sample run into a CSV row),
 * lua_ensemble_result.c (a finished file read back into the result
 * table), lua_ensemble_netcdf.c (ens:write_netcdf),
 * lua_ensemble_pool.c (worker threads and their states) and, below
 * those, lua_ensemble_host.c (a state's host, registry keys, clock).
 *
 * The replay machinery (a worker state that runs the script up to the
 * k-th parallel call and is then handed that call's table) serves every
 * parallel call of the binding: dfle.ensemble here and dfle.invert
 * (src/lua/invert/), which include this header for it.
 */
#ifndef DFLE_LUA_ENSEMBLE_INTERNAL_H
#define DFLE_LUA_ENSEMBLE_INTERNAL_H

#include <pthread.h>
#include <stddef.h>

#include "lua/core/dfle_lua.h"
#include "lua/ensemble/lua_ensemble.h"
#include "dfle/ensemble.h"

#define RUN_BOX "dfle.ensemble_run"
#define RESULT_MT "dfle.ensemble"

/* Registry keys (their addresses are the keys). */
extern const char dfle_lua_ens_worker_key;
extern const char dfle_lua_ens_spec_key;

/* C resources held while Lua code runs: freed by __gc if it raises. */
typedef struct run_box {
    dfle_ens_file *file;
    dfle_ens_queue *queue;
    dfle_ens_table *table;
} run_box;

/* The ensemble's table, checked. */
typedef struct spec {
    lua_Integer n, seed;
    int workers; /* 0: not given */
    int resume;
    size_t limit; /* 0: no limit */
    size_t nparams, noutputs;
} spec;

/* The samples of one ensemble shared by worker threads. */
typedef struct pool {
    const dfle_lua_ensemble_host *host;
    lua_Integer target; /* which dfle.ensemble call of the script */
    const char *meta, *header;
    dfle_ens_file *file;
    dfle_ens_queue *queue;
    pthread_mutex_t lock;
    pthread_cond_t cond;
    size_t done, failed;
    int active;
    int error;
    char msg[DFLE_ERROR_MSG_MAX];
    /* The main state's interrupt flag (dfle_lua_set_interrupt), or NULL:
     * once it is up, no worker takes another sample. */
    const volatile sig_atomic_t *interrupt;
    /* Other processes may share the queue (host->remote_begin): set,
     * the pool asks, and if they take part its main thread polls them
     * while the threads run, and after. */
    int remote;
    int table_workers;     /* the table's `workers` (0: not given)  */
    size_t rdone, rfailed; /* their rows so far (main thread only) */
} pool;

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

/* lua_ensemble_host.c; dfle_lua_set_ensemble_host is in lua_ensemble.h. */

/* Count a parallel call of `kind` (its table at arg) and decide what to
 * do with it (above); *call receives its number among the calls of its
 * kind (0 for a nested call, which is not counted).  When it is the
 * target of a replaying worker, the table is handed over and the script
 * stopped: this does not return. */
int dfle_lua_par_enter(lua_State *L, int kind, int arg, lua_Integer *call);
/* Parallel calls in progress in this state (a sample being run, an
 * inversion evaluating): calls made meanwhile are nested. */
void dfle_lua_par_depth(lua_State *L, int delta);
/* 1 while this state runs inside a parallel call (a sample of an
 * ensemble, an inversion's model): the cores are taken already. */
int dfle_lua_par_inside(lua_State *L);
/* The name of a kind in messages: "dfle.ensemble", "dfle.invert". */
const char *dfle_lua_par_name(int kind);
const dfle_lua_ensemble_host *dfle_lua_ens_host(lua_State *L);
double dfle_lua_ens_now(void);

/* lua_ensemble.c: the box (RUN_BOX) of C resources held while Lua runs. */
int dfle_lua_ens_box_gc(lua_State *L);
run_box *dfle_lua_ens_new_box(lua_State *L);

/* lua_ensemble_spec.c: the ensemble's table and its file's lines. */
void dfle_lua_ens_push_shard_path(lua_State *L, const char *out, size_t i, size_t n);
void dfle_lua_ens_read_spec(lua_State *L, int arg, const char *fn, spec *s,
                            const dfle_lua_ensemble_host *host);

/* lua_ensemble_sample.c: one sample into a row, and the text of a field
 * (a number with 17 digits; any value, quoted as a CSV field when
 * `quote`). */
void dfle_lua_ens_push_number_text(lua_State *L, double v);
void dfle_lua_ens_push_value_text(lua_State *L, int idx, int quote);
int dfle_lua_ens_sample_row(lua_State *L, int ctx, size_t i);

/* lua_ensemble_result.c: a finished file as the result table. */
void dfle_lua_ens_push_result(lua_State *L, const char *fn, const char *path, size_t shard_i,
                              size_t shard_n, lua_Integer ran);

/* lua_ensemble_netcdf.c: set __index of the result metatable (at the
 * top): ens:write_netcdf. */
void dfle_lua_ens_result_methods(lua_State *L);

/* lua_ensemble_pool.c: a worker state from the host (one thread at a
 * time, as the host requires), and the replay in it: run the script (the
 * chunk and nargs arguments on L's stack) up to the target-th call of
 * `kind`, then call serve(spec, ud) in protected mode with that call's
 * table and a light userdata ud.  0, or -1 with a message in msg. */
lua_State *dfle_lua_par_open(const dfle_lua_ensemble_host *host, int *nargs, char *msg,
                             size_t msglen);
int dfle_lua_par_replay(lua_State *L, int nargs, int kind, lua_Integer target,
                        const dfle_lua_ensemble_host *host, lua_CFunction serve, void *ud,
                        char *msg, size_t msglen);
void dfle_lua_ens_run_threads(lua_State *L, pool *pl, int nw, size_t total);

#endif
