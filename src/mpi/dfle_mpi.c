/*
 * dfle_mpi.c - dfle-mpi's start-up, and rank 0's side: a thread that
 * serves the other ranks while the script runs.
 *
 * Rank 0 runs the script.  When a driver's pool runs a task whose
 * evaluator has a key (an ensemble), rank 0's own workers take items as
 * in the plain build, and the service thread shares the same task with
 * the other ranks, each evaluating items on threads of its own
 * (dfle_mpi_worker.c).  Messages (text, through dfle_mpi_link.c, so no
 * rank ever spins in a blocking MPI call; items and results as
 * dfle_mpi_wire.h writes them):
 *
 *   0 -> r  "E <seq> <workers> <total> <ninputs> <noutputs>\n<key>"
 *                   run task <seq>: the evaluator that <key> names
 *                   (<workers>: what the caller asked, 0 = not given)
 *           "I <seq>\n<item line>..."   items to evaluate
 *           "S <seq>"  take no more items of <seq> (its end, or a stop)
 *           "H"        heartbeat
 *           "Q [1]"    quit (1: a rank was lost, leave without MPI_Finalize)
 *   r -> 0  "R <seq> <want>\n<result line>..."   results, and a request
 *                   for <want> more items
 *           "X <seq> <message>"   the rank failed (its replay, say)
 *           "D <seq> <results> <threads> <cpu>"  its threads have ended
 *                   and every result is sent (<cpu>: seconds the rank
 *                   used on it)
 *           "H"        heartbeat
 *
 * A rank asks for about two items per thread ahead, so its threads
 * never wait for an answer.  Rank 0 ends a task when it has no more
 * items and no rank holds one without a result (or at once when it
 * stops: an error, an interrupt); messages of an ended task are dropped
 * by their <seq>.  Before it announces task k + 1 every rank that took
 * part in k has been sent "S k", so a rank has at most one task waiting
 * while it finishes the last one.
 *
 * Lost ranks: every rank says something at least every dfle_link_beat
 * seconds.  Rank 0 takes a rank silent for the timeout (--rank-timeout)
 * as lost: the items it held go back to the task (the others run them;
 * having no row, a resumed run would too), its later messages are
 * dropped and it is told to quit.  Ranks waiting on a silent rank 0
 * stop the job with a message (dfle_mpi_worker.c).  Under a plain
 * `mpirun` a rank that dies ends the whole job (the others get SIGTERM):
 * rank 0 then stops as on any interrupt, and the rows written, whole
 * lines, are kept.
 */
/* sched_getaffinity and the CPU_* macros. */
#define _GNU_SOURCE

#include "mpi/dfle_mpi.h"

#include <mpi.h>
#include <pthread.h>
#include <sched.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "mpi/dfle_mpi_link.h"
#include "mpi/dfle_mpi_wire.h"

enum { P_IDLE, P_BUSY, P_LOST };

/* Rank 0's view of another rank. */
typedef struct peer {
    int state;
    unsigned seq;          /* the ensemble it was told to run (P_BUSY) */
    double heard, said;    /* when it last sent us, and we it, anything [s] */
    size_t want;           /* items it asked for and was not given yet */
    size_t *given;         /* items it holds without a result */
    size_t ngiven, capgiven;
} peer;

/* The service: rank 0's state shared by its main thread (the script)
 * and the service thread, under `lock`. */
static struct service {
    pthread_t tid;
    pthread_mutex_t lock;
    pthread_cond_t wake; /* CLOCK_MONOTONIC */
    int started;
    /* set by the main thread */
    int quit;              /* 1: finish, 2: leave at once (torn down) */
    int stop, fresh;       /* fresh: `cmd` is still to be announced */
    char *cmd;
    const dfle_pool_task *task;
    size_t ninputs, noutputs;
    unsigned seq;
    /* set by the service thread */
    int active;   /* a task is shared (begin .. poll's last call)        */
    int finished; /* ... and the service no longer touches the task     */
    double finished_at; /* when it finished [s, dfle_link_now]            */
    int error;
    int exhausted; /* the task had nothing for a rank that asked        */
    char msg[DFLE_ERROR_MSG_MAX];
    double *x;    /* ninputs: an item's inputs                           */
    dfle_eval_out out; /* a result read                                  */
    double *y;    /* noutputs                                            */
    char *notes;     /* lines for the main thread to print: each starts
                      * with 'W' (a warning) or 'N' (a note)             */
    size_t nnotes;
    peer *peers;
    char (*nodes)[MPI_MAX_PROCESSOR_NAME]; /* each rank's node          */
    void (*tell)(void *ud, int warning, const char *line);
    void *tell_ud;
} S = {.lock = PTHREAD_MUTEX_INITIALIZER};

