/*
 * lsq.h - a bounded least-squares point estimate and its covariance, for
 * residual functions that may fail: minimise RSS(u) = sum r_i(u)^2 with
 * GSL's Nelder-Mead simplex (nmsimplex2), then estimate the covariance
 * from a finite-difference Jacobian at the minimum.
 *
 * Why Nelder-Mead and not Levenberg-Marquardt: each residual vector here
 * is a forward model run, which may fail (no steady state, a slope that
 * is not positive) or leave the parameter's range; the simplex only
 * compares values, so a failure is just a very bad value (1e300) and
 * the search moves on, where a Jacobian-based step would stop.  The
 * covariance then uses the Jacobian after all, once, at the answer:
 *
 *   J_ij = d r_i / d u_j  (central differences; one-sided at a bound),
 *   C = s^2 (J^T J)^-1,   s^2 = RSS / (m - n)  or the known sigma^2,
 *
 * the usual linearised covariance of least squares (Gaussian errors of
 * equal variance, a model near-linear over the uncertainty).
 *
 * The search starts from u0 with a simplex of steps `step`, and is
 * restarted once from its answer (a simplex can stall on a ridge, which
 * trade-offs between parameters make common); it stops when the simplex
 * size falls below tol times the mean step, or after max_evals
 * evaluations.
 */
#ifndef DFLE_LSQ_H
#define DFLE_LSQ_H

#include <stddef.h>

#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Residuals r (m values) at u (n values).  Return DFLE_OK; DFLE_EFIT when
 * there is no value at u (counted as a failed evaluation, the search goes
 * on); any other status stops the fit with that status. */
typedef int (*dfle_lsq_fn)(void *ud, const double *u, double *r, dfle_error *err);

typedef struct dfle_lsq_opts {
    size_t n, m;            /* parameters, residuals (m > n)               */
    const double *u0;       /* start (inside the bounds)                    */
    const double *step;     /* initial simplex steps, > 0                   */
    const double *lo, *hi;  /* bounds (may be -inf, inf); NULL: none        */
    size_t max_evals;       /* 0: 400 (n + 1)                               */
    double tol;             /* 0: 1e-6                                      */
    double sigma;           /* > 0: the known noise sd for C; 0: estimate   */
} dfle_lsq_opts;

typedef struct dfle_lsq_info {
    double rss;             /* at the answer                               */
    double s2;              /* the variance used in C                      */
    size_t evaluations;     /* residual calls, Jacobian included           */
    size_t failed;          /* of which had no value (DFLE_EFIT)           */
    int converged;          /* the simplex shrank below tol                */
    int cov_ok;             /* J^T J was positive definite                 */
    char why[160];          /* when not converged or no covariance: why    */
} dfle_lsq_info;

/* The answer goes to u (n values), its covariance to cov (n x n, may be
 * NULL; NaN when J^T J is singular).  DFLE_EFIT if even the start has no
 * value. */
int dfle_lsq_fit(const dfle_lsq_opts *o, dfle_lsq_fn f, void *ud, double *u, double *cov,
                 dfle_lsq_info *info, dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
