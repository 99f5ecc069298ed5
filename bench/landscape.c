/*
 * landscape.c - time and memory per step of a landscape (landscape.h)
 * on the set-up of fastscapelib's benchmark: square grids of 250^2 to
 * 2000^2 cells of 30 m, a random start (uniform noise of 1 m), every
 * edge a base level, stream power E = K A^m S^n with m = 0.5 and n = 1
 * or 2.33, uplift 1e-3 m/yr, steps of 1e4 yr, every cell a channel
 * (A_0 = 0: no hillslope rule, as fastscapelib's).  Each step routes
 * flow (D8 and depressions through the basin graph) and solves the
 * implicit stream power law in stack order.
 *
 * Reports, per grid: CPU s of the first step (routing the random
 * surface: about one cell in nine is a pit) and the mean of the next
 * `steps` steps (routing, erosion, whole step), bytes per cell held, and
 * the exponent p of t ~ n^p fitted over the grids.  Figures only:
 * nothing here asserts on time.
 *
 * The streaming bound: a step reads and writes the arrays the landscape
 * holds, so it cannot take less than the time to stream each of their
 * bytes in and out once, 2 x (bytes held) / bandwidth, with the
 * bandwidth of a STREAM triad (a[i] = b[i] + s c[i], 24 bytes an
 * element) over arrays as large as those of the largest grid, measured
 * in the same run.  Each grid's step is printed beside 10 times its
 * bound, the target.
 *
 *   build/bench/landscape [steps [side ...]]     (default 10; 250 500 1000 2000)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "dfle/landscape.h"

#include "bench.h"


/* Bytes a second of a STREAM triad over three arrays of `bytes` in all,
 * and in *read of a sum over the same bytes (reading alone is faster:
 * no write-back), best of 5 after a warm-up (the machine is shared). */
static double triad_bandwidth(size_t bytes, double *read)
{
    const size_t n = bytes / (3 * sizeof(double));
    double *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b), *c = malloc(n * sizeof *c);
    double best = 0, sink = 0;
    if (a == NULL || b == NULL || c == NULL) {
        free(a);
        free(b);
        free(c);
        return NAN;
    }
    for (size_t i = 0; i < n; i++) {
        a[i] = 0;
        b[i] = 1.0 + (double)(i & 7);
        c[i] = 2.0;
    }
    for (int rep = 0; rep < 6; rep++) {
        double t0 = cpu_seconds(), t;
        for (size_t i = 0; i < n; i++)
            a[i] = b[i] + 0.5 * c[i];
        t = cpu_seconds() - t0;
        sink += a[n / 2];
        if (rep > 0 && t > 0 && 24.0 * (double)n / t > best)
            best = 24.0 * (double)n / t;
        c[rep] = a[rep + 1]; /* each round depends on the last */
    }
    *read = 0;
    for (int rep = 0; rep < 6; rep++) {
        double t0 = cpu_seconds(), t, s0 = 0, s1 = 0, s2 = 0, s3 = 0;
        for (size_t i = 0; i + 3 < n; i += 4) {
            s0 += a[i] + b[i] + c[i];
            s1 += a[i + 1] + b[i + 1] + c[i + 1];
            s2 += a[i + 2] + b[i + 2] + c[i + 2];
            s3 += a[i + 3] + b[i + 3] + c[i + 3];
        }
        t = cpu_seconds() - t0;
        sink += s0 + s1 + s2 + s3;
        if (rep > 0 && t > 0 && 24.0 * (double)n / t > *read)
            *read = 24.0 * (double)n / t;
    }
    free(a);
    free(b);
    free(c);
    return sink > 0 ? best : NAN;
}

typedef struct figures {
    double first, route, solve, step, bytes;
} figures;

