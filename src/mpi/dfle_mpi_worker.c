/*
 * dfle_mpi_worker.c - a rank > 0 of dfle-mpi: wait for rank 0's tasks
 * and evaluate their items on a pool of threads (dfle/pool.h), the
 * evaluator made by the command from the key rank 0 sends (for an
 * ensemble, a Lua state per thread that replays the script up to the
 * call, as the plain build's threads do).  The rank's main thread alone
 * talks to rank 0 (the protocol is at the top of dfle_mpi.c): it passes
 * items in and results out, asks for items ahead so that no thread
 * waits on an answer, and
 * sends a heartbeat when it has had nothing else to say.  It polls with
 * a growing pause rather than blocking, so a rank between ensembles
 * takes no CPU from the threads of other ranks on its node.
 */
#include "mpi/dfle_mpi.h"

#include <mpi.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "mpi/dfle_mpi_link.h"
#include "mpi/dfle_mpi_wire.h"

/* One task on this rank. */
typedef struct job {
    const dfle_mpi_worker *w;
    dfle_evaluator *ev;  /* made from the key                          */
    char *cmd;           /* the "E" message; the key points into it    */
    unsigned seq;
    size_t ninputs, noutputs;
    int nthreads;
    pthread_t runner;    /* runs the pool                              */
    int started;
    pthread_mutex_t lock;
    pthread_cond_t work; /* for the threads: items came, or stop       */
    pthread_cond_t news; /* for the main thread: a result, the end
                          * (CLOCK_MONOTONIC)                          */
    size_t *stock;       /* items to run: stock[head .. nstock)        */
    double *stock_x;     /* their inputs, ninputs each                 */
    size_t head, nstock, capstock;
    size_t inflight;     /* items received without a result yet        */
    size_t ahead;        /* how many to hold: grows when a thread waits */
    int stopping;
    wire_buf rows;       /* results not yet sent                       */
    int alive;           /* the pool is running                        */
    int error;
    char msg[DFLE_ERROR_MSG_MAX];
    size_t ran;          /* results put                                */
    /* main thread only */
    size_t asked; /* items asked for, not yet received */
    int told;     /* the error has been sent           */
    struct timespec cpu0; /* the process's CPU time at the start */
} job;

static double last_said; /* when this rank last sent rank 0 anything [s] */

static void say(const char *text, size_t len)
{
    dfle_link_post(0, text, len);
    last_said = dfle_link_now();
}

static void say_str(const char *text) { say(text, strlen(text)); }

/* Give up: rank 0 has gone silent (or a message from it broke off). */
static void fatal(const char *why)
{
    char name[MPI_MAX_PROCESSOR_NAME];
    int len = 0;
    memset(name, 0, sizeof name);
    MPI_Get_processor_name(name, &len);
    fprintf(stderr, "dfle-mpi: rank %d (%s): %s; stopping the job\n", dfle_link_rank, name, why);
    fflush(stderr);
    MPI_Abort(MPI_COMM_WORLD, 1);
}

/* ------------------------------------------------------------------ */
/* The pool's task: items from rank 0, results to it.                  */

static int job_next(void *ud, size_t *item, double *x)
{
    job *jb = ud;
    int got = 0;
    pthread_mutex_lock(&jb->lock);
    /* Ends with items or a stop: the main thread stops the job when
     * rank 0 says so, and ends the process if rank 0 falls silent. */
    /* A thread that finds no item waiting: ask further ahead (fast
     * samples, a slow answer), twice as far each time, up to 32 a
     * thread, and wake the main thread to ask now rather than at its
     * next round.  Doubling: a round trip to rank 0 takes a few ms, as
     * long as several fast samples, and each wait it takes to learn
     * that is a thread idle (growing by one a thread, a 200-sample
     * ensemble's other ranks ran half the samples they could). */
    if (jb->head == jb->nstock && !jb->stopping) {
        const size_t most = 32 * (size_t)jb->nthreads;
        jb->ahead = 2 * jb->ahead < most ? 2 * jb->ahead : most;
        pthread_cond_signal(&jb->news);
    }
    while (jb->head == jb->nstock && !jb->stopping)
        pthread_cond_wait(&jb->work, &jb->lock);
    if (!jb->stopping && jb->head < jb->nstock) {
        *item = jb->stock[jb->head];
        memcpy(x, jb->stock_x + jb->head * jb->ninputs, jb->ninputs * sizeof *x);
        jb->head++;
        got = 1;
    }
    pthread_mutex_unlock(&jb->lock);
    return got;
}

