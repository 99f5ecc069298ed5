/*
 * sampling.h - seeded Latin hypercube designs for ensembles of runs.
 *
 * The paper's experiments (McGuire et al. 2023, Sect. 2.5.1) sample
 * 500-4000 parameter sets by Latin hypercube.  A design here is fully
 * determined by (seed, n, the parameters in order, centred or not): the
 * same numbers come out on every platform, so a sharded or distributed
 * runner can rebuild the design anywhere and take any slice of it
 * (dfle_lhs_row gives sample i alone; building the whole design is cheap).
 *
 * The algorithm, exactly (doc/sensitivity.md says the same):
 *  - generator: GSL's gsl_rng_mt19937 seeded by gsl_rng_set(seed), i.e.
 *    the reference MT19937 (Matsumoto & Nishimura, init_genrand), giving
 *    32-bit words w; GSL maps seed 0 to its default 4357;
 *  - a uniform index below m (1 <= m <= 2^32) is w mod m, drawing w
 *    again while w >= 2^32 - (2^32 mod m) (no modulo bias);
 *  - a uniform number in [0, 1) is w / 2^32;
 *  - for each dimension d = 0 .. D-1 in turn: a permutation p of
 *    0 .. n-1 by Fisher-Yates (for i = n-1 down to 1: swap p[i] with
 *    p[j], j = uniform index below i+1), then for i = 0 .. n-1 the unit
 *    value u[i][d] = (p[i] + v) / n, where v is a fresh uniform number
 *    (v = 1/2, and no draw, when the design is centred);
 *  - u maps to the parameter: uniform lo + u (hi - lo); log-uniform
 *    exp(ln lo + u (ln hi - ln lo)); discrete values[floor(u k)] for k
 *    values.  Results are clamped to [lo, hi].
 *
 * The unit design and uniform and discrete values are bit-identical
 * everywhere (IEEE double arithmetic only); log-uniform values go through
 * the C library's exp() and log() and may differ in the last bit between
 * C libraries.
 */
#ifndef DFLE_SAMPLING_H
#define DFLE_SAMPLING_H

#include <stddef.h>
#include <stdint.h>

#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- The generator ---------------------------------------------- */

/* MT19937 as described above.  Seeds are whole numbers in [0, 2^32 - 1]. */
typedef struct dfle_rng dfle_rng;

#define DFLE_SEED_MAX 4294967295UL

int dfle_rng_new(unsigned long seed, dfle_rng **out, dfle_error *err);
void dfle_rng_free(dfle_rng *rng); /* accepts NULL */

/* The next 32-bit word of the MT19937 stream. */
uint32_t dfle_rng_u32(dfle_rng *rng);
/* Uniform in [0, m), 1 <= m <= 2^32, by rejection (see above). */
uint64_t dfle_rng_below(dfle_rng *rng, uint64_t m);
/* Uniform in [0, 1): w / 2^32. */
double dfle_rng_uniform(dfle_rng *rng);

/* ---- Latin hypercube designs ------------------------------------ */

typedef enum dfle_lhs_kind {
    DFLE_LHS_UNIFORM = 0,     /* lo + u (hi - lo); needs lo < hi         */
    DFLE_LHS_LOG_UNIFORM = 1, /* uniform in ln x; needs 0 < lo < hi      */
    DFLE_LHS_DISCRETE = 2     /* one of `values`, equally likely         */
} dfle_lhs_kind;

/* One dimension of the design.  The units of lo, hi and values are the
 * parameter's own; the design copies names and values. */
typedef struct dfle_lhs_param {
    const char *name;      /* non-empty, unique within a design        */
    dfle_lhs_kind kind;
    double lo, hi;         /* range (uniform and log-uniform), finite  */
    const double *values;  /* discrete: the allowed values             */
    size_t nvalues;        /* discrete: how many (>= 1)                */
} dfle_lhs_param;

typedef struct dfle_lhs_opts {
    size_t n;             /* samples, 1 .. 2^32 - 1                      */
    unsigned long seed;   /* 0 .. 2^32 - 1 (0 acts as GSL's 4357)       */
    int centered;         /* nonzero: stratum centres, no position draw */
} dfle_lhs_opts;

/* Defaults: n = 100, seed = 1, not centred. */
void dfle_lhs_opts_default(dfle_lhs_opts *opts);

typedef struct dfle_lhs dfle_lhs;

/* Build the design of opts->n samples of the `np` parameters in the
 * order given.  DFLE_EINVAL names the parameter at fault (lo >= hi, a
 * log range with lo <= 0, a non-finite bound, no values, duplicate
 * names, n == 0, seed out of range); DFLE_ENOMEM.  On failure *out is
 * NULL. */
int dfle_lhs_new(const dfle_lhs_opts *opts, size_t np, const dfle_lhs_param *params,
                 dfle_lhs **out, dfle_error *err);
void dfle_lhs_free(dfle_lhs *design); /* accepts NULL */

size_t dfle_lhs_n(const dfle_lhs *design);   /* samples          */
size_t dfle_lhs_dim(const dfle_lhs *design); /* parameters (D)   */
const char *dfle_lhs_name(const dfle_lhs *design, size_t d);
dfle_lhs_kind dfle_lhs_param_kind(const dfle_lhs *design, size_t d);

/* Sample i (0-based, i < n): its D parameter values, in parameter order
 * (NULL if i is out of range).  Valid until dfle_lhs_free. */
const double *dfle_lhs_row(const dfle_lhs *design, size_t i);
/* The same sample in the unit hypercube: u in [0, 1) per dimension. */
const double *dfle_lhs_unit_row(const dfle_lhs *design, size_t i);
/* For a discrete dimension d, the index into its values chosen for
 * sample i (floor(u k)); 0 for other kinds or out-of-range arguments. */
size_t dfle_lhs_choice(const dfle_lhs *design, size_t i, size_t d);

/* Check one parameter as dfle_lhs_new would (message names it). */
int dfle_lhs_param_check(const dfle_lhs_param *p, dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