static int run(size_t side, double n_exp, int steps, figures *f)
{
    const size_t n = side * side;
    uint64_t x = BENCH_NOISE_SEED;
    double *z = malloc(n * sizeof *z);
    dfle_fluvial *fl = NULL;
    dfle_landscape *ls = NULL;
    dfle_landscape_opts o;
    dfle_landscape_status st;
    dfle_error err;
    int rc = 1;

    if (z == NULL)
        return 1;
    bench_noise(z, n, &x);
    dfle_landscape_opts_default(&o);
    o.nx = o.ny = side;
    o.dx = o.dy = 30.0;
    o.z = z;
    o.A0 = 0.0;
    o.U.value = 1e-3;
    if (dfle_fluvial_new_stream_power(n_exp == 1 ? 2e-5 : 1e-3, 0.5, n_exp, &fl, &err) != DFLE_OK)
        goto fail;
    o.fluvial = fl;
    if (dfle_landscape_new(&o, &ls, &err) != DFLE_OK) {
        fprintf(stderr, "landscape bench: %s\n", err.msg);
        goto done;
    }
    {
        double t0 = cpu_seconds();
        if (dfle_landscape_step(ls, 1e4, 1e-3, &st, &err) != DFLE_OK)
            goto fail;
        f->first = cpu_seconds() - t0;
    }
    f->route = f->solve = f->step = 0;
    for (int s = 0; s < steps; s++) {
        double t0 = cpu_seconds();
        if (dfle_landscape_step(ls, 1e4, 1e-3, &st, &err) != DFLE_OK)
            goto fail;
        f->step += cpu_seconds() - t0;
        f->route += st.route_seconds;
        f->solve += st.solve_seconds;
    }
    f->step /= steps;
    f->route /= steps;
    f->solve /= steps;
    f->bytes = (double)dfle_landscape_memory(ls) / (double)n;
    rc = 0;
    goto done;
fail:
    fprintf(stderr, "landscape bench: %s\n", err.msg);
done:
    dfle_landscape_free(ls);
    dfle_fluvial_free(fl);
    free(z);
    return rc;
}

int main(int argc, char **argv)
{
    static const size_t default_sides[] = {250, 500, 1000, 2000};
    static const double exps[2] = {1.0, 2.33};
    size_t sides[16];
    int n_sides = 0, steps = argc > 1 ? atoi(argv[1]) : 10;

    if (steps < 1)
        steps = 1;
    for (int a = 2; a < argc && n_sides < 16; a++)
        sides[n_sides++] = (size_t)strtoul(argv[a], NULL, 10);
    if (n_sides == 0)
        for (size_t s = 0; s < sizeof default_sides / sizeof *default_sides; s++)
            sides[n_sides++] = default_sides[s];
    size_t largest = 0;
    double bw, bw_triad;
    for (int k = 0; k < n_sides; k++)
        largest = sides[k] > largest ? sides[k] : largest;
    /* The arrays of the largest grid: about 86 bytes a cell. */
    bw_triad = triad_bandwidth(86 * largest * largest, &bw);
    if (!(bw > bw_triad))
        bw = bw_triad; /* the bound takes the faster */
    printf("Streaming bandwidth over %.0f MB, best of 5: %.1f GB/s (STREAM triad), %.1f GB/s "
           "(read); the bound takes %.1f GB/s\n", 86e-6 * (double)(largest * largest),
           1e-9 * bw_triad, 1e-9 * bw, 1e-9 * bw);
    printf("Landscape steps (route with depressions + implicit stream power), 30 m cells, "
           "random start, edges at base level, CPU s (mean of %d steps after the first);\n"
           "bound: 2 x bytes held / bandwidth; target: step <= 10 x bound (single thread):\n",
           steps);
    for (int e = 0; e < 2; e++) {
        double cells[16], tr[16], ts[16], tt[16];
        printf("  m = 0.5, n = %.2f\n  %-9s %10s %9s %9s %9s %9s %8s %9s %9s %7s\n", exps[e],
               "grid", "cells", "1st step", "route", "erode", "step", "B/cell", "bound",
               "target", "x bound");
        for (int k = 0; k < n_sides; k++) {
            figures f;
            if (run(sides[k], exps[e], steps, &f) != 0)
                return 1;
            cells[k] = (double)(sides[k] * sides[k]);
            tr[k] = f.route;
            ts[k] = f.solve;
            tt[k] = f.step;
            {
                const double bound = 2.0 * f.bytes * cells[k] / bw;
                printf("  %5zu^2   %10.0f %9.4f %9.4f %9.4f %9.4f %8.1f %9.4f %9.4f %7.1f %s\n",
                       sides[k], cells[k], f.first, f.route, f.solve, f.step, f.bytes, bound,
                       10 * bound, f.step / bound, f.step <= 10 * bound ? "met" : "NOT met");
            }
        }
        if (n_sides >= 2)
            printf("  time ~ n^p: p = %.3f (routing), %.3f (erosion), %.3f (step)\n",
                   exponent(cells, tr, n_sides), exponent(cells, ts, n_sides),
                   exponent(cells, tt, n_sides));
    }
    return 0;
}
