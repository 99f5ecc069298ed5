/*
 * lua_ensemble.h - what a host program (the dfle CLI) tells
 * dfle.ensemble so that it can run samples in parallel (not installed).
 *
 * Parallel workers each get a Lua state of their own, made by the host
 * exactly like the main one (libraries, dfle, `arg`, the script loaded),
 * because only the host knows how the script was started.  Without a
 * host (dfle.so loaded by a plain `lua`) ensembles run in the calling
 * state, one sample at a time.
 */
#ifndef DFLE_LUA_ENSEMBLE_H
#define DFLE_LUA_ENSEMBLE_H

#include <stddef.h>

#include <lua.h>

#include "dfle/ensemble.h"

typedef struct dfle_lua_ensemble_host {
    /* A new state prepared like the main one, with the script's chunk
     * and then its arguments pushed; *nargs receives their count.  On
     * failure NULL and a message in msg.  May be NULL (no workers).
     * Called from worker threads, one at a time. */
    lua_State *(*open_state)(void *ud, int *nargs, char *msg, size_t msglen);
    /* Progress of an ensemble (main thread only; may be NULL). */
    void (*progress)(void *ud, size_t done, size_t total, size_t failed, double elapsed);
    void (*progress_end)(void *ud);
    /* Share the samples of the script's `call`-th dfle.ensemble with
     * other processes (the MPI build) while this one runs its own
     * worker threads: they take indices from `queue` and their rows go
     * to `file`.  `workers` is the table's `workers` (0: not given),
     * `total` the samples to run.  begin returns 1 when others take
     * part, 0 when there are none (run here alone), -1 on failure
     * (msg).  Then the main thread calls poll about every 0.1 s, and
     * after its own threads have ended, until it returns 0 (all
     * finished) or -1 (finished with a failure, msg): *done and
     * *failed receive the rows the others have written so far; `stop`
     * (an error or an interrupt here) asks them to take no more
     * samples, and the caller no longer waits for theirs.  A remote
     * failure stops `queue` itself.  Either may be NULL (no MPI). */
    int (*remote_begin)(void *ud, long long call, int workers, size_t total,
                        const char *meta, const char *header, dfle_ens_file *file,
                        dfle_ens_queue *queue, char *msg, size_t msglen);
    int (*remote_poll)(void *ud, int stop, size_t *done, size_t *failed, char *msg,
                       size_t msglen);
    void *ud;
    int workers;            /* -j N; 0: not given                          */
    int cores;              /* ensemble workers when neither -j nor the
                             * table says: this process's share of its
                             * node (an MPI rank's); 0: all cores.  An
                             * inversion, which other ranks sit out, uses
                             * all cores. */
    size_t shard_i, shard_n; /* --shard i/n; shard_n = 0: whole ensemble   */
} dfle_lua_ensemble_host;

/* Worker threads for a parallel call (in each process): -j, then the
 * table's `workers` (0: not given), then `cores` (host->cores for an
 * ensemble, shared with other processes; 0), then all online cores.
 * host may be NULL. */
int dfle_lua_par_workers(const dfle_lua_ensemble_host *host, int table_workers, int cores);

/* Install (or with NULL remove) the host of state L; h must outlive L. */
void dfle_lua_set_ensemble_host(lua_State *L, const dfle_lua_ensemble_host *h);

/* The worker side of a remote driver: in state L (from open_state:
 * chunk and nargs arguments pushed), replay the script up to its
 * `call`-th dfle.ensemble, check that it builds the ensemble of `meta`
 * and `header` (NULL: no check), then run samples: next(ud, &i) gives
 * an index (0 when there are no more), put(ud, i, row, failed, ...)
 * takes its row (non-zero return: stop with its message).  Returns 0,
 * or -1 with a message in msg. */
int dfle_lua_ensemble_serve(lua_State *L, int nargs, long long call,
                            const dfle_lua_ensemble_host *host, const char *meta,
                            const char *header, int (*next)(void *ud, size_t *index),
                            int (*put)(void *ud, size_t index, const char *row, int failed,
                                       char *msg, size_t msglen),
                            void *ud, char *msg, size_t msglen);

#endif