static int job_put(void *ud, size_t item, const dfle_eval_out *out, dfle_error *err)
{
    job *jb = ud;
    (void)err;
    pthread_mutex_lock(&jb->lock);
    wire_put_result(&jb->rows, item, out, jb->noutputs);
    jb->inflight--;
    jb->ran++;
    /* Wake the main thread only when the stock runs low: the results go
     * with its next round anyway, and fewer wake-ups cost less CPU. */
    if (2 * (jb->nstock - jb->head) <= jb->ahead)
        pthread_cond_signal(&jb->news);
    pthread_mutex_unlock(&jb->lock);
    return DFLE_OK;
}

static void job_fail(job *jb, const char *msg)
{
    /* under jb->lock */
    if (!jb->error) {
        jb->error = 1;
        snprintf(jb->msg, sizeof jb->msg, "%s", msg);
    }
    jb->stopping = 1;
    pthread_cond_broadcast(&jb->work);
}

static void job_halt(void *ud)
{
    job *jb = ud;
    pthread_mutex_lock(&jb->lock);
    jb->stopping = 1;
    pthread_cond_broadcast(&jb->work);
    pthread_mutex_unlock(&jb->lock);
}

/* The runner thread: the pool on the evaluator, until the items end. */
static void *job_runner(void *arg)
{
    job *jb = arg;
    dfle_pool_opts po;
    dfle_pool_task t;
    dfle_pool *pool = NULL;
    dfle_error err = {0}, e2;
    int st;

    dfle_pool_opts_default(&po);
    po.threads = jb->nthreads;
    po.caller = 0;
    po.ninputs = jb->ninputs;
    po.noutputs = jb->noutputs;
    memset(&t, 0, sizeof t);
    t.next = job_next;
    t.done = job_put;
    t.stop = job_halt;
    t.ud = jb;
    st = dfle_pool_new(jb->ev, &po, &pool, &err);
    if (st == DFLE_OK)
        st = dfle_pool_run(pool, &t, &err);
    if (dfle_pool_free(pool, &e2) != DFLE_OK && st == DFLE_OK) {
        st = e2.code;
        err = e2;
    }
    pthread_mutex_lock(&jb->lock);
    if (st != DFLE_OK && st != DFLE_ECANCELED)
        job_fail(jb, err.msg[0] ? err.msg : "the rank's workers failed");
    jb->alive = 0;
    pthread_cond_signal(&jb->news);
    pthread_mutex_unlock(&jb->lock);
    return NULL;
}

/* ------------------------------------------------------------------ */
/* The main thread's side of a job.                                    */

/* Start the task of "E <seq> <workers> <total> <ninputs> <noutputs>\n<key>"
 * (takes cmd).  A job that cannot start reports its error and ends at
 * its first step. */
static job *job_start(const dfle_mpi_worker *w, char *cmd)
{
    job *jb = calloc(1, sizeof *jb);
    pthread_condattr_t ca;
    char *key;
    int workers = 0;
    size_t total = 0;
    dfle_error err = {0};

    if (jb == NULL) {
        fprintf(stderr, "dfle-mpi: rank %d: out of memory\n", dfle_link_rank);
        MPI_Abort(MPI_COMM_WORLD, 1);
        return NULL;
    }
    jb->w = w;
    jb->cmd = cmd;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &jb->cpu0);
    pthread_mutex_init(&jb->lock, NULL);
    pthread_cond_init(&jb->work, NULL);
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&jb->news, &ca);
    pthread_condattr_destroy(&ca);
    key = strchr(cmd, '\n');
    if (sscanf(cmd, "E %u %d %zu %zu %zu", &jb->seq, &workers, &total, &jb->ninputs,
               &jb->noutputs) != 5 || key == NULL) {
        job_fail(jb, "a malformed message from rank 0");
        return jb;
    }
    key++;
    if (w->make_evaluator(w->ud, key, &jb->ev, &err) != DFLE_OK) {
        job_fail(jb, err.msg);
        return jb;
    }
    jb->nthreads = w->workers > 0   ? w->workers
                   : workers > 0    ? workers
                   : w->cores > 0   ? w->cores
                                    : (int)sysconf(_SC_NPROCESSORS_ONLN);
    if (jb->nthreads < 1)
        jb->nthreads = 1;
    if ((size_t)jb->nthreads > total)
        jb->nthreads = total > 0 ? (int)total : 1;
    jb->ahead = 2 * (size_t)jb->nthreads; /* two a thread; each wait doubles it */
    jb->alive = 1;
    if (pthread_create(&jb->runner, NULL, job_runner, jb) != 0) {
        jb->alive = 0;
        job_fail(jb, "cannot start worker threads");
        return jb;
    }
    jb->started = 1;
    return jb;
}

