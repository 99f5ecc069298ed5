/*
 * pool.c - the drivers' worker pool (pool.h): threads that open an
 * evaluator once and then run the items of one task after another, the
 * calling thread as a worker too when asked, and a remote (other
 * processes) sharing the task's items.
 *
 * One lock guards the pool's state; the task's ops and the evaluator run
 * outside it (next may block, eval takes milliseconds).  A run ends when
 * next has said "no more" (exhausted), no worker is inside an item and no
 * remote holds one; a stop (an error, an interrupt, a cancelled item)
 * ends it as soon as the items running are finished.
 */
#include "dfle/pool.h"

#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "drive/drive_internal.h"

typedef struct worker {
    dfle_pool *pool;
    int id;
    pthread_t tid;
    void *state;
    double *x, *y;
    dfle_eval_out out;
} worker;

struct dfle_pool {
    const dfle_evaluator *ev;
    dfle_pool_opts o;
    int nworkers; /* w[0] is the caller's when o.caller, then the threads */
    worker *w;
    int started;  /* threads started */
    pthread_mutex_t lock;
    pthread_cond_t work; /* threads: a run started, or quit */
    pthread_cond_t idle; /* the runner: an item ended, a thread opened */
    /* the run (under lock) */
    const dfle_pool_task *task;
    int exhausted, stop, canceled, busy, failed;
    dfle_error err;
    /* the pool */
    int ready, opening, quit;
    int open_failed, open_reported;
    dfle_error open_err;
};

void dfle_pool_opts_default(dfle_pool_opts *o)
{
    memset(o, 0, sizeof *o);
    o->caller = 1;
}

int dfle_evaluator_check(const dfle_evaluator *ev, dfle_error *err)
{
    if (ev == NULL || ev->ops == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "evaluator: no ops table");
    if (ev->ops->version < 1 || ev->ops->version > DFLE_EVALUATOR_VERSION)
        return dfle_error_set(err, DFLE_EINVAL,
                              "evaluator %s: ops version %d, this library knows 1 to %d (set "
                              ".version = DFLE_EVALUATOR_VERSION)",
                              ev->ops->name != NULL ? ev->ops->name : "?", ev->ops->version,
                              DFLE_EVALUATOR_VERSION);
    if (ev->ops->open == NULL || ev->ops->eval == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "evaluator %s: ops table needs open() and eval()",
                              ev->ops->name != NULL ? ev->ops->name : "?");
    return DFLE_OK;
}

static double thread_cpu(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Under the lock: stop the run (the first error is kept).  Returns
 * whether the task's stop is still to be called (by the caller, once it
 * has let go of the lock). */
static int stop_run(dfle_pool *p, int status, const dfle_error *e)
{
    int first = !p->stop;
    p->stop = 1;
    if (status == DFLE_ECANCELED)
        p->canceled = 1;
    else if (status != DFLE_OK && !p->failed) {
        p->failed = status;
        p->err = *e;
        p->err.code = status;
    }
    pthread_cond_broadcast(&p->idle);
    return first && p->task != NULL && p->task->stop != NULL;
}

static int interrupted(const dfle_pool *p)
{
    return p->o.interrupt != NULL && *p->o.interrupt != 0;
}

/* One item by worker w: called and left with the lock held.  Returns 1
 * when it ran one, 0 when there was none to run. */
static int work_one(dfle_pool *p, worker *w)
{
    const dfle_pool_task *t = p->task;
    dfle_error e = {0};
    size_t item = 0;
    int got, st = DFLE_OK, call_stop = 0;

    if (t == NULL || p->exhausted || p->stop)
        return 0;
    if (interrupted(p)) {
        if (stop_run(p, DFLE_ECANCELED, &e)) {
            pthread_mutex_unlock(&p->lock);
            t->stop(t->ud);
            pthread_mutex_lock(&p->lock);
        }
        return 0;
    }
    p->busy++;
    pthread_mutex_unlock(&p->lock);
    got = t->next(t->ud, &item, w->x);
    if (got) {
        double t0;
        for (size_t k = 0; k < p->o.noutputs; k++)
            w->y[k] = NAN;
        w->out.status = DFLE_EVAL_OK;
        w->out.y = w->y;
        w->out.reason[0] = '\0';
        w->out.flags = 0;
        w->out.seconds = -1;
        t0 = thread_cpu();
        st = p->ev->ops->eval(w->state, item, w->x, &w->out, &e);
        if (w->out.seconds < 0)
            w->out.seconds = thread_cpu() - t0;
        if (st == DFLE_OK)
            st = t->done(t->ud, item, &w->out, &e);
    }
    pthread_mutex_lock(&p->lock);
    p->busy--;
    if (!got)
        p->exhausted = 1;
    else if (st != DFLE_OK)
        call_stop = stop_run(p, st, &e);
    pthread_cond_broadcast(&p->idle);
    if (call_stop) {
        pthread_mutex_unlock(&p->lock);
        t->stop(t->ud);
        pthread_mutex_lock(&p->lock);
    }
    return got;
}

