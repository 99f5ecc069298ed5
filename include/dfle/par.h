/*
 * par.h - parallel loops as the library's lower layers ask for them
 * (the landscape's sweeps): n independent items, each run once, on
 * whatever threads the caller lends.
 *
 * The library starts no threads of its own.  A caller that wants its
 * work on several cores passes a dfle_par made on the drivers' worker
 * pool (pool.h, dfle_pool_par_new); without one (NULL) every loop runs
 * in the calling thread.  Whoever splits work into items makes the
 * split, and the order its partial results are combined in, depend on
 * the work alone, never on `workers`: results are then the same for any
 * number of threads.
 */
#ifndef DFLE_PAR_H
#define DFLE_PAR_H

#include <stddef.h>

#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One item of a loop; called from any thread, for each item once. */
typedef void (*dfle_par_fn)(void *arg, size_t item);

#define DFLE_PAR_VERSION 1

typedef struct dfle_par_ops {
    int version;      /* DFLE_PAR_VERSION */
    const char *name; /* "pool" */
    /* fn(arg, i) for every i < n, in any order and on any of the
     * workers; returns once every call has returned.  DFLE_OK, or a
     * status with err set when the items could not be run (none then
     * ran partly: the caller runs them itself). */
    int (*run)(void *ud, size_t n, dfle_par_fn fn, void *arg, dfle_error *err);
} dfle_par_ops;

typedef struct dfle_par {
    const dfle_par_ops *ops;
    void *ud;
    int workers; /* threads that take items (>= 1), the caller's included */
} dfle_par;

/* Run the loop on p, or in this thread when p is NULL, has one worker,
 * or n < 2. */
int dfle_par_run(const dfle_par *p, size_t n, dfle_par_fn fn, void *arg, dfle_error *err);

/* Workers of p (1 for NULL). */
int dfle_par_workers(const dfle_par *p);

#ifdef __cplusplus
}
#endif
#endif
