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
 * binned slope at the channel head (smallest-area bin).
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
    size_t *count;     /* points in the bin                              */
} dfle_bins;

/* Bin n pairs (A [m^2] > 0, finite S).  Pairs with A <= 0 or a
 * non-finite value are skipped.  Fails with DFLE_EINVAL if fewer than
 * two usable pairs or nbins == 0. */
int dfle_bins_compute(size_t n, const double *A, const double *S,
                      size_t nbins, dfle_bins *out, dfle_error *err);
void dfle_bins_release(dfle_bins *b); /* idempotent; b may be zeroed */

typedef struct dfle_eq2_fit {
    double S_df;   /* slope approached at small area [-]          */
    double A_df;   /* transition area [m^2]                       */
    double a2;     /* large-area power-law exponent [-]           */
    double r2;     /* coefficient of determination on the bins    */
    double rmse;   /* root-mean-square residual in S              */
    double S_max;  /* largest binned slope                        */
    double S_ch;   /* binned slope at the channel head            */
    double S_max_minus_S_ch;
    size_t n_points;   /* points fitted                           */
    size_t iterations; /* solver iterations                       */
} dfle_eq2_fit;

/* Fit Eq. (2) to n (A, S) points (typically bin means, A ascending not
 * required).  Needs n >= 4 and positive slopes.  DFLE_EFIT when the
 * solver fails. */
int dfle_fit_eq2(size_t n, const double *A, const double *S,
                 dfle_eq2_fit *out, dfle_error *err);

/* Bin then fit: the whole Fig. 1 analysis.  `bins` may be NULL; if not,
 * it receives the bins (release it with dfle_bins_release). */
int dfle_slope_area_fit(size_t n, const double *A, const double *S,
                        size_t nbins, dfle_bins *bins, dfle_eq2_fit *fit,
                        dfle_error *err);

/* Eq. (2) evaluated at area A. */
double dfle_eq2_eval(double S_df, double A_df, double a2, double A);

#ifdef __cplusplus
}
#endif
#endif
