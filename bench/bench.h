/*
 * bench.h - what the C benchmark drivers share: CPU time and a sort
 * order for taking best and median of repeated runs.
 */
#ifndef DFLE_BENCH_H
#define DFLE_BENCH_H

#include <math.h>
#include <time.h>

/* CPU seconds of this process: steadier than wall time on a loaded
 * machine. */
static inline double cpu_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
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