static void job_free(job *jb)
{
    if (jb->started)
        pthread_join(jb->runner, NULL);
    if (jb->ev != NULL)
        jb->w->free_evaluator(jb->w->ud, jb->ev);
    pthread_cond_destroy(&jb->news);
    pthread_cond_destroy(&jb->work);
    pthread_mutex_destroy(&jb->lock);
    free(jb->stock);
    free(jb->stock_x);
    wire_free(&jb->rows);
    free(jb->cmd);
    free(jb);
}

/* "I <seq>\n<item line>...": items to run. */
static void job_indices(job *jb, const char *m)
{
    const char *p = m + 2;
    char *end;
    unsigned long seq = strtoul(p, &end, 10);
    if (end == p || seq != jb->seq)
        return;
    p = strchr(end, '\n');
    pthread_mutex_lock(&jb->lock);
    for (p = p != NULL ? p + 1 : end + strlen(end); *p != '\0';) {
        size_t item;
        if (jb->nstock == jb->capstock && jb->head > 0) { /* reuse the front first */
            memmove(jb->stock, jb->stock + jb->head, (jb->nstock - jb->head) * sizeof *jb->stock);
            memmove(jb->stock_x, jb->stock_x + jb->head * jb->ninputs,
                    (jb->nstock - jb->head) * jb->ninputs * sizeof *jb->stock_x);
            jb->nstock -= jb->head;
            jb->head = 0;
        }
        if (jb->nstock == jb->capstock) {
            size_t cap = jb->capstock > 0 ? 2 * jb->capstock : 16;
            size_t *s = realloc(jb->stock, cap * sizeof *s);
            double *sx = s == NULL ? NULL
                                   : realloc(jb->stock_x, cap * (jb->ninputs ? jb->ninputs : 1) *
                                                              sizeof *sx);
            if (s != NULL)
                jb->stock = s;
            if (sx == NULL) {
                job_fail(jb, "out of memory");
                break;
            }
            jb->stock_x = sx;
            jb->capstock = cap;
        }
        if (wire_get_item(&p, &item, jb->stock_x + jb->nstock * jb->ninputs, jb->ninputs) != 0) {
            job_fail(jb, "a malformed item from rank 0");
            break;
        }
        if (jb->stopping)
            continue;
        jb->stock[jb->nstock++] = item;
        jb->inflight++;
        jb->asked -= jb->asked > 0;
    }
    pthread_cond_broadcast(&jb->work);
    pthread_mutex_unlock(&jb->lock);
}

static void job_stop(job *jb)
{
    pthread_mutex_lock(&jb->lock);
    jb->stopping = 1;
    jb->inflight -= jb->nstock - jb->head;
    jb->head = jb->nstock = 0;
    pthread_cond_broadcast(&jb->work);
    pthread_mutex_unlock(&jb->lock);
}

/* Send what the threads have for rank 0: results, a request for more
 * items, an error, the end.  Returns 1 when the job has ended. */
static int job_step(job *jb)
{
    char head[96], msg[DFLE_ERROR_MSG_MAX + 32];
    wire_buf rows;
    size_t nrows, want = 0, target;
    struct timespec now;
    int alive, fail;

    pthread_mutex_lock(&jb->lock);
    target = jb->ahead;
    rows = jb->rows;
    nrows = rows.len;
    memset(&jb->rows, 0, sizeof jb->rows);
    if (!jb->stopping && jb->inflight + jb->asked < target)
        want = target - jb->inflight - jb->asked;
    alive = jb->alive;
    fail = jb->error && !jb->told;
    if (fail)
        snprintf(msg, sizeof msg, "X %u %s", jb->seq, jb->msg);
    pthread_mutex_unlock(&jb->lock);
    if (nrows > 0 || want > 0) {
        int hl = snprintf(head, sizeof head, "R %u %zu\n", jb->seq, want);
        char *text = malloc((size_t)hl + nrows);
        if (text == NULL) {
            fprintf(stderr, "dfle-mpi: rank %d: out of memory\n", dfle_link_rank);
            MPI_Abort(MPI_COMM_WORLD, 1);
            return 1;
        }
        memcpy(text, head, (size_t)hl);
        if (nrows > 0)
            memcpy(text + hl, rows.s, nrows);
        say(text, (size_t)hl + nrows);
        free(text);
        jb->asked += want;
    }
    wire_free(&rows);
    if (fail) {
        say_str(msg);
        jb->told = 1;
    }
    if (alive > 0)
        return 0;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
    snprintf(head, sizeof head, "D %u %zu %d %.3f", jb->seq, jb->ran, jb->nthreads,
             (double)(now.tv_sec - jb->cpu0.tv_sec) + 1e-9 * (double)(now.tv_nsec - jb->cpu0.tv_nsec));
    say_str(head);
    return 1;
}

