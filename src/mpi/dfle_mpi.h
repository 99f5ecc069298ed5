/*
 * dfle_mpi.h - the MPI side of `dfle-mpi` (built by `make mpi` only).
 *
 * Rank 0 runs the script; each dfle.ensemble call hands its samples out
 * dynamically to ranks 1..K-1, one index at a time, and writes the rows
 * they send back to its one result file.  Other ranks wait for
 * ensembles, replay the script up to the call (as threads do) and run
 * samples.  See doc/ensembles.md.
 */
#ifndef DFLE_MPI_H
#define DFLE_MPI_H

#include "lua/ensemble/lua_ensemble.h"

/* MPI_Init; returns this rank, *size the number of ranks. */
int dfle_mpi_init(int *size);
/* Rank 0: the host's remote hook (host->remote); `host` gives progress. */
void dfle_mpi_set_host(const dfle_lua_ensemble_host *host);
int dfle_mpi_remote(void *ud, long long call, const char *meta, const char *header,
                    dfle_ens_file *file, dfle_ens_queue *queue, size_t total, size_t *done,
                    char *msg, size_t msglen);
/* Ranks > 0: serve ensembles until rank 0 finishes; returns 0. */
int dfle_mpi_worker_loop(const dfle_lua_ensemble_host *host);
/* Rank 0: tell the other ranks to stop.  Every rank: MPI_Finalize. */
void dfle_mpi_finish(int rank);

#endif
