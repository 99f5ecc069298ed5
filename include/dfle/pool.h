/*
 * pool.h - the one worker pool of the drivers: worker threads, each with
 * an evaluator opened once (evaluator.h), that run the items of a task
 * (the samples of an ensemble, the proposals of a half-step), and other
 * processes that take part through a remote (the MPI driver).
 *
 * Determinism: which worker runs an item is not fixed (a slow worker, or
 * one still opening, takes fewer), where its result goes is: every result
 * reaches the task with its item number, and the task puts it in that
 * item's place (a row of a file, a slot of the half-step).  With an
 * evaluator that is a pure function of its inputs the results are then
 * the same for any number of workers, threads or processes.
 *
 * Interrupts: once the flag in opts.interrupt is up no worker takes
 * another item; items running finish (those an evaluator cut short say
 * so: DFLE_ECANCELED) and dfle_pool_run returns DFLE_ECANCELED.  A
 * cancelled item never reaches the task as a result.
 */
#ifndef DFLE_POOL_H
#define DFLE_POOL_H

#include <signal.h>
#include <stddef.h>

#include "dfle/error.h"
#include "dfle/evaluator.h"
#include "dfle/par.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What a pool runs: items handed out by next, results taken by done.
 * Every op is called from several threads at once (the pool's workers,
 * a remote's service thread) and must be thread-safe. */
typedef struct dfle_pool_task {
    /* The next item: 1 with its number in *item and its ninputs inputs in
     * x; 0 when there is none (the task is done, or stopped).  May block
     * (an MPI rank waiting for indices) as long as stop makes it return. */
    int (*next)(void *ud, size_t *item, double *x);
    /* The result of an item (out->y has noutputs values).  Nonzero (a
     * status, err set): the pool stops with that error. */
    int (*done)(void *ud, size_t item, const dfle_eval_out *out, dfle_error *err);
    /* Optional.  An item handed out that will have no result (a remote
     * process was lost): next hands it out again.  0 or a status. */
    int (*give_back)(void *ud, size_t item, dfle_error *err);
    /* Optional.  Make next return 0 from now on (called when the pool
     * stops on an error or an interrupt). */
    void (*stop)(void *ud);
    /* Optional.  Called in the thread running dfle_pool_run after each
     * item that thread ran, and about every 0.1 s while it waits: progress. */
    void (*tick)(void *ud);
    void *ud;
    size_t total; /* items next will hand out, about (a remote sizes its
                   * workers by it)                                      */
} dfle_pool_task;

/* ---- Other processes: a remote pool ------------------------------- */

#define DFLE_REMOTE_VERSION 1

/* What a remote is told when a run starts. */
typedef struct dfle_remote_job {
    const char *key;      /* the evaluator's key (evaluator.h): how the
                           * other processes open the same evaluator       */
    int workers;          /* workers each should run (0: its own default) */
    size_t total;         /* items the task will hand out, about           */
    size_t ninputs, noutputs;
    const dfle_pool_task *task; /* next, done, give_back: the remote calls
                                 * them from a thread of its own            */
} dfle_remote_job;

typedef struct dfle_remote_ops {
    int version;      /* DFLE_REMOTE_VERSION */
    const char *name; /* "mpi" */
    /* The run of `job` starts: share its items with the other processes.
     * 1: they take part; 0: there are none (the pool runs alone); or a
     * negative status with err set. */
    int (*begin)(void *ud, const dfle_remote_job *job, dfle_error *err);
    /* While they take part, about every 5-100 ms: 1 while they still
     * hold items; 0 once every item they took has its result (or was
     * given back); a negative status (err set) when they failed.  `stop`
     * (an error or an interrupt here): take no more items, and end
     * without waiting for theirs.  After 0 or an error the remote no
     * longer calls the task. */
    int (*poll)(void *ud, int stop, dfle_error *err);
} dfle_remote_ops;

typedef struct dfle_remote {
    const dfle_remote_ops *ops;
    void *ud;
} dfle_remote;

/* ---- The pool ------------------------------------------------------ */

typedef struct dfle_pool dfle_pool;

typedef struct dfle_pool_opts {
    int threads;     /* worker threads to start (>= 0), workers 1..threads */
    int caller;      /* nonzero: the thread running dfle_pool_run is a
                      * worker too, worker 0, its evaluator opened by
                      * dfle_pool_new in that thread                       */
    size_t ninputs;  /* x per item                                         */
    size_t noutputs; /* y per item                                         */
    const volatile sig_atomic_t *interrupt; /* may be NULL                 */
    const dfle_remote *remote; /* other processes (may be NULL): used only
                                * with an evaluator that has a key          */
    int remote_workers;        /* dfle_remote_job.workers                   */
} dfle_pool_opts;

void dfle_pool_opts_default(dfle_pool_opts *o); /* no threads, the caller works */

/* A pool of opts->threads threads (and the caller), each opening ev in
 * its own thread; threads that open slowly (a script replayed) join the
 * runs as they become ready.  ev must outlive the pool.  DFLE_EINVAL for
 * a pool with no worker or a bad evaluator, the caller's own open error,
 * DFLE_ENOMEM; a thread that cannot be started is no error while another
 * worker is left. */
int dfle_pool_new(const dfle_evaluator *ev, const dfle_pool_opts *opts, dfle_pool **out,
                  dfle_error *err);

/* Run task t until next has nothing more and every item taken has its
 * result, with the remote too when one takes part (and again here, if
 * the remote gave items back after this process had run out).  Returns
 * DFLE_OK; DFLE_ECANCELED (interrupted: what finished reached done, the
 * rest did not run); or the first error of an evaluator, of done or of
 * the remote (the others stop, items running finish).  A worker whose
 * open failed stops every run from then on with its error. */
int dfle_pool_run(dfle_pool *p, const dfle_pool_task *t, dfle_error *err);

/* Evaluators opened so far (the caller's included). */
int dfle_pool_ready(dfle_pool *p);

/* Stop the threads (each finishes opening first), close every
 * evaluator, free the pool.  DFLE_OK, or the error of a worker that
 * failed to open after the last run: it broke the evaluator's promise
 * all the same.  Accepts NULL. */
int dfle_pool_free(dfle_pool *p, dfle_error *err);

/* ---- Parallel loops on a pool ------------------------------------- */

/* A pool of `workers` threads (the caller's included: workers - 1 are
 * started) that runs the loops of par.h, for the layers below the
 * drivers (dfle_landscape_set_par).  Its loops run one at a time, from
 * the thread that made it.  DFLE_EINVAL for workers < 1, DFLE_ENOMEM. */
typedef struct dfle_pool_par dfle_pool_par;
int dfle_pool_par_new(int workers, dfle_pool_par **out, dfle_error *err);
const dfle_par *dfle_pool_par_get(const dfle_pool_par *pp);
void dfle_pool_par_free(dfle_pool_par *pp); /* accepts NULL */

#ifdef __cplusplus
}
#endif
#endif
