/*
 * dfle_mpi_worker.c - a rank > 0 of dfle-mpi: wait for rank 0's
 * ensembles and run their samples on threads, each with a Lua state of
 * its own that replays the script up to the call (as the plain build's
 * threads do).  The rank's main thread alone talks to rank 0 (the
 * protocol is at the top of dfle_mpi.c): it passes indices in and rows
 * out, asks for indices ahead so that no thread waits on an answer, and
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

#include <lua.h>

#include "mpi/dfle_mpi_link.h"

/* One ensemble on this rank. */
typedef struct job {
    const dfle_lua_ensemble_host *host;
    char *cmd; /* the "E" message; meta and header point into it */
    const char *meta, *header;
    unsigned seq;
    long long call;
    int nthreads, started;
    pthread_t *tid;
    pthread_mutex_t lock;
    pthread_cond_t work; /* for the threads: indices came, or stop       */
    pthread_cond_t news; /* for the main thread: a row, a thread ended
                          * (CLOCK_MONOTONIC)                             */
    size_t *stock;       /* indices to run: stock[head .. nstock)         */
    size_t head, nstock, capstock;
    size_t inflight;     /* indices received without a row yet            */
    size_t ahead;        /* how many to hold: grows when a thread waits   */
    int stopping;
    char *rows;          /* "<f><row>\n"... not yet sent                   */
    size_t nrows, caprows;
    int alive;           /* threads running                               */
    int error;
    char msg[DFLE_ERROR_MSG_MAX];
    size_t ran;          /* rows put                                      */
    /* main thread only */
    size_t asked; /* indices asked for, not yet received */
    int told;     /* the error has been sent             */
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
/* The threads.                                                        */

static pthread_mutex_t open_lock = PTHREAD_MUTEX_INITIALIZER;

static int job_next(void *ud, size_t *index)
{
    job *jb = ud;
    int got = 0;
    pthread_mutex_lock(&jb->lock);
    /* Ends with indices or a stop: the main thread stops the job when
     * rank 0 says so, and ends the process if rank 0 falls silent. */
    /* A thread that finds no index waiting: ask further ahead (fast
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
        *index = jb->stock[jb->head++];
        got = 1;
    }
    pthread_mutex_unlock(&jb->lock);
    return got;
}

static int job_put(void *ud, size_t index, const char *row, int failed, char *msg,
                   size_t msglen)
{
    job *jb = ud;
    size_t len = strlen(row);
    (void)index;
    pthread_mutex_lock(&jb->lock);
    if (jb->nrows + len + 2 > jb->caprows) {
        size_t cap = 2 * (jb->nrows + len + 2);
        char *p = realloc(jb->rows, cap);
        if (p == NULL) {
            pthread_mutex_unlock(&jb->lock);
            snprintf(msg, msglen, "out of memory");
            return -1;
        }
        jb->rows = p;
        jb->caprows = cap;
    }
    jb->rows[jb->nrows++] = failed ? '1' : '0';
    memcpy(jb->rows + jb->nrows, row, len);
    jb->nrows += len;
    jb->rows[jb->nrows++] = '\n';
    jb->inflight--;
    jb->ran++;
    /* Wake the main thread only when the stock runs low: the rows go
     * with its next round anyway, and fewer wake-ups cost less CPU. */
    if (2 * (jb->nstock - jb->head) <= jb->ahead)
        pthread_cond_signal(&jb->news);
    pthread_mutex_unlock(&jb->lock);
    return 0;
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

static void *job_thread(void *arg)
{
    job *jb = arg;
    char msg[DFLE_ERROR_MSG_MAX];
    int nargs = 0, st = -1;
    lua_State *L;

    msg[0] = '\0';
    /* The host makes states one thread at a time. */
    pthread_mutex_lock(&open_lock);
    L = jb->host->open_state(jb->host->ud, &nargs, msg, sizeof msg);
    pthread_mutex_unlock(&open_lock);
    if (L != NULL) {
        st = dfle_lua_ensemble_serve(L, nargs, jb->call, jb->host, jb->meta, jb->header, job_next,
                                     job_put, jb, msg, sizeof msg);
        lua_close(L);
    }
    pthread_mutex_lock(&jb->lock);
    if (st != 0)
        job_fail(jb, msg[0] ? msg : "cannot create a worker's Lua state");
    jb->alive--;
    pthread_cond_signal(&jb->news);
    pthread_mutex_unlock(&jb->lock);
    return NULL;
}

/* ------------------------------------------------------------------ */
/* The main thread's side of a job.                                    */

/* Start the ensemble of "E <seq> <call> <workers> <total>\n<meta>\n<header>"
 * (takes cmd).  A job that cannot start reports its error and ends at
 * its first step. */
static job *job_start(const dfle_lua_ensemble_host *host, char *cmd)
{
    job *jb = calloc(1, sizeof *jb);
    pthread_condattr_t ca;
    char *meta, *header;
    int workers = 0;
    size_t total = 0;

    if (jb == NULL) {
        fprintf(stderr, "dfle-mpi: rank %d: out of memory\n", dfle_link_rank);
        MPI_Abort(MPI_COMM_WORLD, 1);
        return NULL;
    }
    jb->host = host;
    jb->cmd = cmd;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &jb->cpu0);
    pthread_mutex_init(&jb->lock, NULL);
    pthread_cond_init(&jb->work, NULL);
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&jb->news, &ca);
    pthread_condattr_destroy(&ca);
    meta = strchr(cmd, '\n');
    header = meta != NULL ? strchr(meta + 1, '\n') : NULL;
    if (sscanf(cmd, "E %u %lld %d %zu", &jb->seq, &jb->call, &workers, &total) != 4 ||
        header == NULL) {
        job_fail(jb, "a malformed message from rank 0");
        return jb;
    }
    *meta++ = '\0';
    *header++ = '\0';
    jb->meta = meta;
    jb->header = header;
    jb->nthreads = dfle_lua_par_workers(host, workers, host->cores);
    if ((size_t)jb->nthreads > total)
        jb->nthreads = total > 0 ? (int)total : 1;
    jb->ahead = 2 * (size_t)jb->nthreads; /* two a thread; each wait doubles it */
    jb->tid = malloc((size_t)jb->nthreads * sizeof *jb->tid);
    if (jb->tid == NULL) {
        job_fail(jb, "out of memory");
        return jb;
    }
    pthread_mutex_lock(&jb->lock);
    for (; jb->started < jb->nthreads; jb->started++) {
        if (pthread_create(&jb->tid[jb->started], NULL, job_thread, jb) != 0)
            break;
        jb->alive++;
    }
    if (jb->started == 0)
        job_fail(jb, "cannot start worker threads");
    pthread_mutex_unlock(&jb->lock);
    return jb;
}

