/*
 * mcmc.h - the affine-invariant ensemble sampler of Goodman and Weare
 * (2010), with the parallel stretch move (Foreman-Mackey et al. 2013,
 * Algorithm 3).
 *
 * K walkers (K even) move together through the d-dimensional parameter
 * space.  A step updates the first half of the walkers, then the second:
 * walker k of one half picks a walker j of the other half and proposes
 *
 *     y = x_j + z (x_k - x_j),   z ~ g(z) ~ 1/sqrt(z) on [1/a, a],
 *
 * accepted with probability min(1, z^(d-1) p(y) / p(x_k)).  Within a half
 * the proposals depend only on the other half, so the K/2 densities can
 * be evaluated in any order, on any number of threads: the caller gets
 * the proposals (dfle_mcmc_propose), evaluates them however it likes and
 * hands the log densities back (dfle_mcmc_accept).
 *
 * Determinism: the random numbers of walker k at step s (the partner j,
 * z = ((a - 1) r + 1)^2 / a with r uniform, and the uniform of the
 * accept test, in this order) come from the stream (seed, s, k, 0) of
 * stream.h.  A chain is therefore a function of the seed, the starting
 * ensemble and the density alone, and a run restarted from step s with
 * the walkers of step s continues exactly as an uninterrupted one.
 *
 * Log-scaled dimensions: the move acts on ln x instead of x (the sampler
 * is then affine-invariant in ln x), and the acceptance ratio carries the
 * Jacobian prod y_i / x_i, so the density given is always that of x.
 * Positions are kept in x, so what is stored is what is reported.
 *
 * References: Goodman, J., Weare, J. (2010), Ensemble samplers with
 * affine invariance, Comm. App. Math. Comp. Sci. 5, 65-80.
 * Foreman-Mackey, D., Hogg, D. W., Lang, D., Goodman, J. (2013), emcee:
 * the MCMC hammer, PASP 125, 306-312.
 */
#ifndef DFLE_MCMC_H
#define DFLE_MCMC_H

#include <stddef.h>
#include <stdint.h>

#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_mcmc_opts {
    size_t ndim;        /* d >= 1                                      */
    size_t nwalkers;    /* K: even, >= 2 d (and >= 4)                  */
    uint64_t seed;      /* chain seed                                  */
    double a;           /* stretch scale, > 1; default 2               */
    const int *log_scale; /* d flags (non-zero: move in ln x), or NULL */
} dfle_mcmc_opts;

void dfle_mcmc_opts_default(dfle_mcmc_opts *o); /* a = 2, seed = 1 */

typedef struct dfle_mcmc dfle_mcmc;

int dfle_mcmc_new(const dfle_mcmc_opts *o, dfle_mcmc **out, dfle_error *err);
void dfle_mcmc_free(dfle_mcmc *s); /* accepts NULL */

/* Set the ensemble after `step` completed steps (0: the start): x holds
 * K x d positions, walker-major; lp their log densities.  Every lp must
 * be > -inf, and log-scaled coordinates > 0 (DFLE_EINVAL otherwise). */
int dfle_mcmc_set_state(dfle_mcmc *s, size_t step, const double *x, const double *lp,
                        dfle_error *err);

const double *dfle_mcmc_x(const dfle_mcmc *s);  /* K x d current positions */
const double *dfle_mcmc_lp(const dfle_mcmc *s); /* K log densities         */
size_t dfle_mcmc_step(const dfle_mcmc *s);      /* steps completed         */
size_t dfle_mcmc_ndim(const dfle_mcmc *s);
size_t dfle_mcmc_nwalkers(const dfle_mcmc *s);

/* Proposals for half h (0: walkers 0 .. K/2-1; 1: the rest) of the next
 * step into y (K/2 x d).  DFLE_ESTATE before a state is set or when the
 * halves are not called in order 0, 1. */
int dfle_mcmc_propose(dfle_mcmc *s, int half, double *y, dfle_error *err);

/* The log densities of the proposals (NaN and -inf reject); accepted
 * moves replace the walkers.  accepted (K/2 flags) may be NULL.  After
 * half 1 the step is complete. */
int dfle_mcmc_accept(dfle_mcmc *s, int half, const double *y, const double *lp_y,
                     unsigned char *accepted, dfle_error *err);

/* A density evaluated for n points (n x d) at once; non-zero status
 * stops the run with that status. */
typedef int (*dfle_mcmc_logp_fn)(void *ud, size_t n, const double *x, double *lp,
                                 dfle_error *err);

/* Run nsteps whole steps.  chain (nsteps x K x d) and lpchain (nsteps x
 * K) receive the ensemble after each step and may be NULL; naccept (K)
 * accumulates accepted moves per walker and may be NULL. */
int dfle_mcmc_run(dfle_mcmc *s, size_t nsteps, dfle_mcmc_logp_fn f, void *ud, double *chain,
                  double *lpchain, size_t *naccept, dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
