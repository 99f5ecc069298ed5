/*
 * likelihood.h - how well a model's steady profile matches binned
 * slope-area data: log-slope residuals and their Gaussian likelihood.
 *
 * Data are n_obs bins, each an area A_i [m^2] (the geometric-mean area of
 * the bin) and ln S_i, the logarithm of its mean slope (the aggregate of
 * the paper's Fig. 1 and of dfle_bins_compute).  The model's slope at
 * A_i is read off its profile by linear interpolation of ln S against
 * ln A between the two nodes whose areas bracket A_i: for a profile
 * whose nodes are a few metres apart this is the bin's mean slope to
 * well within the scatter of real data, and it is defined for data that
 * come binned from elsewhere, whose bin edges are unknown.
 *
 *   r_i = ln S_i - ln S_model(A_i)
 *   ln L = -1/2 sum (r_i / sigma)^2 - n ln sigma - n/2 ln(2 pi)
 *
 * doc/inversion.md states the assumptions (independent bins, one noise
 * scale in log slope) and what they mean.
 */
#ifndef DFLE_LIKELIHOOD_H
#define DFLE_LIKELIHOOD_H

#include <stddef.h>

#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Slopes S_q at areas A_q [m^2] of a profile of n nodes (A [m^2]
 * non-decreasing, S > 0 where used), interpolated linearly in
 * (ln A, ln S).  DFLE_EINVAL if an A_q lies outside [A[0], A[n-1]]
 * (beyond a relative 1e-9, rounding in a bin's mean area) or a
 * bracketing node's slope is not positive (the message says which). */
int dfle_slope_at(size_t n, const double *A, const double *S, size_t nq, const double *A_q,
                  double *S_q, dfle_error *err);

/* r_i = lnS_obs[i] - ln S_model(A_obs[i]) for nobs bins. */
int dfle_log_slope_residuals(size_t n, const double *A, const double *S, size_t nobs,
                             const double *A_obs, const double *lnS_obs, double *r,
                             dfle_error *err);

/* The Gaussian log-likelihood of residuals r with standard deviation
 * sigma > 0 (-inf for sigma <= 0 or NaN residuals). */
double dfle_gauss_loglike(size_t n, const double *r, double sigma);

#ifdef __cplusplus
}
#endif
#endif
