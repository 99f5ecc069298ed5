/*
 * likelihood.c - log-slope residuals of a model profile against binned
 * slope-area data and their Gaussian log-likelihood (see
 * dfle/likelihood.h; doc/inversion.md gives the reasoning).
 *
 * Interpolating in log-log space keeps a power-law reach of the profile
 * exact between nodes, so the answer does not depend on where the nodes
 * happen to fall relative to the bins.
 */
#include "dfle/likelihood.h"

#include <math.h>

int dfle_slope_at(size_t n, const double *A, const double *S, size_t nq, const double *A_q,
                  double *S_q, dfle_error *err)
{
    if (n < 2)
        return dfle_error_set(err, DFLE_EINVAL, "likelihood: the profile has %zu node%s; need "
                              "at least 2", n, n == 1 ? "" : "s");
    for (size_t q = 0; q < nq; q++) {
        double a = A_q[q], t, lo, hi;
        size_t i0 = 0, i1 = n - 1;
        /* A bin's geometric-mean area, exp(mean ln A), can miss the end
         * node's area by a rounding error: that is still the end. */
        if (a < A[0] && a >= A[0] * (1 - 1e-9))
            a = A[0];
        if (a > A[n - 1] && a <= A[n - 1] * (1 + 1e-9))
            a = A[n - 1];
        if (!(a >= A[0] && a <= A[n - 1]))
            return dfle_error_set(err, DFLE_EINVAL, "likelihood: data area %g m^2 lies outside "
                                  "the model channel's areas (%g .. %g m^2)", a, A[0], A[n - 1]);
        /* The last node with A <= a, by bisection: i0 ends with A[i0] <= a < A[i1]. */
        while (i1 - i0 > 1) {
            size_t mid = i0 + (i1 - i0) / 2;
            if (A[mid] <= a)
                i0 = mid;
            else
                i1 = mid;
        }
        if (!(S[i0] > 0) || !(S[i1] > 0) || !isfinite(S[i0]) || !isfinite(S[i1]))
            return dfle_error_set(err, DFLE_EINVAL, "likelihood: the model's slope near A = %g "
                                  "m^2 is %g (node %zu) and %g (node %zu); a log-slope "
                                  "likelihood needs positive finite slopes", a, S[i0], i0 + 1,
                                  S[i1], i1 + 1);
        lo = log(S[i0]);
        hi = log(S[i1]);
        t = A[i1] > A[i0] ? (log(a) - log(A[i0])) / (log(A[i1]) - log(A[i0])) : 0.0;
        if (t > 1)
            t = 1;
        S_q[q] = exp(lo + t * (hi - lo));
    }
    return DFLE_OK;
}

int dfle_log_slope_residuals(size_t n, const double *A, const double *S, size_t nobs,
                             const double *A_obs, const double *lnS_obs, double *r,
                             dfle_error *err)
{
    int st = dfle_slope_at(n, A, S, nobs, A_obs, r, err);
    if (st != DFLE_OK)
        return st;
    for (size_t i = 0; i < nobs; i++)
        r[i] = lnS_obs[i] - log(r[i]);
    return DFLE_OK;
}

double dfle_gauss_loglike(size_t n, const double *r, double sigma)
{
    double ss = 0;
    if (!(sigma > 0) || !isfinite(sigma))
        return -INFINITY;
    for (size_t i = 0; i < n; i++)
        ss += (r[i] / sigma) * (r[i] / sigma);
    if (isnan(ss))
        return -INFINITY;
    return -0.5 * ss - (double)n * (log(sigma) + 0.9189385332046727);
}
