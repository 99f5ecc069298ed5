/*
 * sensitivity_bootstrap.c - PAWN's bootstrap confidence intervals: B
 * replicates of the analysis on resampled rows, run on opts->threads
 * threads (pthreads), and their percentile intervals.
 *
 * Each replicate is the same block of the one generator's draws whatever
 * the number of threads (boot_run), so the intervals do not depend on
 * it.  A replicate is the analysis of sensitivity_slices.c with the
 * counts of its resample as row multiplicities: no table is materialised
 * and nothing is sorted per replicate.
 */
#include "analysis/sensitivity_internal.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/sampling.h"

/* Percentile intervals from B replicates of D x 6 indices. */
static int percentile_intervals(const double *reps, size_t B, size_t D, double conf,
                                double *lo, double *hi)
{
    double *buf = malloc(B * sizeof *buf);
    double qlo = (1.0 - conf) / 2.0, qhi = (1.0 + conf) / 2.0;

    if (buf == NULL)
        return DFLE_ENOMEM;
    for (size_t i = 0; i < D * DFLE_PAWN_NSTATS; i++) {
        size_t m = 0;
        for (size_t b = 0; b < B; b++) {
            double v = reps[b * D * DFLE_PAWN_NSTATS + i];
            if (!isnan(v))
                buf[m++] = v;
        }
        if (m == 0) {
            lo[i] = hi[i] = NAN;
            continue;
        }
        qsort(buf, m, sizeof *buf, dfle_pawn_compare_doubles);
        lo[i] = dfle_quantile_linear(buf, m, qlo);
        hi[i] = dfle_quantile_linear(buf, m, qhi);
    }
    free(buf);
    return DFLE_OK;
}

/* The bootstrap's replicates, shared by its threads.  Replicate b is
 * always drawn as the b-th block of N draws of the one generator: a
 * thread takes the next replicate and draws its rows under the lock, in
 * replicate order, then analyses it on its own.  So the replicates, and
 * the intervals, do not depend on how many threads there are. */
typedef struct boot_run {
    const pawn_work *w;
    size_t B;
    double *reps;          /* B x D x 6 */
    dfle_rng *rng;
    pthread_mutex_t lock;
    size_t next;           /* the next replicate to draw */
} boot_run;

typedef struct boot_thread {
    boot_run *run;
    pawn_scratch sc;
    uint32_t *draw;        /* N: the rows of the replicate being drawn */
    pthread_t id;
    int started;
} boot_thread;

static void *boot_worker(void *arg)
{
    boot_thread *t = arg;
    boot_run *run = t->run;
    const pawn_work *w = run->w;
    const size_t N = w->N, D = w->D;

    for (;;) {
        size_t b;
        pthread_mutex_lock(&run->lock);
        b = run->next;
        if (b < run->B) {
            run->next++;
            for (size_t i = 0; i < N; i++)
                t->draw[i] = (uint32_t)dfle_rng_below(run->rng, N);
        }
        pthread_mutex_unlock(&run->lock);
        if (b >= run->B)
            break;
        memset(t->sc.mult, 0, N * sizeof *t->sc.mult);
        for (size_t i = 0; i < N; i++)
            t->sc.mult[t->draw[i]]++;
        dfle_pawn_scratch_set_mult(&t->sc, w, t->sc.mult);
        dfle_pawn_analyse(w, &t->sc, t->sc.mult, run->reps + b * D * DFLE_PAWN_NSTATS, NULL,
                          NULL, NULL, NULL, NULL);
    }
    return NULL;
}

/* The replicates and their intervals (sensitivity_internal.h). */
int dfle_pawn_bootstrap(const pawn_work *w, const dfle_pawn_opts *opts, dfle_pawn_result *res,
                        dfle_error *err)
{
    const size_t N = w->N, D = w->D, B = opts->bootstrap;
    size_t nt = opts->threads > 1 ? opts->threads : 1;
    boot_thread *th = NULL;
    boot_run run;
    int st = DFLE_OK, locked = 0;

    if (nt > B)
        nt = B;
    memset(&run, 0, sizeof run);
    run.w = w;
    run.B = B;
    if ((st = dfle_rng_new(opts->seed, &run.rng, err)) != DFLE_OK)
        return st;
    run.reps = malloc(B * D * DFLE_PAWN_NSTATS * sizeof *run.reps);
    th = calloc(nt, sizeof *th);
    if (run.reps == NULL || th == NULL)
        goto nomem;
    for (size_t i = 0; i < nt; i++) {
        th[i].run = &run;
        if (dfle_pawn_scratch_init(&th[i].sc, N, w->S) != DFLE_OK ||
            (th[i].draw = malloc(N * sizeof *th[i].draw)) == NULL)
            goto nomem;
    }
    if (pthread_mutex_init(&run.lock, NULL) != 0) {
        st = dfle_error_set(err, DFLE_ENOMEM, "pawn: cannot create a lock for the bootstrap");
        goto done;
    }
    locked = 1;
    /* Threads that cannot be started leave their share to the others. */
    for (size_t i = 1; i < nt; i++)
        th[i].started = pthread_create(&th[i].id, NULL, boot_worker, &th[i]) == 0;
    boot_worker(&th[0]);
    for (size_t i = 1; i < nt; i++)
        if (th[i].started)
            pthread_join(th[i].id, NULL);
    if (percentile_intervals(run.reps, B, D, opts->conf, res->lo, res->hi) != DFLE_OK)
        goto nomem;
    goto done;
nomem:
    st = dfle_error_set(err, DFLE_ENOMEM, "pawn: out of memory for %zu bootstrap replicates", B);
done:
    if (locked)
        pthread_mutex_destroy(&run.lock);
    for (size_t i = 0; th != NULL && i < nt; i++) {
        dfle_pawn_scratch_free(&th[i].sc);
        free(th[i].draw);
    }
    free(th);
    free(run.reps);
    dfle_rng_free(run.rng);
    return st;
}
