/*
 * pawn.c - PAWN with bootstrap intervals at the size of the paper's
 * empirical-router ensemble (Table G5: 7 inputs, 4000 runs, S = 10,
 * B = 1000, outputs A_df and S_df), on synthetic data of that shape.
 *
 * Issue 15: the bootstrap took as long as the runs it analyses (about
 * 2.4 s) on one thread, a pass over the rows per slice.  Timed here in one
 * run: that path (dfle_pawn_opts.per_slice, 1 thread), one pass per input
 * on 1 thread, and on every core; the three results must be identical,
 * bit for bit, and the line says whether they are.  Best of several
 * repetitions: CPU seconds of the process for the one-thread paths (steady
 * on a loaded machine), wall-clock seconds for the threads, beside their
 * CPU seconds (the work the threads add) and the load average: a
 * wall-clock ratio means something only when the cores are free.
 *
 *   build/bench/pawn [repetitions (3) [threads (all cores)]]
 *
 * Figures only: nothing here asserts on time.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bench.h"
#include "dfle/sampling.h"
#include "dfle/sensitivity.h"

#define N 4000
#define D 7
#define OUTPUTS 2

static double wall_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Inputs uniform on [0, 1); two outputs of different shape, with noise
 * and a few ties (rounded), as steady-state fits give. */
static int make_data(double *x[D], double *y[OUTPUTS])
{
    dfle_rng *rng;
    dfle_error err;
    if (dfle_rng_new(7, &rng, &err) != DFLE_OK)
        return 1;
    for (size_t i = 0; i < N; i++) {
        double a = 0.0, s = 0.0;
        for (int d = 0; d < D; d++) {
            x[d][i] = dfle_rng_uniform(rng);
            a += (double)(d + 1) * x[d][i] * x[d][i];
            s += sin(3.0 * x[d][i]) / (double)(d + 1);
        }
        y[0][i] = round(1e3 * exp(a + 0.2 * dfle_rng_uniform(rng))) / 1e3;
        y[1][i] = s + 0.1 * dfle_rng_uniform(rng);
    }
    dfle_rng_free(rng);
    return 0;
}

/* Both outputs analysed with `o`: the best wall and CPU times of `reps`. */
typedef struct { double wall, cpu; } timing;
static timing time_pawn(const double *const x[D], double *const y[OUTPUTS],
                        const dfle_pawn_opts *o, int reps, dfle_pawn_result res[OUTPUTS])
{
    timing best = {INFINITY, INFINITY};
    for (int r = 0; r < reps; r++) {
        double t0 = wall_seconds(), c0 = cpu_seconds(), dt, dc;
        for (int k = 0; k < OUTPUTS; k++) {
            dfle_error err;
            dfle_pawn_release(&res[k]);
            if (dfle_pawn(N, D, x, y[k], o, &res[k], &err) != DFLE_OK) {
                fprintf(stderr, "pawn bench: %s\n", err.msg);
                exit(1);
            }
        }
        dt = wall_seconds() - t0;
        dc = cpu_seconds() - c0;
        if (dt < best.wall)
            best.wall = dt;
        if (dc < best.cpu)
            best.cpu = dc;
    }
    return best;
}

/* The 1-minute load average (Linux), or -1: timings on a shared machine
 * need it to be read. */
static double load_average(void)
{
    FILE *f = fopen("/proc/loadavg", "r");
    double l = -1.0;
    if (f != NULL) {
        if (fscanf(f, "%lf", &l) != 1)
            l = -1.0;
        fclose(f);
    }
    return l;
}

static int same(const dfle_pawn_result *a, const dfle_pawn_result *b)
{
    const size_t n = D * DFLE_PAWN_NSTATS;
    return memcmp(a->index, b->index, n * sizeof *a->index) == 0 &&
           memcmp(a->lo, b->lo, n * sizeof *a->lo) == 0 &&
           memcmp(a->hi, b->hi, n * sizeof *a->hi) == 0;
}

int main(int argc, char **argv)
{
    int reps = argc > 1 ? atoi(argv[1]) : 3;
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    size_t threads = argc > 2 ? (size_t)atol(argv[2]) : (size_t)(cores > 0 ? cores : 1);
    double *x[D], *y[OUTPUTS];
    dfle_pawn_result old[OUTPUTS], one[OUTPUTS], many[OUTPUTS];
    dfle_pawn_opts o;
    timing t_old, t_one, t_many;
    int identical = 1;

    if (reps < 1)
        reps = 1;
    if (threads < 1)
        threads = 1;
    for (int d = 0; d < D; d++)
        if ((x[d] = malloc(N * sizeof *x[d])) == NULL)
            return 1;
    for (int k = 0; k < OUTPUTS; k++)
        if ((y[k] = malloc(N * sizeof *y[k])) == NULL)
            return 1;
    if (make_data(x, y) != 0)
        return 1;
    memset(old, 0, sizeof old);
    memset(one, 0, sizeof one);
    memset(many, 0, sizeof many);

    dfle_pawn_opts_default(&o);
    o.S = 10;
    o.bootstrap = 1000;
    o.per_slice = 1;
    t_old = time_pawn((const double *const *)x, y, &o, reps, old);
    o.per_slice = 0;
    t_one = time_pawn((const double *const *)x, y, &o, reps, one);
    o.threads = threads;
    t_many = time_pawn((const double *const *)x, y, &o, reps, many);
    for (int k = 0; k < OUTPUTS; k++)
        identical &= same(&old[k], &one[k]) && same(&one[k], &many[k]);

    printf("PAWN + bootstrap (N = %d, %d inputs, S = 10, B = 1000, %d outputs, as Table G5), "
           "CPU time: a pass per slice %.2f s, one pass per input %.2f s (%.1fx); "
           "wall-clock: 1 thread %.2f s, %zu threads %.2f s (%.2fx; CPU %.2f s, %.2fx the "
           "one thread's work), %.1fx over the old path; results identical: %s (target: "
           "identical results, >= 1.8x from 2 threads on 2 free cores; load average %.1f)\n",
           N, D, OUTPUTS, t_old.cpu, t_one.cpu, t_old.cpu / t_one.cpu, t_one.wall, threads,
           t_many.wall, t_one.wall / t_many.wall, t_many.cpu, t_many.cpu / t_one.cpu,
           t_old.wall / t_many.wall, identical ? "yes" : "NO", load_average());

    for (int k = 0; k < OUTPUTS; k++) {
        dfle_pawn_release(&old[k]);
        dfle_pawn_release(&one[k]);
        dfle_pawn_release(&many[k]);
    }
    for (int d = 0; d < D; d++)
        free(x[d]);
    for (int k = 0; k < OUTPUTS; k++)
        free(y[k]);
    return identical ? 0 : 1;
}
