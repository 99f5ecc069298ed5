/*
 * bench.h - what the C benchmark drivers share: CPU time and a sort
 * order for taking best and median of repeated runs.
 */
#ifndef DFLE_BENCH_H
#define DFLE_BENCH_H

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

#endif
