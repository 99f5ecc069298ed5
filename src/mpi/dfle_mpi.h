/*
 * dfle_mpi.h - the MPI side of `dfle-mpi` (built by `make mpi` only).
 *
 * Rank 0 runs the script; at each dfle.ensemble its worker threads and
 * those of every other rank take samples from one queue, and rank 0
 * writes the one result file.  Other ranks wait for ensembles, replay
 * the script up to the call on each of their threads (as the plain
 * build's threads do) and run samples.  See doc/ensembles.md.
 */
#ifndef DFLE_MPI_H
#define DFLE_MPI_H

#include <stddef.h>

#include "lua/ensemble/lua_ensemble.h"

/* MPI_Init_thread, and what every rank learns at start: *rank, *size
 * (ranks), *cores (the workers this rank runs when neither -j nor the
 * table says: the processors it may use, shared with the ranks of its
 * node that may use the same ones).  `timeout` [s]: silence after which
 * a rank counts as lost (0: 60 s).  0, or -1 with a message (every rank). */
int dfle_mpi_init(double timeout, int *rank, int *size, int *cores, char *msg, size_t msglen);

/* Rank 0 with other ranks: serve them from a thread of its own, and let
 * `host` share its ensembles with them (host->remote_begin and
 * remote_poll).  tell(ud, warning, line) prints a warning (a rank lost)
 * or a note for --verbose (what each rank ran); it is called from the
 * main thread only.  0, or -1 with a message. */
int dfle_mpi_serve(dfle_lua_ensemble_host *host,
                   void (*tell)(void *ud, int warning, const char *line), void *ud, char *msg,
                   size_t msglen);

/* Ranks > 0: run rank 0's ensembles until it says quit; 0. */
int dfle_mpi_worker_loop(const dfle_lua_ensemble_host *host);

/* Every rank at the end: rank 0 tells the others to quit; then
 * MPI_Finalize, unless the job is being torn down (`torn_down`: rank 0
 * was interrupted, as mpirun does when a rank dies) or a rank was lost,
 * when it would wait for ranks that are gone. */
void dfle_mpi_finish(int torn_down);

#endif