/* Wait for news from the threads, at most `pause` seconds. */
static void job_wait(job *jb, double pause)
{
    struct timespec ts;
    long ns;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    ns = ts.tv_nsec + (long)(pause * 1e9);
    ts.tv_sec += ns / 1000000000L;
    ts.tv_nsec = ns % 1000000000L;
    pthread_mutex_lock(&jb->lock);
    if (jb->alive > 0 && !(jb->error && !jb->told))
        pthread_cond_timedwait(&jb->news, &jb->lock, &ts);
    pthread_mutex_unlock(&jb->lock);
}

/* ------------------------------------------------------------------ */
/* The loop.                                                           */

int dfle_mpi_worker_loop(const dfle_mpi_worker *host)
{
    job *jb = NULL;
    char *waiting = NULL; /* an "E" that came while a job was ending */
    double heard = dfle_link_now(), pause = DFLE_LINK_PAUSE_MIN, t0;
    int quit = 0;

    last_said = heard;
    while (!quit) {
        int from, busy = 0;
        unsigned seq;
        char *m;
        while (!quit && (m = dfle_link_take(0, dfle_link_timeout, &from)) != NULL) {
            heard = dfle_link_now();
            busy = 1;
            switch (m[0]) {
            case 'E':
                if (jb == NULL) {
                    jb = job_start(host, m);
                } else {
                    free(waiting);
                    waiting = m;
                }
                m = NULL;
                break;
            case 'I':
                if (jb != NULL)
                    job_indices(jb, m);
                break;
            case 'S':
                if (sscanf(m, "S %u", &seq) == 1) {
                    if (jb != NULL && jb->seq == seq)
                        job_stop(jb);
                    /* A waiting ensemble already over: it never starts. */
                    if (waiting != NULL && strtoul(waiting + 2, NULL, 10) == seq) {
                        free(waiting);
                        waiting = NULL;
                    }
                }
                break;
            case 'Q':
                quit = 1;
                dfle_link_lost = m[1] == ' ' && m[2] == '1';
                break;
            default: /* "H" */
                break;
            }
            free(m);
        }
        if (!quit && from >= 0)
            fatal("a message from rank 0 broke off");
        if (jb != NULL && job_step(jb)) {
            job_free(jb);
            jb = NULL;
            busy = 1;
            if (waiting != NULL) {
                jb = job_start(host, waiting);
                waiting = NULL;
            }
        }
        if (!quit && dfle_link_now() - heard > dfle_link_timeout) {
            char why[96];
            snprintf(why, sizeof why, "no word from rank 0 for %.0f s", dfle_link_now() - heard);
            fatal(why);
        }
        if (dfle_link_now() - last_said > dfle_link_beat)
            say_str("H");
        dfle_link_progress();
        pause = busy ? DFLE_LINK_PAUSE_MIN : dfle_link_backoff(pause, jb != NULL ? 4e-3 : 2e-2);
        if (quit)
            break;
        if (jb != NULL)
            job_wait(jb, pause);
        else
            dfle_link_nap(pause);
    }
    free(waiting);
    if (jb != NULL) {
        /* Rank 0 is finishing: let the samples running end (each is
         * bounded by its run's own limits), then leave. */
        job_stop(jb);
        while (job_step(jb) == 0)
            job_wait(jb, 0.01);
        job_free(jb);
    }
    t0 = dfle_link_now();
    while (dfle_link_progress() > 0 && dfle_link_now() - t0 < dfle_link_timeout)
        dfle_link_nap(1e-3);
    return 0;
}