static void *worker_main(void *arg)
{
    worker *w = arg;
    dfle_pool *p = w->pool;
    dfle_error e = {0};
    int st = p->ev->ops->open(p->ev->ud, w->id, &w->state, &e);

    pthread_mutex_lock(&p->lock);
    p->opening--;
    if (st != DFLE_OK) {
        if (!p->open_failed) {
            p->open_failed = st;
            p->open_err = e;
            p->open_err.code = st;
        }
        /* A run going on stops: the evaluator broke its promise. */
        if (p->task != NULL && stop_run(p, st, &e)) {
            const dfle_pool_task *t = p->task;
            pthread_mutex_unlock(&p->lock);
            t->stop(t->ud);
            pthread_mutex_lock(&p->lock);
        }
        pthread_cond_broadcast(&p->idle);
        pthread_mutex_unlock(&p->lock);
        return NULL;
    }
    p->ready++;
    pthread_cond_broadcast(&p->idle);
    for (;;) {
        while (!p->quit && !(p->task != NULL && !p->exhausted && !p->stop))
            pthread_cond_wait(&p->work, &p->lock);
        if (p->quit)
            break;
        work_one(p, w);
    }
    pthread_mutex_unlock(&p->lock);
    if (p->ev->ops->close != NULL)
        p->ev->ops->close(w->state);
    return NULL;
}

static int worker_init(dfle_pool *p, worker *w, int id)
{
    w->pool = p;
    w->id = id;
    w->x = calloc(p->o.ninputs ? p->o.ninputs : 1, sizeof *w->x);
    w->y = calloc(p->o.noutputs ? p->o.noutputs : 1, sizeof *w->y);
    return w->x != NULL && w->y != NULL;
}

static void pool_release(dfle_pool *p)
{
    for (int k = 0; k < p->nworkers; k++) {
        free(p->w[k].x);
        free(p->w[k].y);
    }
    pthread_cond_destroy(&p->work);
    pthread_cond_destroy(&p->idle);
    pthread_mutex_destroy(&p->lock);
    free(p->w);
    free(p);
}

int dfle_pool_new(const dfle_evaluator *ev, const dfle_pool_opts *opts, dfle_pool **out,
                  dfle_error *err)
{
    dfle_pool *p;
    int st, first;

    *out = NULL;
    if ((st = dfle_evaluator_check(ev, err)) != DFLE_OK)
        return st;
    if (opts->threads < 0 || (opts->threads == 0 && !opts->caller))
        return dfle_error_set(err, DFLE_EINVAL, "pool: no worker (threads = %d, no caller)",
                              opts->threads);
    p = calloc(1, sizeof *p);
    if (p == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "pool: out of memory");
    p->ev = ev;
    p->o = *opts;
    p->nworkers = opts->threads + (opts->caller != 0);
    p->w = calloc((size_t)p->nworkers, sizeof *p->w);
    pthread_mutex_init(&p->lock, NULL);
    pthread_cond_init(&p->work, NULL);
    pthread_cond_init(&p->idle, NULL);
    if (p->w == NULL) {
        free(p->w);
        p->nworkers = 0;
        pool_release(p);
        return dfle_error_set(err, DFLE_ENOMEM, "pool: out of memory");
    }
    for (int k = 0; k < p->nworkers; k++)
        if (!worker_init(p, &p->w[k], opts->caller ? k : k + 1)) {
            pool_release(p);
            return dfle_error_set(err, DFLE_ENOMEM, "pool: out of memory");
        }
    if (opts->caller) {
        if ((st = ev->ops->open(ev->ud, 0, &p->w[0].state, err)) != DFLE_OK) {
            pool_release(p);
            return st;
        }
        p->ready = 1;
    }
    first = opts->caller ? 1 : 0;
    pthread_mutex_lock(&p->lock);
    for (int k = first; k < p->nworkers; k++) {
        p->opening++;
        if (pthread_create(&p->w[k].tid, NULL, worker_main, &p->w[k]) != 0) {
            p->opening--;
            break;
        }
        p->started++;
    }
    pthread_mutex_unlock(&p->lock);
    if (p->started == 0 && !opts->caller) {
        pool_release(p);
        return dfle_error_set(err, DFLE_EEXTERNAL, "pool: cannot start worker threads");
    }
    *out = p;
    return DFLE_OK;
}

int dfle_pool_ready(dfle_pool *p)
{
    int n;
    pthread_mutex_lock(&p->lock);
    n = p->ready;
    pthread_mutex_unlock(&p->lock);
    return n;
}

/* Wait on p->idle for at most `seconds` (the lock held). */
static void wait_idle(dfle_pool *p, double seconds)
{
    struct timespec ts;
    long ns;
    clock_gettime(CLOCK_REALTIME, &ts);
    ns = ts.tv_nsec + (long)(seconds * 1e9);
    ts.tv_sec += ns / 1000000000L;
    ts.tv_nsec = ns % 1000000000L;
    pthread_cond_timedwait(&p->idle, &p->lock, &ts);
}

