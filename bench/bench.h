/*
 * bench.h - what the C benchmark drivers share: CPU time and a sort
 * order for taking best and median of repeated runs.
 */
#ifndef DFLE_BENCH_H
#define DFLE_BENCH_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <time.h>

/* CPU seconds of this process: steadier than wall time on a loaded
 * machine. */
static inline double cpu_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* n values of uniform noise in [0, 1) from xorshift64 state *x (start
 * it at BENCH_NOISE_SEED): the same surfaces every run, on every
 * machine, so that benchmarks and fingerprints compare like with like. */
#define BENCH_NOISE_SEED 0x9E3779B97F4A7C15ull
static inline void bench_noise(double *z, size_t n, uint64_t *x)
{
    for (size_t i = 0; i < n; i++) {
        *x ^= *x << 13;
        *x ^= *x >> 7;
        *x ^= *x << 17;
        z[i] = (double)(*x >> 11) / 9007199254740992.0;
    }
}

/* qsort order of doubles, ascending. */
static inline int by_value(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Growth exponent: the slope of log t against log n, least squares
 * over k sizes (1 is O(n)). */
static inline double exponent(const double *n, const double *t, int k)
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int i = 0; i < k; i++) {
        double x = log(n[i]), y = log(t[i]);
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
    }
    return (k * sxy - sx * sy) / (k * sxx - sx * sx);
}

#endif
