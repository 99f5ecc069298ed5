/*
 * lua_ensemble_internal.h - what the files of the dfle.ensemble binding
 * share (not installed): lua_ensemble.c (the Lua entry points),
 * lua_ensemble_spec.c (the ensemble's table checked into a context
 * table and the driver's options), lua_ensemble_sample.c (one sample
 * run in Lua: the evaluator's kind), lua_ensemble_result.c (a finished
 * file read back into the result table), lua_ensemble_netcdf.c
 * (ens:write_netcdf).
 *
 * The run itself is the driver's (dfle/ensemble_run.h): the design, the
 * file, the rows, the worker pool.  The binding reads the table, gives
 * the evaluator that runs build and measure, and reads the file back.
 */
#ifndef DFLE_LUA_ENSEMBLE_INTERNAL_H
#define DFLE_LUA_ENSEMBLE_INTERNAL_H

#include <stddef.h>

#include "dfle/ensemble.h"
#include "dfle/ensemble_run.h"
#include "lua/core/dfle_lua.h"
#include "lua/drive/lua_parallel.h"
#include "lua/ensemble/lua_ensemble.h"

#define RUN_BOX "dfle.ensemble_run"
#define RESULT_MT "dfle.ensemble"

/* C resources held while Lua code runs: freed by __gc if it raises. */
typedef struct run_box {
    dfle_ens_table *table;
    char *meta, *header;   /* the driver's texts, pushed then freed      */
    dfle_lua_eval_spec ev; /* the evaluator's texts                     */
    int ev_set;
} run_box;

/* The ensemble's table, checked: the driver's options (their arrays
 * userdata anchored in the context table, their texts anchored there
 * too) and what only the binding uses. */
typedef struct spec {
    dfle_ensemble_opts o;
    int workers;  /* the table's `workers`; 0: not given */
} spec;

/* lua_ensemble.c: the box (RUN_BOX) of C resources held while Lua runs. */
run_box *dfle_lua_ens_new_box(lua_State *L);

/* lua_ensemble_spec.c: read and check the table at arg (for dfle.<fn>)
 * into *s, pushing the context table (build, measure, run, fit, names,
 * outputs, values, out: the file with the shard's suffix, meta, header,
 * identity, and what the options point to). */
void dfle_lua_ens_read_spec(lua_State *L, int arg, const char *fn, spec **s,
                            const dfle_lua_host *host);

/* lua_ensemble_sample.c: the evaluator's kind for dfle.ensemble. */
extern const dfle_lua_kind dfle_lua_ens_kind;

/* lua_ensemble_result.c: a finished file as the result table. */
void dfle_lua_ens_push_result(lua_State *L, const char *fn, const char *path, size_t shard_i,
                              size_t shard_n, lua_Integer ran);

/* lua_ensemble_netcdf.c: set __index of the result metatable (at the
 * top): ens:write_netcdf. */
void dfle_lua_ens_result_methods(lua_State *L);

#endif
