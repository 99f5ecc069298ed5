/*
 * lua_drive.h - the Lua binding's side of the driver layer (not
 * installed): what a host program (the dfle command) tells dfle.ensemble
 * and dfle.invert so that they run on worker threads and other
 * processes, and the Lua evaluator another process opens from a key.
 *
 * The drivers themselves are C (dfle/ensemble_run.h, dfle/invert_run.h,
 * dfle/pool.h).  The binding gives them an evaluator whose workers each
 * have a Lua state of their own, made by the host exactly like the main
 * one (libraries, dfle, `arg`, the script loaded), because only the host
 * knows how the script was started; the worker runs the same script up
 * to the same call (doc/ensembles.md, "the replay rule") and then
 * evaluates samples in it.  Without a host (dfle.so in a plain `lua`)
 * every sample runs in the calling state, one after the other.
 * lua_ensemble.h adds the evaluator that other processes (dfle-mpi's
 * ranks) open from the key a rank 0 sends.
 */
#ifndef DFLE_LUA_DRIVE_H
#define DFLE_LUA_DRIVE_H

#include <stddef.h>

#include <lua.h>

#include "dfle/error.h"
#include "dfle/evaluator.h"
#include "dfle/pool.h"

typedef struct dfle_lua_host {
    /* A new state prepared like the main one, with the script's chunk
     * and then its arguments pushed; *nargs receives their count.  On
     * failure NULL and err set.  May be NULL (no workers).  Called from
     * worker threads, one at a time. */
    lua_State *(*open_state)(void *ud, int *nargs, dfle_error *err);
    /* Progress of an ensemble or an inversion (calling thread only; may
     * be NULL). */
    void (*progress)(void *ud, size_t done, size_t total, size_t failed, double elapsed);
    void (*progress_end)(void *ud);
    void *ud;
    int workers;             /* -j N; 0: not given                           */
    int cores;               /* ensemble workers when neither -j nor the
                              * table says: this process's share of its
                              * node (an MPI rank's); 0: all cores.  An
                              * inversion, which other ranks sit out, uses
                              * all cores. */
    size_t shard_i, shard_n; /* --shard i/n; shard_n = 0: whole ensemble     */
    /* Other processes (dfle-mpi's ranks) that share each ensemble's
     * samples, or NULL. */
    const dfle_remote *remote;
} dfle_lua_host;

/* Install (or with NULL remove) the host of state L; h must outlive L. */
void dfle_lua_set_host(lua_State *L, const dfle_lua_host *h);

/* Worker threads for a parallel call (in each process): -j, then the
 * table's `workers` (0: not given), then `cores` (0: none), then all
 * online cores.  host may be NULL. */
int dfle_lua_par_workers(const dfle_lua_host *host, int table_workers, int cores);

#endif
