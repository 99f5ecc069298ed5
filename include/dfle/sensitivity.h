/*
 * sensitivity.h - PAWN sensitivity indices on given data, computed as
 * SALib's `pawn.analyze` computes them (SALib 1.5 / commit 1c375488 with
 * numpy 1.24 and scipy 1.10), plus bootstrap confidence intervals.
 *
 * The paper ranks parameters with PAWN (McGuire et al. 2023, Sect. 2.5.2,
 * Figs. 5-10); geomorphologists check such numbers against SALib, so the
 * indices here reproduce SALib's to the last bit on its reference cases
 * (doc/sensitivity.md, Verification).  For each input d, with N rows and S slices:
 *
 *  1. edges b_s = numpy's default (linear) quantile of x_d at level
 *     s * (1.0 / S), s = 0 .. S;
 *  2. slice s holds the rows with b_s <= x < b_{s+1} (half-open for every
 *     slice, the last one too: rows at the largest x fall in no slice);
 *  3. KS_s = two-sample Kolmogorov-Smirnov statistic between the outputs
 *     of slice s and the *whole* output vector, as scipy's ks_2samp: for
 *     N <= DFLE_PAWN_EXACT_MAX_N the exact fraction h / lcm(n_s, N)
 *     rounded once to double, above that the largest floating-point
 *     difference of the two empirical CDFs; an empty slice has no KS_s
 *     and is skipped below (NaN in `ks`);
 *  4. over the slices that are not empty: minimum, mean (numpy's pairwise
 *     summation over the S values with empty slices as 0, divided by the
 *     count), median (middle value, or the mean of the two middle ones),
 *     maximum, stdev (population: sqrt of the pairwise sum of squared
 *     deviations over the count) and CV = stdev / mean.
 *
 * Bootstrap (not in SALib): B times, draw N row indices uniformly with
 * replacement (dfle_rng_below(N) on the MT19937 stream of `seed`, N
 * draws per replicate), run the whole analysis above on the resampled
 * table (its own quantile edges included), and report for every index
 * the percentile interval: numpy-linear quantiles at (1 - conf)/2 and
 * (1 + conf)/2 of the B replicate values (NaN replicates left out).
 * Replicate b is always the b-th block of N draws, so the intervals do
 * not depend on opts.threads, which spreads the replicates over threads.
 */
#ifndef DFLE_SENSITIVITY_H
#define DFLE_SENSITIVITY_H

#include <stddef.h>
#include <stdint.h>

#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The statistics, in SALib's order, then stdev. */
enum dfle_pawn_stat {
    DFLE_PAWN_MINIMUM = 0,
    DFLE_PAWN_MEAN = 1,
    DFLE_PAWN_MEDIAN = 2,
    DFLE_PAWN_MAXIMUM = 3,
    DFLE_PAWN_CV = 4,
    DFLE_PAWN_STDEV = 5
};
#define DFLE_PAWN_NSTATS 6

/* scipy's MAX_AUTO_N: up to this many rows the KS statistic is the exact
 * fraction h / lcm. */
#define DFLE_PAWN_EXACT_MAX_N 10000

/* The most bootstrap threads dfle_pawn starts (each has O(N + S) scratch). */
#define DFLE_PAWN_MAX_THREADS 4096

/* "minimum", "mean", "median", "maximum", "CV", "stdev" (NULL otherwise). */
const char *dfle_pawn_stat_name(int stat);

typedef struct dfle_pawn_opts {
    size_t S;                 /* slices per input, >= 1 (default 10)        */
    size_t bootstrap;         /* replicates; 0 = no intervals (default 0)   */
    double conf;              /* confidence level in (0, 1) (default 0.95)  */
    unsigned long seed;       /* bootstrap seed, 0 .. 2^32 - 1 (default 1)  */
    const char *const *names; /* D input names for messages (may be NULL)   */
    const char *output;       /* output name for messages (may be NULL)     */
    size_t threads;           /* threads for the bootstrap replicates, the
                               * calling one included, at most
                               * DFLE_PAWN_MAX_THREADS; 0 or 1: the calling
                               * thread alone (default 1).  The library
                               * starts threads - 1 pthreads for the call and
                               * joins them before it returns; the results
                               * are the same, bit for bit, for any count  */
    int per_slice;            /* 1: a pass over the rows per slice (the
                               * reference algorithm, for tests and
                               * benchmarks; the same results); 0: one pass
                               * per input for all its slices (default)     */
} dfle_pawn_opts;

void dfle_pawn_opts_default(dfle_pawn_opts *opts);

typedef struct dfle_pawn_result {
    size_t N, D, S;
    double *index;      /* D x 6: index[d * 6 + stat]                       */
    double *edges;      /* D x (S + 1): slice edges b_s of input d           */
    double *ks;         /* D x S: KS statistic per slice, NaN if empty       */
    size_t *count;      /* D x S: rows in each slice                         */
    uint64_t *ks_h;     /* D x S: KS = ks_h / ks_lcm when exact (else 0, 0)  */
    uint64_t *ks_lcm;
    size_t bootstrap;   /* replicates drawn (0: lo and hi are NULL)          */
    double conf;
    double *lo, *hi;    /* D x 6: percentile interval of each index          */
} dfle_pawn_result;

/* PAWN for D inputs x[0..D-1] (each an array of N values) against the
 * output y (N values).  All values must be finite; N >= 2, D >= 1.
 * On success `out` owns its arrays: release it with dfle_pawn_release.
 * DFLE_EINVAL (naming the input and 1-based row), DFLE_ENOMEM. */
int dfle_pawn(size_t N, size_t D, const double *const *x, const double *y,
              const dfle_pawn_opts *opts, dfle_pawn_result *out, dfle_error *err);

/* Free the arrays of a result; idempotent, accepts a zeroed struct. */
void dfle_pawn_release(dfle_pawn_result *res);

/* ---- numpy's arithmetic, exposed for tests and other analyses ---- */

/* numpy's default ("linear") quantile of n >= 1 sorted values at level
 * q in [0, 1]: virtual index h = (n - 1) q, j = floor(h), t = h - j,
 * a = x[j], b = x[j + 1]; a + (b - a) t if t < 0.5, else
 * b - (b - a)(1 - t); x[n - 1] when h >= n - 1. */
double dfle_quantile_linear(const double *sorted, size_t n, double q);

/* numpy's float64 sum (np.sum / np.add.reduce): pairwise summation with
 * eight accumulators over blocks of up to 128 values. */
double dfle_sum_pairwise(const double *a, size_t n);

#ifdef __cplusplus
}
#endif
#endif