static void job_free(job *jb)
{
    for (int k = 0; k < jb->started; k++)
        pthread_join(jb->tid[k], NULL);
    pthread_cond_destroy(&jb->news);
    pthread_cond_destroy(&jb->work);
    pthread_mutex_destroy(&jb->lock);
    free(jb->tid);
    free(jb->stock);
    free(jb->rows);
    free(jb->cmd);
    free(jb);
}

/* "I <seq> <index>...": indices to run. */
static void job_indices(job *jb, const char *m)
{
    const char *p = m + 2;
    char *end;
    unsigned long seq = strtoul(p, &end, 10);
    if (end == p || seq != jb->seq)
        return;
    pthread_mutex_lock(&jb->lock);
    for (p = end;; p = end) {
        size_t i = (size_t)strtoull(p, &end, 10);
        if (end == p)
            break;
        if (jb->stopping)
            continue;
        if (jb->nstock == jb->capstock && jb->head > 0) { /* reuse the front first */
            memmove(jb->stock, jb->stock + jb->head, (jb->nstock - jb->head) * sizeof *jb->stock);
            jb->nstock -= jb->head;
            jb->head = 0;
        }
        if (jb->nstock == jb->capstock) {
            size_t cap = jb->capstock > 0 ? 2 * jb->capstock : 16;
            size_t *s = realloc(jb->stock, cap * sizeof *s);
            if (s == NULL) {
                job_fail(jb, "out of memory");
                break;
            }
            jb->stock = s;
            jb->capstock = cap;
        }
        jb->stock[jb->nstock++] = i;
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

/* Send what the threads have for rank 0: rows, a request for more
 * indices, an error, the end.  Returns 1 when the job has ended. */
static int job_step(job *jb)
{
    char *rows, head[96], msg[DFLE_ERROR_MSG_MAX + 32];
    size_t nrows, want = 0, target;
    struct timespec now;
    int alive, fail;

    pthread_mutex_lock(&jb->lock);
    target = jb->ahead;
    rows = jb->rows;
    nrows = jb->nrows;
    jb->rows = NULL;
    jb->nrows = jb->caprows = 0;
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
            memcpy(text + hl, rows, nrows);
        say(text, (size_t)hl + nrows);
        free(text);
        jb->asked += want;
    }
    free(rows);
    if (fail) {
        say_str(msg);
        jb->told = 1;
    }
    if (alive > 0)
        return 0;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
    snprintf(head, sizeof head, "D %u %zu %d %.3f", jb->seq, jb->ran, jb->started,
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

int dfle_mpi_worker_loop(const dfle_lua_ensemble_host *host)
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