/* ------------------------------------------------------------------ */
/* Start-up (every rank).                                              */

/* The processors this rank may use (its binding), shared among the
 * ranks of its node whose bindings overlap it: a rank bound to 4 cores
 * alone runs 4 workers; 3 unbound ranks on 2 cores run 1 each. */
static int share_of_node(void)
{
    cpu_set_t mine, both, *all;
    MPI_Comm node;
    int n, sharing = 0, count;

    if (sched_getaffinity(0, sizeof mine, &mine) != 0) {
        long c = sysconf(_SC_NPROCESSORS_ONLN);
        CPU_ZERO(&mine);
        for (long k = 0; k < c && k < CPU_SETSIZE; k++)
            CPU_SET((int)k, &mine);
    }
    MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node);
    MPI_Comm_size(node, &n);
    all = malloc((size_t)n * sizeof *all);
    if (all == NULL) {
        fprintf(stderr, "dfle-mpi: out of memory at start-up\n");
        MPI_Abort(MPI_COMM_WORLD, 1);
        return 1;
    }
    MPI_Allgather(&mine, (int)sizeof mine, MPI_BYTE, all, (int)sizeof mine, MPI_BYTE, node);
    for (int k = 0; k < n; k++) {
        CPU_AND(&both, &mine, &all[k]);
        sharing += CPU_COUNT(&both) > 0;
    }
    free(all);
    MPI_Comm_free(&node);
    count = CPU_COUNT(&mine) / (sharing > 0 ? sharing : 1);
    return count > 0 ? count : 1;
}

int dfle_mpi_init(double timeout, int *rank, int *size, int *cores, dfle_error *err)
{
    char name[MPI_MAX_PROCESSOR_NAME];
    int provided = 0, len = 0;

    MPI_Init_thread(NULL, NULL, MPI_THREAD_SERIALIZED, &provided);
    MPI_Comm_rank(MPI_COMM_WORLD, rank);
    MPI_Comm_size(MPI_COMM_WORLD, size);
    dfle_link_rank = *rank;
    dfle_link_size = *size;
    dfle_link_timeout = timeout > 0 ? timeout : 60;
    dfle_link_beat = dfle_link_timeout / 4 < 1 ? dfle_link_timeout / 4 : 1;
    *cores = share_of_node();
    memset(name, 0, sizeof name);
    MPI_Get_processor_name(name, &len);
    if (*rank == 0) {
        S.nodes = calloc((size_t)*size, sizeof *S.nodes);
        S.peers = calloc((size_t)*size, sizeof *S.peers);
        if (S.nodes == NULL || S.peers == NULL) {
            fprintf(stderr, "dfle-mpi: out of memory at start-up\n");
            MPI_Abort(MPI_COMM_WORLD, 1);
        }
    }
    MPI_Gather(name, MPI_MAX_PROCESSOR_NAME, MPI_CHAR, S.nodes, MPI_MAX_PROCESSOR_NAME, MPI_CHAR,
               0, MPI_COMM_WORLD);
    /* Rank 0 serves the others from a second thread. */
    if (*size > 1 && provided < MPI_THREAD_SERIALIZED)
        return dfle_error_set(err, DFLE_EEXTERNAL,
                              "this MPI library cannot be called from a second thread "
                              "(MPI_THREAD_SERIALIZED), which dfle-mpi needs on rank 0");
    return DFLE_OK;
}

/* ------------------------------------------------------------------ */
/* The service thread (rank 0); everything here runs under S.lock.     */

