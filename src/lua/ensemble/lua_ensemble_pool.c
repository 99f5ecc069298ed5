/*
 * lua_ensemble_pool.c - worker threads, each with a Lua state of its
 * own made by the host, replaying the script up to its ensemble call and
 * then running samples from a shared queue (lua_ensemble.c); in the MPI
 * build the host shares that queue with other processes meanwhile, and
 * the pool's main thread polls them.  The replay itself
 * (dfle_lua_par_open, dfle_lua_par_replay) serves dfle.invert's workers
 * too (src/lua/invert/lua_invert_pool.c), and the serving of a remote
 * feed (dfle_lua_ensemble_serve) the threads of other MPI ranks.
 */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "lua/ensemble/lua_ensemble_internal.h"

/* ------------------------------------------------------------------ */
/* Worker threads.                                                     */

static pthread_mutex_t open_lock = PTHREAD_MUTEX_INITIALIZER;

static void pool_fail(pool *pl, const char *msg)
{
    pthread_mutex_lock(&pl->lock);
    if (!pl->error) {
        pl->error = 1;
        snprintf(pl->msg, sizeof pl->msg, "%s", msg);
    }
    pthread_mutex_unlock(&pl->lock);
    dfle_ens_queue_stop(pl->queue);
}

/* Where a worker gets sample indices and puts rows: the local pool, or
 * a remote driver (MPI, through dfle_lua_ensemble_serve). */
typedef struct feed {
    lua_Integer target;
    const dfle_lua_ensemble_host *host;
    const char *meta, *header; /* the main state's, to compare; may be NULL */
    int (*next)(void *ud, size_t *index);
    int (*put)(void *ud, size_t index, const char *row, int failed, char *msg, size_t msglen);
    void *ud;
} feed;

/* replay_main(job, chunk, args...): runs protected in the worker's state. */
typedef struct replay_job {
    int kind;
    lua_CFunction serve;
    void *ud;
} replay_job;

static int replay_main(lua_State *L)
{
    const replay_job *jb = lua_touserdata(L, 1);
    int nargs = lua_gettop(L) - 2, st;
    worker_mode *wm;

    st = lua_pcall(L, nargs, 0, 0);
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &dfle_lua_ens_spec_key) != LUA_TTABLE) {
        if (st != LUA_OK)
            return luaL_error(L, "worker: the script failed before reaching %s: %s",
                              dfle_lua_par_name(jb->kind),
                              lua_tostring(L, -2) ? lua_tostring(L, -2) : "(no message)");
        return luaL_error(L, "worker: the script ended without reaching the same %s call (the "
                             "script must do the same thing on every run up to it)",
                          dfle_lua_par_name(jb->kind));
    }
    lua_rawgetp(L, LUA_REGISTRYINDEX, &dfle_lua_ens_worker_key);
    wm = lua_touserdata(L, -1);
    lua_pop(L, 1);
    wm->serving = 1;
    lua_pushcfunction(L, jb->serve);
    lua_insert(L, -2);
    lua_pushlightuserdata(L, jb->ud);
    lua_call(L, 2, 0);
    return 0;
}

int dfle_lua_par_replay(lua_State *L, int nargs, int kind, lua_Integer target,
                        const dfle_lua_ensemble_host *host, lua_CFunction serve, void *ud,
                        char *msg, size_t msglen)
{
    worker_mode wm;
    replay_job jb;
    int st = 0;

    wm.kind = kind;
    wm.target = target;
    wm.serving = 0;
    jb.kind = kind;
    jb.serve = serve;
    jb.ud = ud;
    dfle_lua_set_ensemble_host(L, host);
    lua_pushlightuserdata(L, &wm);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &dfle_lua_ens_worker_key);
    /* stack: chunk, args -> replay_main, job, chunk, args */
    lua_pushcfunction(L, replay_main);
    lua_insert(L, 1);
    lua_pushlightuserdata(L, &jb);
    lua_insert(L, 2);
    if (lua_pcall(L, nargs + 2, 0, 0) != LUA_OK) {
        const char *m = lua_tostring(L, -1);
        snprintf(msg, msglen, "%s", m ? m : "worker failed");
        st = -1;
    }
    lua_pushnil(L);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &dfle_lua_ens_worker_key);
    return st;
}

lua_State *dfle_lua_par_open(const dfle_lua_ensemble_host *host, int *nargs, char *msg,
                             size_t msglen)
{
    lua_State *L;
    pthread_mutex_lock(&open_lock);
    L = host->open_state(host->ud, nargs, msg, msglen);
    pthread_mutex_unlock(&open_lock);
    return L;
}

