/*
 * dfle_mpi.c - dynamic sharing of ensemble samples across MPI ranks.
 *
 * Protocol (all messages between rank 0 and one other rank r):
 *   0 -> r  TAG_CMD  "E <call>\n<meta>\n<header>": run the script's
 *                    <call>-th dfle.ensemble; "Q": quit.
 *   r -> 0  TAG_REQ  "R" (ready), "W<f><row>" (a row; f = '1' if the
 *                    sample failed, '0' if not), "X<message>" (failed).
 *   0 -> r  TAG_IDX  one unsigned long long: the next sample, 0 = none.
 * Every TAG_REQ message gets exactly one TAG_IDX answer, so a rank that
 * fails mid-way is answered 0 and goes back to waiting for commands.
 * Rank 0 only coordinates and writes; samples run on ranks 1..K-1.
 */
#include "mpi/dfle_mpi.h"

#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <lua.h>

enum { TAG_CMD = 1, TAG_REQ = 2, TAG_IDX = 3 };

static int nranks = 1;
static const dfle_lua_ensemble_host *rank0_host;

int dfle_mpi_init(int *size)
{
    int rank = 0;
    MPI_Init(NULL, NULL);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &nranks);
    *size = nranks;
    return rank;
}

void dfle_mpi_set_host(const dfle_lua_ensemble_host *host) { rank0_host = host; }

/* Receive a whole message of unknown length from `src` with `tag`
 * (NUL-terminated, malloc'd; out of memory aborts the job).  *from:
 * the sender. */
static char *recv_text(int src, int tag, int *from)
{
    MPI_Status st;
    int n;
    char *buf;
    MPI_Probe(src, tag, MPI_COMM_WORLD, &st);
    MPI_Get_count(&st, MPI_CHAR, &n);
    buf = malloc((size_t)n + 1);
    if (buf == NULL) {
        fprintf(stderr, "dfle-mpi: out of memory receiving a message\n");
        MPI_Abort(MPI_COMM_WORLD, 1);
        return NULL;
    }
    MPI_Recv(buf, n, MPI_CHAR, st.MPI_SOURCE, tag, MPI_COMM_WORLD, &st);
    buf[n] = '\0';
    *from = st.MPI_SOURCE;
    return buf;
}

static void send_text(const char *s, int dst, int tag)
{
    MPI_Send(s, (int)strlen(s), MPI_CHAR, dst, tag, MPI_COMM_WORLD);
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int dfle_mpi_remote(void *ud, long long call, const char *meta, const char *header,
                    dfle_ens_file *file, dfle_ens_queue *queue, size_t total, size_t *done,
                    char *msg, size_t msglen)
{
    size_t len = strlen(meta) + strlen(header) + 32, failed = 0;
    char *cmd;
    int active = nranks - 1, error = 0;
    double t0 = now();

    (void)ud;
    *done = 0;
    if (nranks <= 1)
        return 0;
    cmd = malloc(len);
    if (cmd == NULL) {
        snprintf(msg, msglen, "out of memory");
        return -1;
    }
    snprintf(cmd, len, "E %lld\n%s\n%s", call, meta, header);
    for (int r = 1; r < nranks; r++)
        send_text(cmd, r, TAG_CMD);
    free(cmd);
    while (active > 0) {
        int from;
        unsigned long long next = 0;
        size_t i;
        char *m = recv_text(MPI_ANY_SOURCE, TAG_REQ, &from);
        if (m == NULL) {
            if (!error)
                snprintf(msg, msglen, "out of memory");
            error = 1;
        } else if (m[0] == 'W') {
            dfle_error err;
            i = (size_t)strtoull(m + 2, NULL, 10);
            if (dfle_ens_file_append(file, i, m + 2, &err) != DFLE_OK) {
                if (!error)
                    snprintf(msg, msglen, "%s", err.msg);
                error = 1;
            } else {
                (*done)++;
                failed += m[1] == '1';
            }
        } else if (m[0] == 'X') {
            if (!error)
                snprintf(msg, msglen, "rank %d: %s", from, m + 1);
            error = 1;
        }
        free(m);
        if (error)
            dfle_ens_queue_stop(queue);
        if (dfle_ens_queue_next(queue, &i))
            next = i;
        else
            active--;
        MPI_Send(&next, 1, MPI_UNSIGNED_LONG_LONG, from, TAG_IDX, MPI_COMM_WORLD);
        if (rank0_host != NULL && rank0_host->progress != NULL)
            rank0_host->progress(rank0_host->ud, *done, total, failed, now() - t0);
    }
    if (rank0_host != NULL && rank0_host->progress_end != NULL)
        rank0_host->progress_end(rank0_host->ud);
    return error ? -1 : 1;
}

/* A worker rank's side of one ensemble: the message it owes rank 0. */
typedef struct link {
    char *pending; /* "W..." row to send with the next request, or NULL */
    int owes;      /* a request is due (the last answer was an index)   */
} link;

static int link_next(void *ud, size_t *index)
{
    link *lk = ud;
    unsigned long long i;
    send_text(lk->pending != NULL ? lk->pending : "R", 0, TAG_REQ);
    free(lk->pending);
    lk->pending = NULL;
    MPI_Recv(&i, 1, MPI_UNSIGNED_LONG_LONG, 0, TAG_IDX, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    lk->owes = i != 0;
    *index = (size_t)i;
    return i != 0;
}

static int link_put(void *ud, size_t index, const char *row, int failed, char *msg,
                    size_t msglen)
{
    link *lk = ud;
    size_t n = strlen(row);
    (void)index;
    lk->pending = malloc(n + 3);
    if (lk->pending == NULL) {
        snprintf(msg, msglen, "out of memory");
        return -1;
    }
    lk->pending[0] = 'W';
    lk->pending[1] = failed ? '1' : '0';
    memcpy(lk->pending + 2, row, n + 1);
    return 0;
}

int dfle_mpi_worker_loop(const dfle_lua_ensemble_host *host)
{
    for (;;) {
        int from, nargs = 0;
        char *cmd = recv_text(0, TAG_CMD, &from), *meta, *header;
        char msg[DFLE_ERROR_MSG_MAX + 1];
        long long call;
        link lk = {NULL, 1};
        lua_State *L;

        if (cmd == NULL || cmd[0] != 'E') {
            free(cmd);
            return 0; /* "Q" */
        }
        call = strtoll(cmd + 2, NULL, 10);
        meta = strchr(cmd, '\n');
        header = meta != NULL ? strchr(meta + 1, '\n') : NULL;
        msg[0] = 'X';
        msg[1] = '\0';
        L = host->open_state(host->ud, &nargs, msg + 1, sizeof msg - 1);
        if (L != NULL && meta != NULL && header != NULL) {
            *meta++ = '\0';
            *header++ = '\0';
            if (dfle_lua_ensemble_serve(L, nargs, call, host, meta, header, link_next, link_put,
                                        &lk, msg + 1, sizeof msg - 1) == 0)
                lk.owes = 0;
        }
        if (L != NULL)
            lua_close(L);
        if (lk.owes) {
            unsigned long long i;
            send_text(msg, 0, TAG_REQ);
            MPI_Recv(&i, 1, MPI_UNSIGNED_LONG_LONG, 0, TAG_IDX, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        }
        free(lk.pending);
        free(cmd);
    }
}

void dfle_mpi_finish(int rank)
{
    if (rank == 0)
        for (int r = 1; r < nranks; r++)
            send_text("Q", r, TAG_CMD);
    MPI_Finalize();
}
