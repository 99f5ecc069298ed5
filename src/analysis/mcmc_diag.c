/*
 * mcmc_diag.c - integrated autocorrelation times and posterior summaries
 * of ensemble-sampler chains (see dfle/mcmc_diag.h).
 *
 * The autocorrelation function comes from an FFT of each walker's series
 * padded to a power of two at least twice its length (so the circular
 * correlation equals the linear one), through GSL's radix-2 transform.
 * Averaging the functions over walkers before summing, rather than
 * averaging per-walker times, is what makes the estimate usable on the
 * short chains an ensemble sampler produces.
 */
#include "dfle/mcmc_diag.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_fft_complex.h>

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double dfle_quantile_sorted(const double *x, size_t n, double p)
{
    double h;
    size_t lo;
    if (n == 0)
        return NAN;
    h = p * (double)(n - 1);
    lo = (size_t)h;
    if (lo + 1 >= n)
        return x[n - 1];
    return x[lo] + (h - (double)lo) * (x[lo + 1] - x[lo]);
}

int dfle_summarize(const double *x, size_t n, size_t stride, dfle_summary *out,
                   dfle_error *err)
{
    double *v, mean = 0, ss = 0;
    size_t m = 0;

    memset(out, 0, sizeof *out);
    out->mean = out->sd = out->median = out->lo68 = out->hi68 = out->lo95 = out->hi95 = NAN;
    if (stride == 0)
        stride = 1;
    v = malloc((n ? n : 1) * sizeof *v);
    if (v == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "summary: out of memory");
    for (size_t i = 0; i < n; i++)
        if (!isnan(x[i * stride]))
            v[m++] = x[i * stride];
    out->n = m;
    if (m > 0) {
        for (size_t i = 0; i < m; i++)
            mean += v[i];
        mean /= (double)m;
        for (size_t i = 0; i < m; i++)
            ss += (v[i] - mean) * (v[i] - mean);
        out->mean = mean;
        out->sd = m > 1 ? sqrt(ss / (double)(m - 1)) : NAN;
        qsort(v, m, sizeof *v, cmp_double);
        out->median = dfle_quantile_sorted(v, m, 0.5);
        out->lo68 = dfle_quantile_sorted(v, m, 0.15865525393145707);
        out->hi68 = dfle_quantile_sorted(v, m, 0.8413447460685429);
        out->lo95 = dfle_quantile_sorted(v, m, 0.025);
        out->hi95 = dfle_quantile_sorted(v, m, 0.975);
    }
    free(v);
    return DFLE_OK;
}

int dfle_mcmc_autocorr(const double *chain, size_t nsteps, size_t nwalkers, size_t ndim,
                       double c, double *tau, int *windowed, dfle_error *err)
{
    size_t N2 = 1;
    double *buf, *rho;
    int st = DFLE_OK;

    if (windowed != NULL)
        *windowed = 1;
    if (nsteps < 2 || nwalkers < 1 || ndim < 1)
        return dfle_error_set(err, DFLE_EINVAL, "autocorrelation: needs at least 2 steps "
                              "(got %zu)", nsteps);
    if (!(c > 0))
        c = 5.0;
    while (N2 < 2 * nsteps)
        N2 *= 2;
    buf = malloc(2 * N2 * sizeof *buf);
    rho = malloc(nsteps * sizeof *rho);
    if (buf == NULL || rho == NULL) {
        free(buf);
        free(rho);
        return dfle_error_set(err, DFLE_ENOMEM, "autocorrelation: out of memory");
    }
    for (size_t j = 0; j < ndim; j++) {
        size_t used = 0, M;
        double t = 1.0;
        memset(rho, 0, nsteps * sizeof *rho);
        for (size_t k = 0; k < nwalkers; k++) {
            double mean = 0, c0;
            for (size_t s = 0; s < nsteps; s++)
                mean += chain[(s * nwalkers + k) * ndim + j];
            mean /= (double)nsteps;
            memset(buf, 0, 2 * N2 * sizeof *buf);
            for (size_t s = 0; s < nsteps; s++)
                buf[2 * s] = chain[(s * nwalkers + k) * ndim + j] - mean;
            if (gsl_fft_complex_radix2_forward(buf, 1, N2) != GSL_SUCCESS) {
                st = dfle_error_set(err, DFLE_ENOMEM, "autocorrelation: FFT failed");
                goto done;
            }
            for (size_t i = 0; i < N2; i++) {
                double re = buf[2 * i], im = buf[2 * i + 1];
                buf[2 * i] = re * re + im * im;
                buf[2 * i + 1] = 0;
            }
            if (gsl_fft_complex_radix2_backward(buf, 1, N2) != GSL_SUCCESS) {
                st = dfle_error_set(err, DFLE_ENOMEM, "autocorrelation: FFT failed");
                goto done;
            }
            c0 = buf[0];
            if (!(c0 > 0))
                continue; /* this walker never moved in this parameter */
            for (size_t s = 0; s < nsteps; s++)
                rho[s] += buf[2 * s] / c0;
            used++;
        }
        if (used == 0) {
            tau[j] = NAN;
            continue;
        }
        /* Sokal's window: the first M with M >= c tau(M). */
        for (M = 1; M < nsteps; M++) {
            t += 2.0 * rho[M] / (double)used;
            if ((double)M >= c * t)
                break;
        }
        if (M >= nsteps && windowed != NULL)
            *windowed = 0;
        tau[j] = t;
    }
done:
    free(buf);
    free(rho);
    return st;
}
