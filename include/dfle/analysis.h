/*
 * analysis.h - slope-area analysis: log binning and the fit of Eq. (2),
 *
 *   S = S_df / (1 + (A / A_df)^a2),
 *
 * as in McGuire et al. (2023) Fig. 1: slope-area pairs are put into
 * `nbins` (default 100) logarithmically spaced area bins spanning the
 * data; empty bins are dropped; Eq. (2) is fitted to the mean slope of
 * each bin by nonlinear least squares (GSL multifit_nlinear, trust
 * region) with S_df, A_df and a2 free.  R^2 is that of the fit on the
 * binned means.  S_max - S_ch is the largest binned slope minus the
 * binned slope at the channel head (smallest-area bin).  Residuals may
 * also be taken in log S, fitted to the bins' geometric-mean slopes
 * (dfle_residuals), for noisy DEM data.
 */
#ifndef DFLE_ANALYSIS_H
#define DFLE_ANALYSIS_H

#include <stddef.h>
#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_bins {
    size_t nbins;      /* bins requested                                 */
    size_t n;          /* non-empty bins kept (arrays below hold n)      */
    size_t n_empty;    /* bins dropped for having no data                */
    double *A;         /* geometric-mean area of the bin's points [m^2]  */
    double *A_lo, *A_hi; /* bin edges [m^2]                              */
    double *S_mean;    /* mean slope                                     */
    double *S_median;  /* median slope                                   */
    double *S_q25, *S_q75; /* quartiles (linear interpolation)           */
    double *S_geomean; /* geometric mean of the positive slopes, the
                          bin's mean in log S; NaN if none is positive   */
    size_t *count;     /* points in the bin                              */
} dfle_bins;

/* Bin n pairs (A [m^2] > 0, finite S).  Pairs with A <= 0 or a
 * non-finite value are skipped.  Fails with DFLE_EINVAL if fewer than
 * two usable pairs or nbins == 0. */
int dfle_bins_compute(size_t n, const double *A, const double *S,
                      size_t nbins, dfle_bins *out, dfle_error *err);
void dfle_bins_release(dfle_bins *b); /* idempotent; b may be zeroed */

/* The space the residuals of the Eq. (2) fit are measured in. */
typedef enum dfle_residuals {
    DFLE_RESIDUALS_LINEAR = 0, /* S - S_model: the paper's; steep points weigh most   */
    DFLE_RESIDUALS_LOG = 1     /* log S - log S_model: every decade alike, as
                                  multiplicative (log-normal) noise in DEM slopes calls for */
} dfle_residuals;

typedef struct dfle_eq2_fit {
    double S_df;   /* slope approached at small area [-]          */
    double A_df;   /* transition area [m^2]                       */
    double a2;     /* large-area power-law exponent [-]           */
    int residuals; /* enum dfle_residuals: the fit's              */
    double r2;     /* R^2 in S (linear space)                     */
    double rmse;   /* root-mean-square residual in S              */
    double r2_log; /* R^2 in log S                                */
    double rmse_log; /* root-mean-square residual in log10 S [decades] */
    double S_max;  /* largest binned slope                        */
    double S_ch;   /* binned slope at the channel head            */
    double S_max_minus_S_ch;
    size_t n_points;   /* points fitted                           */
    size_t iterations; /* solver iterations                       */
} dfle_eq2_fit;

/* Fit Eq. (2) to n (A, S) points (typically bin means, A ascending not
 * required) with residuals in linear S.  Needs n >= 4 and positive
 * slopes.  DFLE_EFIT when the solver fails.  r2 and r2_log are both on
 * these points. */
int dfle_fit_eq2(size_t n, const double *A, const double *S,
                 dfle_eq2_fit *out, dfle_error *err);
/* The same with residuals in the space given. */
int dfle_fit_eq2_residuals(size_t n, const double *A, const double *S, dfle_residuals residuals,
                           dfle_eq2_fit *out, dfle_error *err);

/* R^2 = 1 - SS_res / SS_tot of Eq. (2) with these parameters on n
 * points, in S (linear) or in log S; NaN when n < 2 or the points'
 * values are all equal (SS_tot = 0). */
double dfle_eq2_r2(double S_df, double A_df, double a2, size_t n, const double *A,
                   const double *S, dfle_residuals space);

/* Bin then fit: the whole Fig. 1 analysis, with residuals in linear S
 * (the paper's).  `bins` may be NULL; if not, it receives the bins
 * (release it with dfle_bins_release). */
int dfle_slope_area_fit(size_t n, const double *A, const double *S,
                        size_t nbins, dfle_bins *bins, dfle_eq2_fit *fit,
                        dfle_error *err);

/* The same with residuals in the space given: linear S fitted to the
 * bins' mean slopes (bins whose mean is positive), log S fitted to the
 * log of their geometric-mean slopes (the mean of log S over the bin's
 * positive slopes; bins with none left out).  Either way r2 and rmse are
 * measured on the mean slopes in S, r2_log and rmse_log on the
 * geometric means in log S, so the two fits compare on the same terms;
 * S_max and S_ch are from the mean slopes. */
int dfle_slope_area_fit_residuals(size_t n, const double *A, const double *S, size_t nbins,
                                  dfle_residuals residuals, dfle_bins *bins, dfle_eq2_fit *fit,
                                  dfle_error *err);

/* Eq. (2) evaluated at area A. */
double dfle_eq2_eval(double S_df, double A_df, double a2, double A);

#ifdef __cplusplus
}
#endif
#endif
