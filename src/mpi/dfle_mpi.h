/*
 * dfle_mpi.h - the MPI driver of `dfle-mpi` (built by `make mpi` only): a
 * remote pool of the driver layer (dfle/pool.h).
 *
 * Rank 0 runs the script.  When a driver's pool runs a task whose
 * evaluator has a key (dfle/evaluator.h), the remote of rank 0 announces
 * it to every other rank, hands them items from the same task and gives
 * their results to it, while rank 0's own workers take items too.  The
 * other ranks make the evaluator from the key (the command does: the Lua
 * binding replays the script up to the call the key names), run it on a
 * pool of their own threads and send the results back.  Nothing here
 * knows Lua.  See doc/ensembles.md, "MPI".
 */
#ifndef DFLE_MPI_H
#define DFLE_MPI_H

#include <stddef.h>

#include "dfle/error.h"
#include "dfle/evaluator.h"
#include "dfle/pool.h"

/* MPI_Init_thread, and what every rank learns at start: *rank, *size
 * (ranks), *cores (the workers this rank runs when neither -j nor the
 * table says: the processors it may use, shared with the ranks of its
 * node that may use the same ones).  `timeout` [s]: silence after which
 * a rank counts as lost (0: 60 s).  0, or a status with err (every rank). */
int dfle_mpi_init(double timeout, int *rank, int *size, int *cores, dfle_error *err);

/* Rank 0 with other ranks: serve them from a thread of its own; *remote
 * receives the remote (dfle/pool.h) that shares a run's items with them.
 * tell(ud, warning, line) prints a warning (a rank lost) or a note for
 * --verbose (what each rank ran); it is called from the thread polling
 * the remote only.  0, or a status with err. */
int dfle_mpi_serve(const dfle_remote **remote,
                   void (*tell)(void *ud, int warning, const char *line), void *ud,
                   dfle_error *err);

/* What a rank > 0 needs to run rank 0's work. */
typedef struct dfle_mpi_worker {
    /* The evaluator that rank 0's key names (*ev valid until free). */
    int (*make_evaluator)(void *ud, const char *key, dfle_evaluator **ev, dfle_error *err);
    void (*free_evaluator)(void *ud, dfle_evaluator *ev);
    void *ud;
    int workers; /* threads (-j); 0: what rank 0 says, else `cores`     */
    int cores;   /* this rank's share of its node (dfle_mpi_init)        */
} dfle_mpi_worker;

/* Ranks > 0: run rank 0's work until it says quit; 0. */
int dfle_mpi_worker_loop(const dfle_mpi_worker *w);

/* Every rank at the end: rank 0 tells the others to quit; then
 * MPI_Finalize, unless the job is being torn down (`torn_down`: rank 0
 * was interrupted, as mpirun does when a rank dies) or a rank was lost,
 * when it would wait for ranks that are gone. */
void dfle_mpi_finish(int torn_down);

#endif
