/*
 * lua_invert_pool.c - worker threads that evaluate batches of proposals
 * for dfle.invert, each in a Lua state of its own.
 *
 * A worker is started like an ensemble worker (lua_ensemble_pool.c: the
 * host makes a state, the script is replayed up to this dfle.invert call
 * and hands its table over), builds the same problem and then waits for
 * batches.  A batch is the K/2 proposals of one half-step: the main
 * thread posts it, takes items itself too, and the workers take the
 * rest; each result goes to its item's slot, so which thread evaluated
 * what never shows in the chain.  A worker still replaying when a batch
 * comes simply joins later.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lua/invert/lua_invert_internal.h"

struct inv_pool {
    const dfle_lua_ensemble_host *host;
    lua_Integer target;
    char meta[8192];        /* the main state's identity line        */
    size_t d;
    int nthreads, started;
    pthread_t *tid;
    pthread_mutex_t lock;
    pthread_cond_t work, done_cv;
    /* the batch */
    size_t n, next, ndone;
    const double *x;
    double *lp, *ll;
    unsigned char *st;
    char *msgs;
    double fwd;             /* workers' forward-model seconds        */
    int quit, error;
    char errmsg[DFLE_ERROR_MSG_MAX];
};

static void pool_fail(inv_pool *pl, const char *msg)
{
    pthread_mutex_lock(&pl->lock);
    if (!pl->error) {
        pl->error = 1;
        snprintf(pl->errmsg, sizeof pl->errmsg, "%s", msg);
    }
    pthread_cond_broadcast(&pl->done_cv);
    pthread_mutex_unlock(&pl->lock);
}

/* serve(spec, pool): the worker's side, once handed its table. */
static int invert_serve(lua_State *L)
{
    inv_pool *pl = lua_touserdata(L, 2);
    inv_run *R;
    int ctx;

    inv_read_spec(L, 1, &R);
    ctx = lua_gettop(L);
    lua_getfield(L, ctx, "meta");
    if (strcmp(lua_tostring(L, -1), pl->meta) != 0)
        return luaL_error(L, "worker: the script built a different inversion when run again (the "
                             "script must do the same thing on every run up to dfle.invert)");
    lua_pop(L, 1);
    pthread_mutex_lock(&pl->lock);
    for (;;) {
        size_t i;
        double fwd = 0;
        while (!pl->quit && pl->next >= pl->n)
            pthread_cond_wait(&pl->work, &pl->lock);
        if (pl->quit)
            break;
        i = pl->next++;
        pthread_mutex_unlock(&pl->lock);
        pl->st[i] = (unsigned char)inv_eval(L, ctx, R, pl->x + i * pl->d, &pl->lp[i], &pl->ll[i],
                                            &fwd, pl->msgs + i * INV_MSG, INV_MSG);
        pthread_mutex_lock(&pl->lock);
        pl->fwd += fwd;
        if (++pl->ndone == pl->n)
            pthread_cond_broadcast(&pl->done_cv);
    }
    pthread_mutex_unlock(&pl->lock);
    return 0;
}

static void *worker_thread(void *arg)
{
    inv_pool *pl = arg;
    char msg[DFLE_ERROR_MSG_MAX];
    int nargs = 0;
    lua_State *L;

    msg[0] = '\0';
    L = dfle_lua_par_open(pl->host, &nargs, msg, sizeof msg);
    if (L == NULL) {
        pool_fail(pl, msg[0] ? msg : "cannot create a worker's Lua state");
        return NULL;
    }
    if (dfle_lua_par_replay(L, nargs, DFLE_LUA_PAR_INVERT, pl->target, pl->host, invert_serve,
                            pl, msg, sizeof msg) != 0)
        pool_fail(pl, msg);
    lua_close(L);
    return NULL;
}

