/*
 * drainage.c - flow-routing speed and memory on random-noise grids, the
 * landscape model's worst case (about one cell in nine is a pit): every
 * edge a base level, depressions routed through the basin graph
 * (DFLE_DRAINAGE_CARVE), re-routing the same object as a model would at
 * each time step.  Reports CPU seconds per routing (best and median of
 * several), the routing's memory in bytes per cell, and the exponent of
 * a least-squares fit t ~ n^p over the sizes.  Without depressions
 * (KEEP: D8, flats, donors, stack, area only) for comparison.
 *
 *   build/bench/drainage [repetitions [side ...]]   (default 5; 250 500 1000 2000)
 *
 * Figures only: nothing here asserts on time.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "dfle/drainage.h"

#include "bench.h"

typedef struct result {
    double best, median, bytes_per_cell;
    dfle_drainage_counts counts;
} result;

/* Route z `reps` times on one object (after a first, sizing call). */
static int time_routing(size_t side, const double *z, enum dfle_drainage_depressions dep,
                        int reps, result *res)
{
    dfle_drainage_opts o;
    dfle_drainage *dr;
    dfle_error err;
    double *t = malloc((size_t)reps * sizeof *t);
    int st;

    dfle_drainage_opts_default(&o);
    o.nx = o.ny = side;
    o.dx = o.dy = 10.0;
    for (int s = 0; s < 4; s++)
        o.edge[s] = DFLE_DRAINAGE_BASE_LEVEL;
    o.depressions = dep;
    if (t == NULL || (st = dfle_drainage_new(&o, &dr, &err)) != DFLE_OK) {
        fprintf(stderr, "drainage bench: %s\n", t == NULL ? "out of memory" : err.msg);
        free(t);
        return 1;
    }
    st = dfle_drainage_route(dr, z, &err);
    for (int r = 0; r < reps && st == DFLE_OK; r++) {
        double t0 = cpu_seconds();
        st = dfle_drainage_route(dr, z, &err);
        t[r] = cpu_seconds() - t0;
    }
    if (st != DFLE_OK) {
        fprintf(stderr, "drainage bench: %s\n", err.msg);
    } else {
        qsort(t, (size_t)reps, sizeof *t, by_value);
        res->best = t[0];
        res->median = t[reps / 2];
        res->bytes_per_cell = (double)dfle_drainage_memory(dr) / (double)(side * side);
        res->counts = dfle_drainage_get_counts(dr);
    }
    dfle_drainage_free(dr);
    free(t);
    return st != DFLE_OK;
}


int main(int argc, char **argv)
{
    static const size_t default_sides[] = {250, 500, 1000, 2000};
    size_t sides[16];
    int n_sides = 0, reps = argc > 1 ? atoi(argv[1]) : 5;
    double cells[16], carve_t[16], keep_t[16];
    uint64_t x = BENCH_NOISE_SEED; /* one stream over all grids */

    if (reps < 1)
        reps = 1;
    for (int a = 2; a < argc && n_sides < 16; a++)
        sides[n_sides++] = (size_t)strtoul(argv[a], NULL, 10);
    if (n_sides == 0)
        for (size_t s = 0; s < sizeof default_sides / sizeof *default_sides; s++)
            sides[n_sides++] = default_sides[s];

    printf("Flow routing on random noise, every edge a base level, CPU s per routing "
           "(best / median of %d):\n", reps);
    printf("  %-11s %9s %16s %9s %14s %9s %10s\n", "grid", "cells", "CARVE s", "B/cell",
           "cells/s", "pits", "KEEP s");
    for (int k = 0; k < n_sides; k++) {
        size_t n = sides[k] * sides[k];
        double *z = malloc(n * sizeof *z);
        result carve, keep;
        if (z == NULL) {
            fprintf(stderr, "drainage bench: no memory for %zu cells\n", n);
            return 1;
        }
        bench_noise(z, n, &x);
        if (time_routing(sides[k], z, DFLE_DRAINAGE_CARVE, reps, &carve) != 0 ||
            time_routing(sides[k], z, DFLE_DRAINAGE_KEEP, reps, &keep) != 0) {
            free(z);
            return 1;
        }
        free(z);
        cells[k] = (double)n;
        carve_t[k] = carve.best;
        keep_t[k] = keep.best;
        printf("  %5zu^2     %9zu %7.4f / %6.4f %9.1f %14.3g %9zu %10.4f\n", sides[k], n,
               carve.best, carve.median, carve.bytes_per_cell, (double)n / carve.best,
               carve.counts.pits, keep.best);
    }
    if (n_sides >= 2)
        printf("  time ~ n^p: p = %.3f with depressions (CARVE), %.3f without (KEEP), "
               "sizes %zu^2 to %zu^2\n", exponent(cells, carve_t, n_sides),
               exponent(cells, keep_t, n_sides), sides[0], sides[n_sides - 1]);
    return 0;
}
