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
    /* Run the samples of the script's `call`-th dfle.ensemble on other
     * processes (the MPI build): take indices from `queue`, append the
     * rows to `file`, count them in *done.  Returns 1 when it ran them,
     * 0 to let the caller run them locally, -1 on failure (msg).  May
     * be NULL. */
    int (*remote)(void *ud, long long call, const char *meta, const char *header,
                  dfle_ens_file *file, dfle_ens_queue *queue, size_t total, size_t *done,
                  char *msg, size_t msglen);
    void *ud;
    int workers;            /* -j N; 0: not given                          */
    size_t shard_i, shard_n; /* --shard i/n; shard_n = 0: whole ensemble   */
} dfle_lua_ensemble_host;

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
