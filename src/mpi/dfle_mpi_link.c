/*
 * dfle_mpi_link.c - posted sends, probed receives and naps: the only
 * MPI point-to-point calls of dfle-mpi (see dfle_mpi_link.h for why
 * nothing here waits on another rank).
 */
#include "mpi/dfle_mpi_link.h"

#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { TAG_TEXT = 1 };

/* A send in flight: the request and the copy it reads from. */
typedef struct outgoing {
    MPI_Request req;
    char *buf;
    int dst;
} outgoing;

static outgoing *out;
static size_t nout, capout;

int dfle_link_rank, dfle_link_size = 1;
double dfle_link_timeout = 60, dfle_link_beat = 1;
int dfle_link_lost;

double dfle_link_backoff(double pause, double max)
{
    return 2 * pause < max ? 2 * pause : max;
}

double dfle_link_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void dfle_link_nap(double seconds)
{
    struct timespec ts;
    ts.tv_sec = (time_t)seconds;
    ts.tv_nsec = (long)((seconds - (double)ts.tv_sec) * 1e9);
    nanosleep(&ts, NULL);
}

static void out_of_memory(void)
{
    fprintf(stderr, "dfle-mpi: out of memory for a message between ranks\n");
    MPI_Abort(MPI_COMM_WORLD, 1);
}

void dfle_link_post(int dst, const char *text, size_t len)
{
    outgoing *o;
    if (nout == capout) {
        size_t cap = capout > 0 ? 2 * capout : 16;
        outgoing *p = realloc(out, cap * sizeof *p);
        if (p == NULL) {
            out_of_memory();
            return;
        }
        out = p;
        capout = cap;
    }
    o = &out[nout];
    o->buf = malloc(len > 0 ? len : 1);
    if (o->buf == NULL) {
        out_of_memory();
        return;
    }
    memcpy(o->buf, text, len);
    o->dst = dst;
    MPI_Isend(o->buf, (int)len, MPI_CHAR, dst, TAG_TEXT, MPI_COMM_WORLD, &o->req);
    nout++;
}

void dfle_link_post_str(int dst, const char *text) { dfle_link_post(dst, text, strlen(text)); }

size_t dfle_link_progress(void)
{
    size_t k = 0;
    for (size_t i = 0; i < nout; i++) {
        int done = 0;
        MPI_Test(&out[i].req, &done, MPI_STATUS_IGNORE);
        if (done)
            free(out[i].buf);
        else
            out[k++] = out[i];
    }
    nout = k;
    return nout;
}

void dfle_link_forget(int dst)
{
    size_t k = 0;
    for (size_t i = 0; i < nout; i++) {
        if (out[i].dst == dst) {
            /* The send may still read its buffer: release the request,
             * keep (leak) the copy. */
            MPI_Request_free(&out[i].req);
        } else {
            out[k++] = out[i];
        }
    }
    nout = k;
}

char *dfle_link_take(int src, double timeout, int *from)
{
    MPI_Message m;
    MPI_Status st;
    MPI_Request req;
    int flag = 0, n = 0;
    double t0;
    char *buf;

    *from = -1;
    MPI_Improbe(src == DFLE_LINK_ANY ? MPI_ANY_SOURCE : src, TAG_TEXT, MPI_COMM_WORLD, &flag, &m,
                &st);
    if (!flag)
        return NULL;
    *from = st.MPI_SOURCE;
    MPI_Get_count(&st, MPI_CHAR, &n);
    buf = malloc((size_t)n + 1);
    if (buf == NULL) {
        out_of_memory();
        return NULL;
    }
    /* A long message comes in pieces after the match; its sender may
     * die before the last one. */
    MPI_Imrecv(buf, n, MPI_CHAR, &m, &req);
    flag = 0;
    t0 = dfle_link_now();
    for (double pause = 1e-5;; pause = dfle_link_backoff(pause, 1e-3)) {
        MPI_Test(&req, &flag, MPI_STATUS_IGNORE);
        if (flag)
            break;
        if (dfle_link_now() - t0 > timeout) {
            MPI_Request_free(&req); /* the buffer is leaked with it */
            return NULL;
        }
        dfle_link_nap(pause);
    }
    buf[n] = '\0';
    return buf;
}
