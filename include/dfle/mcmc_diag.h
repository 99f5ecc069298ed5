/*
 * mcmc_diag.h - what a chain says and how far to trust it: integrated
 * autocorrelation times and posterior summaries.
 *
 * Autocorrelation time (Sokal 1997; the ensemble form of Goodman and
 * Weare 2010 and emcee): for each parameter, the normalised
 * autocorrelation function of every walker's series (by FFT) is averaged
 * over the walkers, rho(t); tau(M) = 1 + 2 sum_{t=1..M} rho(t), and the
 * window M is the smallest lag with M >= c tau(M) (c = 5).  A chain of N
 * steps and K walkers holds about K N / tau independent samples; tau is
 * trustworthy only when N is at least about 50 tau, which the caller
 * should check and say.
 *
 * Summaries: mean, standard deviation (n - 1), and quantiles by linear
 * interpolation between order statistics (numpy's default): the median
 * and the central 68 % (16th-84th percentile) and 95 % (2.5th-97.5th)
 * intervals.
 */
#ifndef DFLE_MCMC_DIAG_H
#define DFLE_MCMC_DIAG_H

#include <stddef.h>

#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* tau[j] for each of the d parameters of a chain of nsteps x nwalkers x
 * ndim values (step-major, as dfle_mcmc_run writes it).  c <= 0 means 5.
 * *windowed (may be NULL) is set to 0 if some window reached the end of
 * the chain (tau is then a lower bound).  A parameter on which every
 * walker stood still has tau = NaN.  Needs nsteps >= 2. */
int dfle_mcmc_autocorr(const double *chain, size_t nsteps, size_t nwalkers, size_t ndim,
                       double c, double *tau, int *windowed, dfle_error *err);

typedef struct dfle_summary {
    double mean, sd;
    double median;
    double lo68, hi68; /* 16th and 84th percentiles   */
    double lo95, hi95; /* 2.5th and 97.5th percentiles */
    size_t n;
} dfle_summary;

/* Summary of n values x[0], x[stride], ... (NaN values are left out). */
int dfle_summarize(const double *x, size_t n, size_t stride, dfle_summary *out,
                   dfle_error *err);

/* The p-quantile (0 <= p <= 1) of n sorted values, linear interpolation. */
double dfle_quantile_sorted(const double *sorted, size_t n, double p);

#ifdef __cplusplus
}
#endif
#endif
