/*
 * pool_par.c - parallel loops (par.h) on the worker pool (pool.h): the
 * items of a loop are the pool's items, handed out in order by an
 * atomic counter, and every worker's evaluator calls the loop's function
 * for the item it is given.  The pool, its threads and its evaluator
 * are made once and serve every loop after, so a loop costs a wake-up
 * of the threads, not their start.
 */
#include "dfle/pool.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* The loop under way (one at a time: dfle_par_run is called by the
 * pool's owner only). */
typedef struct par_loop {
    dfle_par_fn fn;
    void *arg;
    size_t n;
    atomic_size_t next;
} par_loop;

struct dfle_pool_par {
    dfle_par par;       /* what callers are given */
    dfle_pool *pool;
    dfle_evaluator ev;
    par_loop loop;
};

static int par_open(void *ud, int worker, void **state, dfle_error *err)
{
    (void)worker;
    (void)err;
    *state = ud; /* every worker reads the loop under way */
    return DFLE_OK;
}

static int par_eval(void *state, size_t index, const double *x, dfle_eval_out *out,
                    dfle_error *err)
{
    par_loop *loop = state;
    (void)x;
    (void)err;
    loop->fn(loop->arg, index);
    out->seconds = 0;
    return DFLE_OK;
}

static const dfle_evaluator_ops par_ops = {DFLE_EVALUATOR_VERSION, "par", par_open, par_eval,
                                           NULL};

static int par_next(void *ud, size_t *item, double *x)
{
    par_loop *loop = ud;
    size_t i = atomic_fetch_add(&loop->next, 1);
    (void)x;
    if (i >= loop->n)
        return 0;
    *item = i;
    return 1;
}

static int par_done(void *ud, size_t item, const dfle_eval_out *out, dfle_error *err)
{
    (void)ud;
    (void)item;
    (void)out;
    (void)err;
    return DFLE_OK;
}

static int par_run(void *ud, size_t n, dfle_par_fn fn, void *arg, dfle_error *err)
{
    dfle_pool_par *pp = ud;
    dfle_pool_task t;
    memset(&t, 0, sizeof t);
    pp->loop.fn = fn;
    pp->loop.arg = arg;
    pp->loop.n = n;
    atomic_store(&pp->loop.next, 0);
    t.next = par_next;
    t.done = par_done;
    t.ud = &pp->loop;
    t.total = n;
    return dfle_pool_run(pp->pool, &t, err);
}

static const dfle_par_ops pool_par_ops = {DFLE_PAR_VERSION, "pool", par_run};

int dfle_pool_par_new(int workers, dfle_pool_par **out, dfle_error *err)
{
    dfle_pool_par *pp;
    dfle_pool_opts o;
    int st;

    *out = NULL;
    if (workers < 1)
        return dfle_error_set(err, DFLE_EINVAL, "threads must be >= 1 (got %d)", workers);
    if ((pp = calloc(1, sizeof *pp)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "threads: out of memory");
    atomic_init(&pp->loop.next, 0);
    pp->ev.ops = &par_ops;
    pp->ev.ud = &pp->loop;
    dfle_pool_opts_default(&o);
    o.threads = workers - 1;
    if ((st = dfle_pool_new(&pp->ev, &o, &pp->pool, err)) != DFLE_OK) {
        free(pp);
        return st;
    }
    pp->par.ops = &pool_par_ops;
    pp->par.ud = pp;
    pp->par.workers = workers;
    *out = pp;
    return DFLE_OK;
}

const dfle_par *dfle_pool_par_get(const dfle_pool_par *pp) { return pp != NULL ? &pp->par : NULL; }

void dfle_pool_par_free(dfle_pool_par *pp)
{
    if (pp == NULL)
        return;
    dfle_pool_free(pp->pool, NULL);
    free(pp);
}