int dfle_pool_run(dfle_pool *p, const dfle_pool_task *t, dfle_error *err)
{
    const dfle_remote *rm = p->o.remote;
    int remote = 0, st;
    dfle_error e = {0};

    pthread_mutex_lock(&p->lock);
    if (p->open_failed) {
        p->open_reported = 1;
        e = p->open_err;
        pthread_mutex_unlock(&p->lock);
        if (err != NULL)
            *err = e;
        return e.code;
    }
    p->task = t;
    p->exhausted = p->stop = p->canceled = p->failed = 0;
    pthread_cond_broadcast(&p->work);
    pthread_mutex_unlock(&p->lock);

    if (rm != NULL && rm->ops != NULL && p->ev->key != NULL) {
        dfle_remote_job job;
        job.key = p->ev->key;
        job.workers = p->o.remote_workers;
        job.total = t->total;
        job.ninputs = p->o.ninputs;
        job.noutputs = p->o.noutputs;
        job.task = t;
        remote = rm->ops->begin(rm->ud, &job, &e);
        if (remote < 0) {
            pthread_mutex_lock(&p->lock);
            if (stop_run(p, remote, &e) && t->stop != NULL) {
                pthread_mutex_unlock(&p->lock);
                t->stop(t->ud);
                pthread_mutex_lock(&p->lock);
            }
            pthread_mutex_unlock(&p->lock);
            remote = 0;
        }
    }

    pthread_mutex_lock(&p->lock);
    for (;;) {
        /* The caller works while there is work, ticking after each item. */
        if (p->o.caller)
            while (work_one(p, &p->w[0])) {
                pthread_mutex_unlock(&p->lock);
                if (t->tick != NULL)
                    t->tick(t->ud);
                pthread_mutex_lock(&p->lock);
            }
        if (!p->stop && interrupted(p)) {
            if (stop_run(p, DFLE_ECANCELED, &e) && t->stop != NULL) {
                pthread_mutex_unlock(&p->lock);
                t->stop(t->ud);
                pthread_mutex_lock(&p->lock);
            }
        }
        if (remote) {
            int stop = p->stop, r;
            pthread_mutex_unlock(&p->lock);
            r = rm->ops->poll(rm->ud, stop, &e);
            pthread_mutex_lock(&p->lock);
            if (r < 0) {
                if (stop_run(p, r, &e) && t->stop != NULL) {
                    pthread_mutex_unlock(&p->lock);
                    t->stop(t->ud);
                    pthread_mutex_lock(&p->lock);
                }
                remote = 0;
            } else if (r == 0) {
                /* The others are done; what they gave back runs here. */
                remote = 0;
                if (!p->stop) {
                    p->exhausted = 0;
                    pthread_cond_broadcast(&p->work);
                    continue;
                }
            }
        }
        if (p->busy == 0 && !remote && (p->exhausted || p->stop))
            break;
        /* Nobody can run the items: every thread failed to open. */
        if (p->busy == 0 && !remote && p->ready == 0 && p->opening == 0 && !p->o.caller) {
            stop_run(p, p->open_failed ? p->open_failed : DFLE_ESTATE,
                     p->open_failed ? &p->open_err : &e);
            break;
        }
        wait_idle(p, remote && (p->exhausted || p->ready == 0) ? 0.005 : 0.1);
        if (t->tick != NULL) {
            pthread_mutex_unlock(&p->lock);
            t->tick(t->ud);
            pthread_mutex_lock(&p->lock);
        }
    }
    p->task = NULL;
    if (p->failed) {
        st = p->failed;
        e = p->err;
        if (p->open_failed && st == p->open_failed)
            p->open_reported = 1;
    } else {
        st = p->canceled ? DFLE_ECANCELED : DFLE_OK;
    }
    pthread_mutex_unlock(&p->lock);
    if (st == DFLE_ECANCELED)
        return dfle_error_set(err, st, "interrupted");
    if (st != DFLE_OK && err != NULL)
        *err = e;
    return st;
}

int dfle_pool_free(dfle_pool *p, dfle_error *err)
{
    int st = DFLE_OK;
    if (p == NULL)
        return DFLE_OK;
    pthread_mutex_lock(&p->lock);
    p->quit = 1;
    pthread_cond_broadcast(&p->work);
    pthread_mutex_unlock(&p->lock);
    for (int k = p->o.caller ? 1 : 0; k < p->o.caller + p->started; k++)
        pthread_join(p->w[k].tid, NULL);
    if (p->o.caller && p->ev->ops->close != NULL)
        p->ev->ops->close(p->w[0].state);
    if (p->open_failed && !p->open_reported) {
        st = p->open_failed;
        if (err != NULL)
            *err = p->open_err;
    }
    pool_release(p);
    return st;
}

const char *dfle_eval_status_name(int status)
{
    static const char *const names[DFLE_EVAL_NSTATUS] = {
        "ok", "not_converged", "fit_failed", "nan", "invalid_profile", "outside_prior", "error"};
    return status >= 0 && status < DFLE_EVAL_NSTATUS ? names[status] : "unknown";
}

void dfle_eval_reason(dfle_eval_out *out, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(out->reason, sizeof out->reason, fmt, ap);
    va_end(ap);
    dfle_drive_cut_utf8(out->reason);
}