/* An ensemble worker, once handed its table (serve(spec, feed)): build
 * the same design and run the samples the feed gives. */
static int ensemble_serve(lua_State *L)
{
    const feed *fd = lua_touserdata(L, 2);
    spec s;
    size_t i;
    int ctx;
    char msg[DFLE_ERROR_MSG_MAX];

    dfle_lua_ens_read_spec(L, 1, "ensemble", &s, fd->host);
    ctx = lua_gettop(L);
    lua_getfield(L, ctx, "meta");
    lua_getfield(L, ctx, "header");
    if (fd->meta != NULL &&
        (strcmp(lua_tostring(L, -2), fd->meta) != 0 || strcmp(lua_tostring(L, -1), fd->header) != 0))
        return luaL_error(L, "worker: the script built a different ensemble when run again (the "
                             "script must do the same thing on every run up to dfle.ensemble)");
    lua_pop(L, 2);
    while (fd->next(fd->ud, &i)) {
        int failed = dfle_lua_ens_sample_row(L, ctx, i);
        if (fd->put(fd->ud, i, lua_tostring(L, -1), failed, msg, sizeof msg) != 0)
            return luaL_error(L, "%s", msg);
        lua_pop(L, 1);
    }
    return 0;
}

/* Run a worker in L (chunk and nargs arguments on the stack): replay
 * the script in worker mode, then serve the feed.  0, or -1 with msg. */
static int run_worker(lua_State *L, int nargs, const feed *fd, char *msg, size_t msglen)
{
    return dfle_lua_par_replay(L, nargs, DFLE_LUA_PAR_ENSEMBLE, fd->target, fd->host,
                               ensemble_serve, (void *)fd, msg, msglen);
}

int dfle_lua_ensemble_serve(lua_State *L, int nargs, long long call,
                            const dfle_lua_ensemble_host *host, const char *meta,
                            const char *header, int (*next)(void *ud, size_t *index),
                            int (*put)(void *ud, size_t index, const char *row, int failed,
                                       char *msg, size_t msglen),
                            void *ud, char *msg, size_t msglen)
{
    feed fd;
    fd.target = (lua_Integer)call;
    fd.host = host;
    fd.meta = meta;
    fd.header = header;
    fd.next = next;
    fd.put = put;
    fd.ud = ud;
    return run_worker(L, nargs, &fd, msg, msglen);
}

static int pool_next(void *ud, size_t *index)
{
    pool *pl = ud;
    if (pl->interrupt != NULL && *pl->interrupt) {
        dfle_ens_queue_stop(pl->queue);
        return 0;
    }
    return dfle_ens_queue_next(pl->queue, index);
}

static int pool_put(void *ud, size_t index, const char *row, int failed, char *msg,
                    size_t msglen)
{
    pool *pl = ud;
    dfle_error err;
    if (dfle_ens_file_append(pl->file, index, row, &err) != DFLE_OK) {
        snprintf(msg, msglen, "%s", err.msg);
        return -1;
    }
    pthread_mutex_lock(&pl->lock);
    pl->done++;
    pl->failed += (size_t)(failed != 0);
    pthread_cond_signal(&pl->cond);
    pthread_mutex_unlock(&pl->lock);
    return 0;
}

static void *worker_thread(void *arg)
{
    pool *pl = arg;
    char msg[DFLE_ERROR_MSG_MAX];
    int nargs = 0;
    lua_State *L;
    feed fd;

    msg[0] = '\0';
    L = dfle_lua_par_open(pl->host, &nargs, msg, sizeof msg);
    if (L == NULL) {
        pool_fail(pl, msg[0] ? msg : "cannot create a worker's Lua state");
    } else {
        fd.target = pl->target;
        fd.host = pl->host;
        fd.meta = pl->meta;
        fd.header = pl->header;
        fd.next = pool_next;
        fd.put = pool_put;
        fd.ud = pl;
        if (run_worker(L, nargs, &fd, msg, sizeof msg) != 0)
            pool_fail(pl, msg);
        lua_close(L);
    }
    pthread_mutex_lock(&pl->lock);
    pl->active--;
    pthread_cond_signal(&pl->cond);
    pthread_mutex_unlock(&pl->lock);
    return NULL;
}

