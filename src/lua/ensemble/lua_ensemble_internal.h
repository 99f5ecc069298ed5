/*
 * lua_ensemble_internal.h - what the files of the dfle.ensemble binding
 * share (not installed): lua_ensemble.c (the Lua entry points),
 * lua_ensemble_sample.c (the ensemble's table, one sample, rows and
 * results), lua_ensemble_pool.c (worker threads and their states) and,
 * below those, lua_ensemble_host.c (a state's host, registry keys, clock).
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
} pool;

typedef struct worker_mode {
    lua_Integer target;
} worker_mode;

/* lua_ensemble_host.c; dfle_lua_set_ensemble_host is in lua_ensemble.h. */
const dfle_lua_ensemble_host *dfle_lua_ens_host(lua_State *L);
double dfle_lua_ens_now(void);
int dfle_lua_ens_box_gc(lua_State *L);
run_box *dfle_lua_ens_new_box(lua_State *L);
void dfle_lua_ens_push_shard_path(lua_State *L, const char *out, size_t i, size_t n);
void dfle_lua_ens_read_spec(lua_State *L, int arg, const char *fn, spec *s,
                            const dfle_lua_ensemble_host *host);
int dfle_lua_ens_sample_row(lua_State *L, int ctx, size_t i);
void dfle_lua_ens_push_result(lua_State *L, const char *fn, const char *path, size_t shard_i,
                              size_t shard_n, lua_Integer ran);
/* Set __index of the result metatable (at the top): ens:write_netcdf. */
void dfle_lua_ens_result_methods(lua_State *L);
void dfle_lua_ens_run_threads(lua_State *L, pool *pl, int nw, size_t total);

#endif