int inv_pool_start(lua_State *L, inv_run *R, int nthreads, lua_Integer call, const char *meta,
                   char *msg, size_t msglen)
{
    inv_pool *pl;
    (void)L;
    if (nthreads <= 0)
        return 0;
    if (strlen(meta) >= sizeof pl->meta) {
        snprintf(msg, msglen, "the inversion's identity line is too long for workers");
        return -1;
    }
    pl = calloc(1, sizeof *pl);
    if (pl == NULL || (pl->tid = calloc((size_t)nthreads, sizeof *pl->tid)) == NULL) {
        free(pl);
        snprintf(msg, msglen, "out of memory");
        return -1;
    }
    pl->host = dfle_lua_ens_host(L);
    pl->target = call;
    snprintf(pl->meta, sizeof pl->meta, "%s", meta);
    pl->d = R->d;
    pl->nthreads = nthreads;
    pthread_mutex_init(&pl->lock, NULL);
    pthread_cond_init(&pl->work, NULL);
    pthread_cond_init(&pl->done_cv, NULL);
    R->pool = pl;
    for (; pl->started < nthreads; pl->started++)
        if (pthread_create(&pl->tid[pl->started], NULL, worker_thread, pl) != 0)
            break;
    return 0; /* fewer threads than asked is fine: the main thread evaluates too */
}

int inv_pool_eval(lua_State *L, int ctx, inv_run *R, size_t n, const double *x, double *lp,
                  double *ll, unsigned char *st, char *msgs, char *msg, size_t msglen)
{
    inv_pool *pl = R->pool;
    if (pl == NULL) {
        for (size_t i = 0; i < n; i++)
            st[i] = (unsigned char)inv_eval(L, ctx, R, x + i * R->d, &lp[i], &ll[i],
                                            &R->fwd_seconds, msgs + i * INV_MSG, INV_MSG);
        R->evaluations += n;
        return 0;
    }
    pthread_mutex_lock(&pl->lock);
    pl->x = x;
    pl->lp = lp;
    pl->ll = ll;
    pl->st = st;
    pl->msgs = msgs;
    pl->ndone = 0;
    pl->next = 0;
    pl->n = n;
    pthread_cond_broadcast(&pl->work);
    /* The main thread takes items too, until none is left; items taken
     * by workers are always finished (evaluations never raise), and a
     * worker that failed takes none, so waiting for them ends. */
    while (pl->next < pl->n) {
        size_t i = pl->next++;
        pthread_mutex_unlock(&pl->lock);
        st[i] = (unsigned char)inv_eval(L, ctx, R, x + i * R->d, &lp[i], &ll[i], &R->fwd_seconds,
                                        msgs + i * INV_MSG, INV_MSG);
        pthread_mutex_lock(&pl->lock);
        pl->ndone++;
    }
    while (pl->ndone < pl->n)
        pthread_cond_wait(&pl->done_cv, &pl->lock);
    pl->n = pl->next = 0; /* nothing for workers until the next batch */
    R->evaluations += n;
    if (pl->error) {
        snprintf(msg, msglen, "%s", pl->errmsg);
        pthread_mutex_unlock(&pl->lock);
        return -1;
    }
    pthread_mutex_unlock(&pl->lock);
    return 0;
}

int inv_pool_stop(inv_run *R, char *msg, size_t msglen)
{
    inv_pool *pl = R->pool;
    int rc;
    if (pl == NULL)
        return 0;
    pthread_mutex_lock(&pl->lock);
    pl->quit = 1;
    pthread_cond_broadcast(&pl->work);
    pthread_mutex_unlock(&pl->lock);
    for (int k = 0; k < pl->started; k++)
        pthread_join(pl->tid[k], NULL);
    /* A worker that failed after the last batch (still replaying when
     * the main thread finished) has broken the replay rule all the same:
     * say so whatever the timing. */
    rc = pl->error ? -1 : 0;
    if (rc != 0 && msg != NULL)
        snprintf(msg, msglen, "%s", pl->errmsg);
    R->fwd_seconds += pl->fwd;
    pthread_cond_destroy(&pl->work);
    pthread_cond_destroy(&pl->done_cv);
    pthread_mutex_destroy(&pl->lock);
    free(pl->tid);
    free(pl);
    R->pool = NULL;
    return rc;
}