int dfle_lua_par_workers(const dfle_lua_ensemble_host *host, int table_workers, int cores)
{
    if (host != NULL && host->workers > 0)
        return host->workers;
    if (table_workers > 0)
        return table_workers;
    if (cores > 0)
        return cores;
    return dfle_lua_cores();
}

/* Start nw worker threads into tid; how many started (0: pl->error). */
static int start_workers(pool *pl, pthread_t *tid, int nw)
{
    int started = 0;
    pthread_mutex_lock(&pl->lock);
    pl->active = nw;
    pthread_mutex_unlock(&pl->lock);
    for (; started < nw; started++)
        if (pthread_create(&tid[started], NULL, worker_thread, pl) != 0)
            break;
    pthread_mutex_lock(&pl->lock);
    pl->active -= nw - started;
    if (started == 0 && !pl->error) {
        pl->error = 1;
        snprintf(pl->msg, sizeof pl->msg, "cannot start worker threads");
    }
    pthread_mutex_unlock(&pl->lock);
    return started;
}

/* Run the queue on `nw` threads, and with the other processes that
 * share it (pl->remote) until they too have finished; the first error
 * is left in pl->error and pl->msg. */
void dfle_lua_ens_run_threads(lua_State *L, pool *pl, int nw, size_t total)
{
    pthread_t *tid = lua_newuserdatauv(L, (size_t)nw * sizeof *tid, 0);
    const dfle_lua_ensemble_host *h = pl->host;
    double t0 = dfle_lua_ens_now();
    int started = 0, remote = 0;

    /* From here on nothing raises until the other processes are done
     * with the file and the queue (remote_poll returned 0 or -1). */
    if (pl->remote) {
        remote = h->remote_begin(h->ud, (long long)pl->target, pl->table_workers, total,
                                 pl->meta, pl->header, pl->file, pl->queue, pl->msg,
                                 sizeof pl->msg);
        if (remote < 0) {
            pl->error = 1;
            lua_pop(L, 1);
            return;
        }
    }
    pthread_mutex_init(&pl->lock, NULL);
    pthread_cond_init(&pl->cond, NULL);
    started = start_workers(pl, tid, nw);
    for (;;) {
        size_t left;
        pthread_mutex_lock(&pl->lock);
        while (pl->active > 0 || remote) {
            struct timespec ts;
            size_t done = pl->done, failed = pl->failed;
            int stop = pl->error;
            /* Wake often once only the other processes are left: their end
             * is seen by polling, not signalled. */
            long wait_ns = pl->active > 0 ? 100000000L : 5000000L;
            pthread_mutex_unlock(&pl->lock);
            /* Interrupted: no new samples; those running here finish and
             * count, the other processes' are not waited for. */
            if (dfle_lua_interrupted(L)) {
                dfle_ens_queue_stop(pl->queue);
                stop = 1;
            }
            if (remote) {
                char msg[DFLE_ERROR_MSG_MAX];
                int r = h->remote_poll(h->ud, stop, &pl->rdone, &pl->rfailed, msg, sizeof msg);
                if (r < 0)
                    pool_fail(pl, msg);
                remote = r > 0;
            }
            if (h->progress != NULL)
                h->progress(h->ud, done + pl->rdone, total, failed + pl->rfailed,
                            dfle_lua_ens_now() - t0);
            pthread_mutex_lock(&pl->lock);
            clock_gettime(CLOCK_REALTIME, &ts);
            ts.tv_nsec += wait_ns;
            if (ts.tv_nsec >= 1000000000L) {
                ts.tv_sec++;
                ts.tv_nsec -= 1000000000L;
            }
            if (pl->active > 0 || remote)
                pthread_cond_timedwait(&pl->cond, &pl->lock, &ts);
        }
        pthread_mutex_unlock(&pl->lock);
        for (int k = 0; k < started; k++)
            pthread_join(tid[k], NULL);
        /* The last other process was lost after these threads had run
         * out of samples, and its samples came back to the queue: run
         * them here.  A round needs samples given back, which only a
         * lost process gives, so there are as many rounds as processes
         * at most. */
        left = pl->error || dfle_lua_interrupted(L) ? 0 : dfle_ens_queue_pending(pl->queue);
        if (left == 0)
            break;
        started = start_workers(pl, tid, (size_t)nw < left ? nw : (int)left);
    }
    if (h->progress_end != NULL)
        h->progress_end(h->ud);
    pthread_cond_destroy(&pl->cond);
    pthread_mutex_destroy(&pl->lock);
    lua_pop(L, 1);
}