static void note(int warning, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* A line for the main thread (flush_notes); dropped if out of memory. */
static void note(int warning, const char *fmt, ...)
{
    char line[DFLE_ERROR_MSG_MAX];
    size_t len;
    char *p;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line + 1, sizeof line - 1, fmt, ap);
    va_end(ap);
    line[0] = warning ? 'W' : 'N';
    len = strlen(line);
    p = realloc(S.notes, S.nnotes + len + 2);
    if (p == NULL)
        return;
    S.notes = p;
    memcpy(S.notes + S.nnotes, line, len);
    S.nnotes += len;
    S.notes[S.nnotes++] = '\n';
    S.notes[S.nnotes] = '\0';
}

static void say(int r, const char *text)
{
    dfle_link_post_str(r, text);
    S.peers[r].said = dfle_link_now();
}

static void set_error(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

static void set_error(const char *fmt, ...)
{
    va_list ap;
    if (S.error)
        return;
    S.error = 1;
    va_start(ap, fmt);
    vsnprintf(S.msg, sizeof S.msg, fmt, ap);
    va_end(ap);
}

/* How long a finished ensemble waits for the other ranks' last word [s]. */
#define DFLE_MPI_DRAIN_S 2.0

static int in_ensemble(const peer *p) { return p->state == P_BUSY && p->seq == S.seq; }

static void give(peer *p, size_t index)
{
    if (p->ngiven == p->capgiven) {
        size_t cap = p->capgiven > 0 ? 2 * p->capgiven : 16;
        size_t *g = realloc(p->given, cap * sizeof *g);
        if (g == NULL) {
            fprintf(stderr, "dfle-mpi: out of memory handing out samples\n");
            MPI_Abort(MPI_COMM_WORLD, 1);
            return;
        }
        p->given = g;
        p->capgiven = cap;
    }
    p->given[p->ngiven++] = index;
}

/* Remove `index` from what p holds; 0 if it did not hold it. */
static int take_back(peer *p, size_t index)
{
    for (size_t k = 0; k < p->ngiven; k++)
        if (p->given[k] == index) {
            p->given[k] = p->given[--p->ngiven];
            return 1;
        }
    return 0;
}

/* The shared task is over for the others: no more items, results of it
 * dropped from now on, and the pool no longer waits for them. */
static void end_ensemble(void)
{
    char text[32];
    snprintf(text, sizeof text, "S %u", S.seq);
    for (int r = 1; r < dfle_link_size; r++)
        if (in_ensemble(&S.peers[r])) {
            say(r, text);
            S.peers[r].ngiven = 0;
            S.peers[r].want = 0;
        }
    S.finished = 1;
    S.finished_at = dfle_link_now();
    S.task = NULL;
}

/* The items p holds go back to the task; how many did. */
static size_t release(peer *p)
{
    size_t back = 0;
    if (S.active && !S.finished && in_ensemble(p)) {
        for (size_t k = 0; k < p->ngiven; k++) {
            dfle_error err;
            if (S.task->give_back == NULL ||
                S.task->give_back(S.task->ud, p->given[k], &err) != DFLE_OK)
                set_error("rank %d's items could not be run again: %s", (int)(p - S.peers),
                          S.task->give_back == NULL ? "the task cannot take them back" : err.msg);
            else
                back++;
        }
        S.exhausted = S.exhausted && back == 0;
    }
    p->ngiven = 0;
    p->want = 0;
    return back;
}

static void lose(int r, const char *why)
{
    peer *p = &S.peers[r];
    size_t back;
    int others = 0;

    if (p->state == P_LOST)
        return;
    back = release(p);
    p->state = P_LOST;
    dfle_link_lost = 1;
    say(r, "Q 1"); /* if it is alive after all, it stops; if not, no harm */
    dfle_link_forget(r);
    for (int k = 1; k < dfle_link_size; k++)
        others += in_ensemble(&S.peers[k]);
    if (back > 0)
        note(1, "rank %d (%s) %s: taken as lost; its %zu sample%s go%s to %s", r, S.nodes[r],
             why, back, back == 1 ? "" : "s", back == 1 ? "es" : "",
             others > 0 ? "the other ranks" : "rank 0's own workers");
    else
        note(1, "rank %d (%s) %s: taken as lost", r, S.nodes[r], why);
    /* No other rank is left in it: the task is rank 0's alone now, whose
     * workers run what is left (again if they had run out of items
     * already: dfle/pool.h). */
    if (others == 0 && S.active && !S.finished)
        end_ensemble();
}

/* "R <seq> <want>\n<result>\n...": results for the task, and a request. */
static void handle_rows(peer *p, char *m)
{
    unsigned seq = 0;
    size_t want = 0;
    const char *line = strchr(m, '\n');

    if (sscanf(m, "R %u %zu", &seq, &want) != 2 || !S.active || S.finished || !in_ensemble(p) ||
        seq != S.seq)
        return; /* an ended task's */
    p->want += want;
    line = line != NULL ? line + 1 : NULL;
    while (line != NULL && *line != '\0' && !S.finished) {
        size_t item;
        dfle_error err;
        S.out.y = S.y;
        if (wire_get_result(&line, &item, &S.out, S.noutputs) != 0) {
            set_error("rank %d (%s) sent a malformed result", (int)(p - S.peers),
                      S.nodes[p - S.peers]);
            break;
        }
        if (take_back(p, item) && S.task->done(S.task->ud, item, &S.out, &err) != DFLE_OK)
            set_error("%s", err.msg);
    }
}

static void handle(int r, char *m)
{
    peer *p = &S.peers[r];
    unsigned seq = 0;

    if (r < 1 || r >= dfle_link_size || p->state == P_LOST)
        return;
    p->heard = dfle_link_now();
    switch (m[0]) {
    case 'R':
        handle_rows(p, m);
        break;
    case 'X':
        if (sscanf(m, "X %u", &seq) == 1 && S.active && !S.finished && in_ensemble(p) &&
            seq == S.seq) {
            const char *text = strchr(m + 2, ' ');
            set_error("rank %d (%s): %s", r, S.nodes[r], text != NULL ? text + 1 : "failed");
        }
        break;
    case 'D': {
        size_t ran = 0;
        double cpu = 0;
        int threads = 0;
        if (sscanf(m, "D %u %zu %d %lf", &seq, &ran, &threads, &cpu) == 4 &&
            p->state == P_BUSY && p->seq == seq) {
            /* Before the end (its threads failed): what it held goes back. */
            release(p);
            p->state = P_IDLE;
            note(0, "rank %d (%s): %zu sample%s on %d thread%s, %.2f s of CPU", r, S.nodes[r],
                 ran, ran == 1 ? "" : "s", threads, threads == 1 ? "" : "s", cpu);
        }
        break;
    }
    default: /* "H" */
        break;
    }
}

/* Hand out what the ranks asked for. */
static void serve_wants(void)
{
    for (int r = 1; r < dfle_link_size; r++) {
        peer *p = &S.peers[r];
        wire_buf b = {0};
        size_t n = 0, item;
        if (!in_ensemble(p) || p->want == 0)
            continue;
        wire_printf(&b, "I %u\n", S.seq);
        /* At most 64 items a message: want is about two per thread. */
        while (p->want > 0 && n < 64 && S.task->next(S.task->ud, &item, S.x)) {
            wire_put_item(&b, item, S.x, S.ninputs);
            give(p, item);
            p->want--;
            n++;
        }
        if (p->want > 0 && n < 64)
            S.exhausted = 1;
        if (n > 0) {
            dfle_link_post(r, b.s, b.len);
            p->said = dfle_link_now();
        }
        wire_free(&b);
    }
}

static void announce(void)
{
    int busy = 0;
    for (int r = 1; r < dfle_link_size; r++) {
        peer *p = &S.peers[r];
        if (p->state == P_LOST)
            continue;
        say(r, S.cmd);
        p->state = P_BUSY;
        p->seq = S.seq;
        p->want = 0;
        p->ngiven = 0;
        busy++;
    }
    free(S.cmd);
    S.cmd = NULL;
    S.fresh = 0;
    S.exhausted = 0;
    if (busy == 0)
        end_ensemble();
}

/* One round: messages in, indices out, the ensemble's end, heartbeats,
 * silent ranks.  Returns whether anything arrived. */
static int serve_round(void)
{
    int arrived = 0, from;
    double now;
    char *m;

    if (S.fresh)
        announce();
    /* Bounded, so that a flood cannot starve the checks below. */
    while (arrived < 1000) {
        m = dfle_link_take(DFLE_LINK_ANY, dfle_link_timeout, &from);
        if (m == NULL && from < 0)
            break;
        arrived++;
        if (m == NULL)
            lose(from, "stopped half-way through a message");
        else
            handle(from, m);
        free(m);
    }
    if (S.active && !S.finished) {
        int held = 0;
        if (!S.stop && !S.error)
            serve_wants();
        for (int r = 1; r < dfle_link_size; r++)
            held += in_ensemble(&S.peers[r]) && S.peers[r].ngiven > 0;
        if (S.stop || S.error || (S.exhausted && held == 0))
            end_ensemble();
    }
    now = dfle_link_now();
    for (int r = 1; r < dfle_link_size; r++) {
        peer *p = &S.peers[r];
        if (p->state == P_LOST)
            continue;
        if (now - p->heard > dfle_link_timeout) {
            char why[64];
            snprintf(why, sizeof why, "has been silent for %.0f s", now - p->heard);
            lose(r, why);
        } else if (now - p->said > dfle_link_beat) {
            say(r, "H");
        }
    }
    dfle_link_progress();
    return arrived > 0;
}

static void *service_main(void *arg)
{
    double pause = DFLE_LINK_PAUSE_MIN, t0;
    (void)arg;
    pthread_mutex_lock(&S.lock);
    while (!S.quit) {
        struct timespec ts;
        long ns;
        pause = serve_round() ? DFLE_LINK_PAUSE_MIN
                              : dfle_link_backoff(pause, S.active && !S.finished ? 2e-3 : 5e-2);
        clock_gettime(CLOCK_MONOTONIC, &ts);
        ns = ts.tv_nsec + (long)(pause * 1e9);
        ts.tv_sec += ns / 1000000000L;
        ts.tv_nsec = ns % 1000000000L;
        if (!S.quit && !S.fresh && !(S.stop && S.active && !S.finished))
            pthread_cond_timedwait(&S.wake, &S.lock, &ts);
    }
    for (int r = 1; r < dfle_link_size; r++)
        if (S.peers[r].state != P_LOST)
            say(r, dfle_link_lost ? "Q 1" : "Q");
    /* Let the quits go out (a rank that died meanwhile gets up to the
     * timeout), unless the job is being torn down. */
    t0 = dfle_link_now();
    while (S.quit == 1 && dfle_link_progress() > 0 && dfle_link_now() - t0 < dfle_link_timeout)
        dfle_link_nap(1e-3);
    pthread_mutex_unlock(&S.lock);
    return NULL;
}

/* ------------------------------------------------------------------ */
/* The host's hooks (rank 0's main thread).                            */

static void flush_notes(void)
{
    char *notes, *line, *save = NULL;
    pthread_mutex_lock(&S.lock);
    notes = S.notes;
    S.notes = NULL;
    S.nnotes = 0;
    pthread_mutex_unlock(&S.lock);
    for (line = notes != NULL ? strtok_r(notes, "\n", &save) : NULL; line != NULL;
         line = strtok_r(NULL, "\n", &save))
        S.tell(S.tell_ud, line[0] == 'W', line + 1);
    free(notes);
}

static int remote_begin(void *ud, const dfle_remote_job *job, dfle_error *err)
{
    size_t len = strlen(job->key) + 128;
    char *cmd = malloc(len);
    double *x = calloc(job->ninputs ? job->ninputs : 1, sizeof *x);
    double *y = calloc(job->noutputs ? job->noutputs : 1, sizeof *y);
    int live = 0;

    (void)ud;
    if (cmd == NULL || x == NULL || y == NULL) {
        free(cmd);
        free(x);
        free(y);
        return dfle_error_set(err, DFLE_ENOMEM, "mpi: out of memory");
    }
    pthread_mutex_lock(&S.lock);
    for (int r = 1; r < dfle_link_size; r++)
        live += S.peers[r].state != P_LOST;
    if (live == 0) {
        pthread_mutex_unlock(&S.lock);
        free(cmd);
        free(x);
        free(y);
        return 0; /* every other rank was lost: this one alone */
    }
    S.seq++;
    snprintf(cmd, len, "E %u %d %zu %zu %zu\n%s", S.seq, job->workers, job->total,
             job->ninputs, job->noutputs, job->key);
    S.cmd = cmd;
    S.fresh = 1;
    S.task = job->task;
    S.ninputs = job->ninputs;
    S.noutputs = job->noutputs;
    free(S.x);
    free(S.y);
    S.x = x;
    S.y = y;
    S.active = 1;
    S.finished = S.stop = S.error = 0;
    S.msg[0] = '\0';
    pthread_cond_signal(&S.wake);
    pthread_mutex_unlock(&S.lock);
    return 1;
}

static int remote_poll(void *ud, int stop, dfle_error *err)
{
    int r;
    (void)ud;
    pthread_mutex_lock(&S.lock);
    if (stop && !S.stop) {
        S.stop = 1;
        pthread_cond_signal(&S.wake);
    }
    r = !S.finished ? 1 : S.error ? -1 : 0;
    /* Finished: the ranks still in it are told to stop and answer with
     * their CPU time once their threads have ended.  Wait a little for
     * those answers, so that what the ensemble cost is reported with it
     * (not at the next ensemble, or never); a rank that does not answer
     * in time is not waited for. */
    if (r == 0 && !S.stop && dfle_link_now() - S.finished_at < DFLE_MPI_DRAIN_S)
        for (int k = 1; k < dfle_link_size && r == 0; k++)
            r = S.peers[k].state == P_BUSY && S.peers[k].seq == S.seq;
    if (r < 0)
        dfle_error_set(err, DFLE_ECALLBACK, "%s", S.msg);
    if (r <= 0)
        S.active = 0;
    pthread_mutex_unlock(&S.lock);
    flush_notes();
    return r < 0 ? DFLE_ECALLBACK : r;
}

static const dfle_remote_ops mpi_remote_ops = {
    .version = DFLE_REMOTE_VERSION,
    .name = "mpi",
    .begin = remote_begin,
    .poll = remote_poll,
};
static const dfle_remote mpi_remote = {&mpi_remote_ops, NULL};

int dfle_mpi_serve(const dfle_remote **remote,
                   void (*tell)(void *ud, int warning, const char *line), void *ud,
                   dfle_error *err)
{
    pthread_condattr_t ca;
    double now = dfle_link_now();

    S.tell = tell;
    S.tell_ud = ud;
    for (int r = 1; r < dfle_link_size; r++)
        S.peers[r].heard = S.peers[r].said = now;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&S.wake, &ca);
    pthread_condattr_destroy(&ca);
    if (pthread_create(&S.tid, NULL, service_main, NULL) != 0)
        return dfle_error_set(err, DFLE_EEXTERNAL,
                              "cannot start the thread that serves the other ranks");
    S.started = 1;
    *remote = &mpi_remote;
    return DFLE_OK;
}

void dfle_mpi_finish(int torn_down)
{
    if (S.started) {
        pthread_mutex_lock(&S.lock);
        S.quit = torn_down ? 2 : 1;
        pthread_cond_signal(&S.wake);
        pthread_mutex_unlock(&S.lock);
        pthread_join(S.tid, NULL);
        flush_notes();
        S.started = 0;
    }
    for (int r = 0; S.peers != NULL && r < dfle_link_size; r++)
        free(S.peers[r].given);
    free(S.peers);
    free(S.nodes);
    free(S.x);
    free(S.y);
    S.peers = NULL;
    S.nodes = NULL;
    S.x = S.y = NULL;
    /* MPI_Finalize waits for every rank: not for one that is gone. */
    if (!torn_down && !dfle_link_lost)
        MPI_Finalize();
}
