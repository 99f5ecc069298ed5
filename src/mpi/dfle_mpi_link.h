/*
 * dfle_mpi_link.h - how the ranks of dfle-mpi talk (private to src/mpi):
 * text messages on one tag, and no call that waits on another rank.
 *
 * OpenMPI's blocking calls spin a core while they wait, and a rank that
 * has died never answers; so every send is posted (MPI_Isend) and
 * completes in the background, every receive is taken only once it has
 * arrived (MPI_Improbe), and waiting is a sleep between polls.  One
 * thread per process makes these calls (MPI_THREAD_SERIALIZED).
 */
#ifndef DFLE_MPI_LINK_H
#define DFLE_MPI_LINK_H

#include <stddef.h>

/* What every rank knows from the start (dfle_mpi_init sets it). */
extern int dfle_link_rank, dfle_link_size;
/* Seconds without a word from a rank after which it counts as lost;
 * every rank sends something at least every dfle_link_beat seconds. */
extern double dfle_link_timeout, dfle_link_beat;
/* A rank was lost: MPI_Finalize would wait for it (OpenMPI waits on a
 * rank that died while a child process of it was running), so every
 * rank leaves without. */
extern int dfle_link_lost;

/* Polls back off from a short pause to a longer one while nothing
 * happens (a message resets it): fast answers when busy, next to no
 * CPU when idle. */
#define DFLE_LINK_PAUSE_MIN 2e-4
double dfle_link_backoff(double pause, double max);

/* Seconds on a monotonic clock. */
double dfle_link_now(void);
/* Sleep for `seconds` (a poll's pause). */
void dfle_link_nap(double seconds);

/* Send `len` bytes of `text` to rank `dst` (a copy is kept until the
 * send completes).  Out of memory ends the job (MPI_Abort). */
void dfle_link_post(int dst, const char *text, size_t len);
/* Send a NUL-terminated string. */
void dfle_link_post_str(int dst, const char *text);
/* Let sends complete; returns how many are still pending. */
size_t dfle_link_progress(void);
/* Rank `dst` is gone: stop waiting for its pending sends. */
void dfle_link_forget(int dst);

/* A message that has arrived from `src` (or any rank with
 * DFLE_LINK_ANY), NUL-terminated and malloc'd, with its sender in
 * *from; NULL and *from = -1 when none has.  A message whose data stop
 * arriving for `timeout` seconds (its sender died half-way) is dropped:
 * NULL with *from set to the sender. */
#define DFLE_LINK_ANY (-1)
char *dfle_link_take(int src, double timeout, int *from);

#endif
