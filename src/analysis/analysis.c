/*
 * analysis.c - slope-area analysis: logarithmic binning of (A, S) pairs
 * and the least-squares fit of Eq. (2) of McGuire et al. (2023),
 *
 *   S = S_df / (1 + (A / A_df)^a2).
 *
 * This is how a modelled or surveyed profile is reduced to the three
 * numbers the paper compares across catchments (Fig. 1): the slope the
 * debris-flow reach tends to (S_df), the area where fluvial incision takes
 * over (A_df) and the fluvial exponent (a2).  Binning comes first because
 * raw pixels crowd the large-area end and would otherwise dominate the fit.
 *
 * The fit works in u = (ln S_df, ln A_df, a2): the logarithms keep S_df
 * and A_df positive whatever step the solver tries and put parameters
 * that differ by six orders of magnitude on comparable scales, while the
 * residuals stay in linear slope as in the paper.
 */
#include "dfle/analysis.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_matrix.h>
#include <gsl/gsl_multifit_nlinear.h>
#include <gsl/gsl_vector.h>

/* ---- Binning ---------------------------------------------------- */

static int usable_pair(double area, double slope)
{
    return area > 0.0 && isfinite(area) && isfinite(slope);
}

static int compare_doubles(const void *pa, const void *pb);

/* Ascending.  A bin holds a handful of slopes (four on a 403-node
 * profile in 100 bins): insertion sort there, qsort's call per
 * comparison only for big ones. */
static void sort_doubles(double *s, size_t m)
{
    if (m > 32) {
        qsort(s, m, sizeof *s, compare_doubles);
        return;
    }
    for (size_t i = 1; i < m; i++) {
        double v = s[i];
        size_t j = i;
        for (; j > 0 && s[j - 1] > v; j--)
            s[j] = s[j - 1];
        s[j] = v;
    }
}

static int compare_doubles(const void *pa, const void *pb)
{
    double a = *(const double *)pa, b = *(const double *)pb;
    return (a > b) - (a < b);
}

/* numpy's default quantile: linear interpolation between the order
 * statistics bracketing position p (m - 1), so results match the
 * Python tools geomorphologists check our numbers against. */
static double quantile_of_sorted(const double *x, size_t m, double p)
{
    double h = p * (double)(m - 1);
    size_t lo = (size_t)h;
    if (lo + 1 >= m)
        return x[m - 1];
    return x[lo] + (h - (double)lo) * (x[lo + 1] - x[lo]);
}

typedef struct log_grid {
    double ln_lo, width;  /* ln of the lowest edge, bin width in ln A */
    double A_min, A_max;  /* exact outer edges                        */
    size_t nbins;
} log_grid;

/* The outer edges are the data extremes exactly, so that rounding in
 * exp(log(x)) can never leave the smallest or largest area outside. */
static double grid_edge(const log_grid *g, size_t k)
{
    if (k == 0)
        return g->A_min;
    if (k >= g->nbins)
        return g->A_max;
    return exp(g->ln_lo + g->width * (double)k);
}

/* Bin k holds A_lo[k] <= A < A_hi[k]; the last bin is closed at the top
 * so the largest area belongs to it.  The index from the logarithm can be
 * one off at an edge, so it is corrected against the edges we report. */
static size_t grid_index(const log_grid *g, double area, double ln_area)
{
    double h = (ln_area - g->ln_lo) / g->width;
    size_t k = h <= 0.0 ? 0
             : h >= (double)g->nbins ? g->nbins - 1 : (size_t)h;
    if (k > 0 && area < grid_edge(g, k))
        k--;
    else if (k + 1 < g->nbins && area >= grid_edge(g, k + 1))
        k++;
    return k;
}

void dfle_bins_release(dfle_bins *b)
{
    if (b == NULL)
        return;
    free(b->A);
    free(b->A_lo);
    free(b->A_hi);
    free(b->S_mean);
    free(b->S_median);
    free(b->S_q25);
    free(b->S_q75);
    free(b->S_geomean);
    free(b->count);
    memset(b, 0, sizeof *b);
}

static int bins_alloc(dfle_bins *b, size_t m)
{
    double **arrays[] = { &b->A, &b->A_lo, &b->A_hi, &b->S_mean,
                          &b->S_median, &b->S_q25, &b->S_q75, &b->S_geomean };
    int ok = 1;
    for (size_t i = 0; i < sizeof arrays / sizeof arrays[0]; i++) {
        *arrays[i] = malloc(m * sizeof(double));
        ok = ok && *arrays[i] != NULL;
    }
    b->count = malloc(m * sizeof(size_t));
    if (!ok || b->count == NULL) {
        dfle_bins_release(b);
        return DFLE_ENOMEM;
    }
    return DFLE_OK;
}

int dfle_bins_compute(size_t n, const double *A, const double *S,
                      size_t nbins, dfle_bins *out, dfle_error *err)
{
    size_t usable = 0, kept = 0;
    log_grid g = { 0.0, 0.0, HUGE_VAL, 0.0, nbins };

    if (out == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "slope-area bins: output is NULL");
    /* out may hold garbage on entry; it is overwritten, never freed. */
    memset(out, 0, sizeof *out);
    if (nbins == 0)
        return dfle_error_set(err, DFLE_EINVAL,
                              "slope-area bins: nbins is 0, need at least 1");
    if (n > 0 && (A == NULL || S == NULL))
        return dfle_error_set(err, DFLE_EINVAL, "slope-area bins: %s array is NULL",
                              A == NULL ? "area" : "slope");
    for (size_t i = 0; i < n; i++) {
        if (usable_pair(A[i], S[i])) {
            usable++;
            g.A_min = fmin(g.A_min, A[i]);
            g.A_max = fmax(g.A_max, A[i]);
        }
    }
    if (usable < 2)
        return dfle_error_set(err, DFLE_EINVAL,
                              "slope-area bins: %zu usable (A, S) pairs of %zu, "
                              "need at least 2 (A > 0, A and S finite)", usable, n);
    if (g.A_min == g.A_max)
        return dfle_error_set(err, DFLE_EINVAL,
                              "slope-area bins: all %zu usable areas equal %g m^2; "
                              "a single area cannot be binned", usable, g.A_min);
    g.ln_lo = log(g.A_min);
    g.width = (log(g.A_max) - g.ln_lo) / (double)nbins;

    /* Counting sort by bin, so each bin's slopes are contiguous for its
     * median: first[k] is where bin k starts, fill[k] how much is placed.
     * The size test keeps 2 nbins + 1 from wrapping round. */
    size_t *first = nbins < SIZE_MAX / (2 * sizeof(size_t))
                  ? calloc(2 * nbins + 1, sizeof *first) : NULL;
    /* ln A and the bin of each usable pair, found once (a logarithm and
     * up to two edges each): the placing pass reads them back. */
    double *lnA_by_bin = malloc(3 * usable * sizeof *lnA_by_bin);
    size_t *bin_of = malloc(usable * sizeof *bin_of);
    if (first != NULL && lnA_by_bin != NULL && bin_of != NULL) {
        double *lnA_of = lnA_by_bin + 2 * usable;
        for (size_t i = 0, u = 0; i < n; i++)
            if (usable_pair(A[i], S[i])) {
                lnA_of[u] = log(A[i]);
                bin_of[u] = grid_index(&g, A[i], lnA_of[u]);
                first[bin_of[u++] + 1]++;
            }
        for (size_t k = 0; k < nbins; k++) {
            kept += first[k + 1] > 0;
            first[k + 1] += first[k];
        }
    }
    if (first == NULL || lnA_by_bin == NULL || bin_of == NULL || bins_alloc(out, kept) != DFLE_OK) {
        free(first);
        free(lnA_by_bin);
        free(bin_of);
        return dfle_error_set(err, DFLE_ENOMEM, "slope-area bins: out of memory "
                              "binning %zu pairs into %zu bins", n, nbins);
    }
    size_t *fill = first + nbins + 1;
    double *S_by_bin = lnA_by_bin + usable;
    for (size_t i = 0, u = 0; i < n; i++) {
        if (usable_pair(A[i], S[i])) {
            size_t k = bin_of[u], slot = first[k] + fill[k]++;
            lnA_by_bin[slot] = lnA_by_bin[2 * usable + u++];
            S_by_bin[slot] = S[i];
        }
    }
    free(bin_of);

    for (size_t k = 0, j = 0; k < nbins; k++) {
        size_t m = first[k + 1] - first[k];
        double *s = S_by_bin + first[k], sum_lnA = 0.0, sum_S = 0.0, sum_lnS = 0.0;
        size_t positive = 0;
        if (m == 0)
            continue;
        for (size_t i = 0; i < m; i++) {
            sum_lnA += lnA_by_bin[first[k] + i];
            sum_S += s[i];
            if (s[i] > 0.0) {
                sum_lnS += log(s[i]);
                positive++;
            }
        }
        sort_doubles(s, m);
        out->A[j] = exp(sum_lnA / (double)m);
        out->A_lo[j] = grid_edge(&g, k);
        out->A_hi[j] = grid_edge(&g, k + 1);
        out->S_mean[j] = sum_S / (double)m;
        out->S_median[j] = quantile_of_sorted(s, m, 0.5);
        out->S_q25[j] = quantile_of_sorted(s, m, 0.25);
        out->S_q75[j] = quantile_of_sorted(s, m, 0.75);
        /* Flats (S = 0) have no logarithm: the log-space mean is that of
         * the positive slopes; a bin with none gets 0 (the limit of the
         * product, and a value the log fit already leaves out) rather than
         * a NaN that would travel into every file and plot. */
        out->S_geomean[j] = positive > 0 ? exp(sum_lnS / (double)positive) : 0.0;
        out->count[j++] = m;
    }
    out->nbins = nbins;
    out->n = kept;
    out->n_empty = nbins - kept;
    free(first);
    free(lnA_by_bin);
    return DFLE_OK;
}

/* ---- Fit of Eq. (2) ---------------------------------------------- */

enum { EQ2_NPAR = 3, EQ2_GUESS_COARSE = 13, EQ2_GUESS_REFINE = 7, EQ2_MAX_ITER = 1000 };

typedef struct eq2_data {
    size_t n;
    const double *lnA;
    const double *S;
    double *lnS; /* log residuals: ln S of each point, else NULL */
} eq2_data;

double dfle_eq2_eval(double S_df, double A_df, double a2, double A)
{
    return S_df / (1.0 + pow(A / A_df, a2));
}

/* Eq. (2) at ln A for u = (ln S_df, ln A_df, a2), and optionally dS/du.
 * With t = (A/A_df)^a2 the model needs 1/(1+t) and t/(1+t); both are
 * logistic functions of z = ln t, evaluated here without forming t, which
 * overflows as soon as a trial step makes a2 or ln A_df extreme. */
static double eq2_model(const double *u, double lnA, double *dS)
{
    double z = u[2] * (lnA - u[1]), e = exp(-fabs(z)); /* e <= 1 */
    double below = z > 0.0 ? e / (1.0 + e) : 1.0 / (1.0 + e);
    double above = z > 0.0 ? 1.0 / (1.0 + e) : e / (1.0 + e);
    /* A wild trial step must give a large finite misfit, which the trust
     * region rejects, rather than Inf * 0 = NaN, which it cannot judge. */
    double S = exp(fmin(u[0], 700.0)) * below;
    if (dS != NULL) {
        dS[0] = S;
        dS[1] = S * u[2] * above;
        dS[2] = -S * above * (lnA - u[1]);
    }
    return S;
}

/* ln of Eq. (2) at ln A, and optionally d ln S / du: the same logistic
 * pieces as eq2_model, in logarithms, so neither underflows to 0 (whose
 * logarithm a log fit cannot take) however far a trial step goes. */
static double eq2_model_log(const double *u, double lnA, double *dlnS)
{
    double z = u[2] * (lnA - u[1]), e = exp(-fabs(z));
    double above = z > 0.0 ? 1.0 / (1.0 + e) : e / (1.0 + e);
    /* ln(1 / (1 + e^z)) = -softplus(z), without overflow */
    double ln_below = -(fmax(z, 0.0) + log1p(e));
    if (dlnS != NULL) {
        dlnS[0] = 1.0;
        dlnS[1] = u[2] * above;
        dlnS[2] = -above * (lnA - u[1]);
    }
    return fmin(u[0], 700.0) + ln_below;
}

/* Residual of point i: in S, or in ln S for a log fit. */
static double eq2_residual(const eq2_data *d, const double *u, size_t i, double *dr)
{
    if (d->lnS != NULL)
        return eq2_model_log(u, d->lnA[i], dr) - d->lnS[i];
    return eq2_model(u, d->lnA[i], dr) - d->S[i];
}

static double eq2_sse(const eq2_data *d, const double *u)
{
    double sse = 0.0;
    for (size_t i = 0; i < d->n; i++) {
        double r = eq2_residual(d, u, i, NULL);
        sse += r * r;
    }
    return sse;
}

static void vector_to_params(const gsl_vector *x, double *u)
{
    for (size_t j = 0; j < EQ2_NPAR; j++)
        u[j] = gsl_vector_get(x, j);
}

static int eq2_residuals(const gsl_vector *x, void *data, gsl_vector *f)
{
    const eq2_data *d = data;
    double u[EQ2_NPAR];
    vector_to_params(x, u);
    for (size_t i = 0; i < d->n; i++)
        gsl_vector_set(f, i, eq2_residual(d, u, i, NULL));
    return GSL_SUCCESS;
}

static int eq2_jacobian(const gsl_vector *x, void *data, gsl_matrix *J)
{
    const eq2_data *d = data;
    double u[EQ2_NPAR], dS[EQ2_NPAR];
    vector_to_params(x, u);
    for (size_t i = 0; i < d->n; i++) {
        eq2_residual(d, u, i, dS);
        for (size_t j = 0; j < EQ2_NPAR; j++)
            gsl_matrix_set(J, i, j, dS[j]);
    }
    return GSL_SUCCESS;
}

/* Starting point.  For a given S_df, Eq. (2) is linear after a change of
 * variable:  ln(S_df / S - 1) = a2 ln A - a2 ln A_df.  So each S_df on a
 * grid from 0.8 to 20 times the largest slope gets A_df and a2 from a
 * weighted straight-line fit (weights (S (S_df - S) / S_df)^2 carry the
 * misfit back to linear slope, ((S_df - S) / S_df)^2 to log slope;
 * points with S >= S_df have no image and sit out), and the candidate
 * with the least squared misfit in the fit's own space wins.  This needs
 * no sorting or smoothing, copes with noise, and finds transitions beyond
 * either end of the data, where a start in the middle slides into the
 * flat a2 -> 0 valley.
 *
 * The grid is searched coarse to fine: 13 values of ln S_df, then a
 * golden-section search between the neighbours of the best.  Each value
 * costs a pass of logarithms and one of the misfit over the data, and
 * the start only has to lie in the basin Levenberg-Marquardt converges
 * from, so 25 values did what 60 evenly spaced ones did, in 40 % of the
 * time; and 7 golden-section values, which leave S_df within about 5 %,
 * what 12 did (the same 9 steps of Levenberg-Marquardt on the Fig. 9
 * profile, the same fit to 2e-12), so that the fit stays under the cost
 * of the steady state it measures now that the direct solver is twice
 * as fast. */
typedef struct eq2_guess {
    double S_hi, lnA_lo, lnA_hi;
    double best, u[EQ2_NPAR]; /* the best candidate so far and its misfit */
} eq2_guess;

/* The misfit of the candidate whose S_df is exp(lnS_df) (HUGE_VAL when
 * the line fit has no meaning there); keeps it when it is the best. */
static double eq2_try(const eq2_data *d, eq2_guess *g, double lnS_df)
{
    double S_df = exp(lnS_df), sw = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
    for (size_t i = 0; i < d->n; i++) {
        double s = d->S[i], x = d->lnA[i];
        if (!(s < S_df))
            continue;
        /* The weight carries a misfit in y back to one in S, or in
         * ln S for a log fit (d ln S / dy = -(S_df - S) / S_df). */
        double y = log(S_df / s - 1.0);
        double w = (d->lnS != NULL ? 1.0 : s) * (S_df - s) / S_df;
        w *= w;
        sw += w;
        sx += w * x;
        sy += w * y;
        sxx += w * x * x;
        sxy += w * x * y;
    }
    if (!(sw > 0.0))
        return HUGE_VAL;
    double x_mean = sx / sw, y_mean = sy / sw;
    double var = sxx / sw - x_mean * x_mean;
    double cov = sxy / sw - x_mean * y_mean;
    if (!(var > 1e-12 * (g->lnA_hi - g->lnA_lo) * (g->lnA_hi - g->lnA_lo)))
        return HUGE_VAL;
    double a2 = cov / var;
    double cand[EQ2_NPAR] = { lnS_df, x_mean - y_mean / a2, a2 };
    if (!(a2 > 0.0) || !isfinite(cand[1]))
        return HUGE_VAL;
    double sse = eq2_sse(d, cand);
    if (sse < g->best) {
        g->best = sse;
        memcpy(g->u, cand, sizeof cand);
    }
    return sse;
}

static void eq2_initial_guess(const eq2_data *d, double *u)
{
    eq2_guess g = { 0.0, HUGE_VAL, -HUGE_VAL, 0.0, { 0.0 } };
    for (size_t i = 0; i < d->n; i++) {
        g.S_hi = fmax(g.S_hi, d->S[i]);
        g.lnA_lo = fmin(g.lnA_lo, d->lnA[i]);
        g.lnA_hi = fmax(g.lnA_hi, d->lnA[i]);
    }
    g.u[0] = log(g.S_hi);
    g.u[1] = 0.5 * (g.lnA_lo + g.lnA_hi);
    g.u[2] = 1.0;
    g.best = eq2_sse(d, g.u);

    /* S_df from 0.8 to 20 times the largest slope. */
    const double lo = log(0.8 * g.S_hi), step = log(25.0) / (EQ2_GUESS_COARSE - 1);
    double sse[EQ2_GUESS_COARSE];
    int k_best = -1;
    for (int k = 0; k < EQ2_GUESS_COARSE; k++) {
        sse[k] = eq2_try(d, &g, lo + k * step);
        if (sse[k] < HUGE_VAL && (k_best < 0 || sse[k] < sse[k_best]))
            k_best = k;
    }
    if (k_best >= 0) {
        /* Golden section on [k_best - 1, k_best + 1] (clamped). */
        const double r = 0.5 * (sqrt(5.0) - 1.0);
        double a = lo + (k_best > 0 ? k_best - 1 : 0) * step;
        double b = lo + (k_best < EQ2_GUESS_COARSE - 1 ? k_best + 1 : k_best) * step;
        double c = b - r * (b - a), e = a + r * (b - a);
        double fc = eq2_try(d, &g, c), fe = eq2_try(d, &g, e);
        for (int it = 2; it < EQ2_GUESS_REFINE; it++) {
            if (fc < fe) {
                b = e, e = c, fe = fc;
                c = b - r * (b - a);
                fc = eq2_try(d, &g, c);
            } else {
                a = c, c = e, fc = fe;
                e = a + r * (b - a);
                fe = eq2_try(d, &g, e);
            }
        }
    }
    memcpy(u, g.u, sizeof g.u);
}

/* Plain Levenberg-Marquardt (GSL trust region, More scaling): from
 * eq2_initial_guess it converges in under a dozen steps on typical
 * profiles, so geodesic acceleration, with its second derivatives and
 * extra step-rejection rule, buys nothing here.
 *
 * GSL's error handler is process-wide and belongs to the host, so it is
 * left alone and every status is checked.  The only GSL_ERROR reachable
 * from here is an allocation failure in gsl_multifit_nlinear_alloc, which
 * the default handler turns into abort(); a host that must survive it
 * calls gsl_set_error_handler_off() once at start-up, and we then return
 * DFLE_ENOMEM.
 *
 * The loop is ours, not gsl_multifit_nlinear_driver: GSL's step test
 * (|dx| < xtol^2 + xtol |x|) turns absolute where ln S_df is near 0, and
 * its gradient test is absolute whenever the misfit is below 1, as slope
 * misfits are.  Ours asks each of u to move by less than 1e-10 (1 + |u|),
 * and takes GSL_ENOPROG after progress as the double-precision floor. */
static int eq2_solve(eq2_data *d, double *u, size_t *iterations,
                     dfle_error *err)
{
    gsl_multifit_nlinear_parameters par = gsl_multifit_nlinear_default_parameters();
    par.trs = gsl_multifit_nlinear_trs_lm;
    par.scale = gsl_multifit_nlinear_scale_more;
    gsl_multifit_nlinear_workspace *w =
        gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &par, d->n, EQ2_NPAR);
    if (w == NULL)
        return dfle_error_set(err, DFLE_ENOMEM,
                              "slope-area fit: out of memory for the solver");

    gsl_multifit_nlinear_fdf fdf;
    memset(&fdf, 0, sizeof fdf);
    fdf.f = eq2_residuals;
    fdf.df = eq2_jacobian;
    fdf.n = d->n;
    fdf.p = EQ2_NPAR;
    fdf.params = d;
    gsl_vector_view start = gsl_vector_view_array(u, EQ2_NPAR);
    int gsl_status = gsl_multifit_nlinear_init(&start.vector, &fdf, w);
    int converged = 0;
    size_t iter = 0;

    while (gsl_status == GSL_SUCCESS && !converged && iter < EQ2_MAX_ITER) {
        double before[EQ2_NPAR];
        vector_to_params(gsl_multifit_nlinear_position(w), before);
        gsl_status = gsl_multifit_nlinear_iterate(w);
        iter++;
        /* ENOPROG: fifteen ever shorter steps failed to lower the misfit. */
        if (gsl_status == GSL_ENOPROG && iter > 1)
            gsl_status = GSL_SUCCESS;
        else if (gsl_status != GSL_SUCCESS)
            break;
        vector_to_params(gsl_multifit_nlinear_position(w), u);
        converged = 1; /* ENOPROG leaves u where it was */
        for (size_t j = 0; j < EQ2_NPAR; j++)
            converged &= fabs(u[j] - before[j]) <= 1e-10 * (1.0 + fabs(before[j]));
    }
    vector_to_params(gsl_multifit_nlinear_position(w), u);
    *iterations = gsl_multifit_nlinear_niter(w);
    gsl_multifit_nlinear_free(w);

    if (gsl_status != GSL_SUCCESS)
        return dfle_error_set(err, DFLE_EFIT, "slope-area fit: solver failed "
                              "from S_df %g, A_df %g m^2, a2 %g: %s", exp(u[0]),
                              exp(u[1]), u[2], gsl_strerror(gsl_status));
    if (!converged)
        return dfle_error_set(err, DFLE_EFIT,
                              "slope-area fit: no convergence in %d iterations "
                              "(S_df %g, A_df %g m^2, a2 %g when stopped); are the "
                              "data a pure power law or nearly constant?",
                              EQ2_MAX_ITER, exp(u[0]), exp(u[1]), u[2]);
    return DFLE_OK;
}

/* Fit Eq. (2) to n points with residuals in S or ln S: the checks on
 * the data, the start, the solver and the checks on the result.  u
 * receives (ln S_df, ln A_df, a2). */
static int fit_points(size_t n, const double *A, const double *S, dfle_residuals residuals,
                      double *u, size_t *iterations, dfle_error *err)
{
    if (n < 4)
        return dfle_error_set(err, DFLE_EINVAL,
                              "slope-area fit: %zu points, need at least 4", n);
    if (A == NULL || S == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "slope-area fit: %s array is NULL",
                              A == NULL ? "area" : "slope");

    double A_min = HUGE_VAL, A_max = 0.0, S_min = HUGE_VAL, S_max = 0.0;
    for (size_t i = 0; i < n; i++) {
        if (!(A[i] > 0.0) || !isfinite(A[i]))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "slope-area fit: point %zu has area %g m^2; "
                                  "areas must be positive and finite", i, A[i]);
        if (!(S[i] > 0.0) || !isfinite(S[i]))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "slope-area fit: point %zu has slope %g; "
                                  "Eq. (2) needs positive finite slopes", i, S[i]);
        A_min = fmin(A_min, A[i]);
        A_max = fmax(A_max, A[i]);
        S_min = fmin(S_min, S[i]);
        S_max = fmax(S_max, S[i]);
    }
    /* Three parameters need three distinct areas; a third one strictly
     * inside the range is enough to know there are. */
    int third_area = 0;
    for (size_t i = 0; i < n && !third_area; i++)
        third_area = A[i] > A_min && A[i] < A_max;
    if (!third_area)
        return dfle_error_set(err, DFLE_EINVAL,
                              "slope-area fit: the %zu points have fewer than 3 "
                              "distinct areas; Eq. (2) has 3 parameters", n);
    if (S_min == S_max)
        return dfle_error_set(err, DFLE_EFIT,
                              "slope-area fit: all %zu slopes equal %g; a constant "
                              "slope has no transition area to fit", n, S_min);

    double *lnA = malloc(2 * n * sizeof *lnA);
    if (lnA == NULL)
        return dfle_error_set(err, DFLE_ENOMEM,
                              "slope-area fit: out of memory for %zu points", n);
    for (size_t i = 0; i < n; i++) {
        lnA[i] = log(A[i]);
        lnA[n + i] = log(S[i]);
    }
    eq2_data d = { n, lnA, S, residuals == DFLE_RESIDUALS_LOG ? lnA + n : NULL };
    eq2_initial_guess(&d, u);
    int status = eq2_solve(&d, u, iterations, err);
    double sse = eq2_sse(&d, u);
    free(lnA);
    if (status != DFLE_OK)
        return status;

    /* Pure power-law data are Eq. (2) only in the limit A_df -> 0,
     * S_df -> Inf, and flat data in the limit A_df -> Inf; the solver then
     * stops somewhere along a valley where only S_df A_df^a2 (or S_df) is
     * determined.  Such numbers would look like a result but mean nothing,
     * so an A_df far outside the data is a failed fit. */
    double S_df = exp(u[0]), A_df = exp(u[1]), a2 = u[2];
    if (!(A_df >= A_min * 1e-4 && A_df <= A_max * 1e4))
        return dfle_error_set(err, DFLE_EFIT,
                              "slope-area fit: A_df = %g m^2 lies far outside the "
                              "areas (%g to %g m^2), so Eq. (2) is not determined: "
                              "the data look like %s", A_df, A_min, A_max,
                              A_df < A_min ? "a pure power law, with no roll-over "
                              "at small area" : "a constant slope");
    if (!isfinite(S_df) || !isfinite(a2) || !isfinite(sse))
        return dfle_error_set(err, DFLE_EFIT,
                              "slope-area fit: the solution is not finite (S_df %g, "
                              "A_df %g m^2, a2 %g)", S_df, A_df, a2);
    return DFLE_OK;
}

/* R^2 and the RMS residual of Eq. (2) with parameters p = (S_df, A_df,
 * a2) on n points, in S or in log10 S (rmse then in decades). */
static void fit_stats(const double *p, size_t n, const double *A, const double *S,
                      dfle_residuals space, double *r2, double *rmse)
{
    double mean = 0.0, ss_res = 0.0, ss_tot = 0.0;
    int lg = space == DFLE_RESIDUALS_LOG;
    for (size_t i = 0; i < n; i++)
        mean += (lg ? log10(S[i]) : S[i]) / (double)n;
    /* log10 of the model from its logarithm (eq2_model_log): Eq. (2)
     * underflows to S = 0 far past A_df when a2 is large, and log10(0)
     * made R^2 -inf and the RMS inf for a fit that is merely poor there. */
    const double u[3] = { log(p[0]), log(p[1]), p[2] };
    for (size_t i = 0; i < n; i++) {
        double y = lg ? log10(S[i]) : S[i];
        double f = lg ? eq2_model_log(u, log(A[i]), NULL) / log(10.0)
                      : dfle_eq2_eval(p[0], p[1], p[2], A[i]);
        double r = f - y;
        ss_res += r * r;
        ss_tot += (y - mean) * (y - mean);
    }
    *r2 = n >= 2 && ss_tot > 0.0 ? 1.0 - ss_res / ss_tot : NAN;
    *rmse = n >= 1 ? sqrt(ss_res / (double)n) : NAN;
}

double dfle_eq2_r2(double S_df, double A_df, double a2, size_t n, const double *A,
                   const double *S, dfle_residuals space)
{
    const double p[3] = { S_df, A_df, a2 };
    double r2, rmse;
    fit_stats(p, n, A, S, space, &r2, &rmse);
    return r2;
}

static void set_params(dfle_eq2_fit *out, const double *u, dfle_residuals residuals,
                       size_t n_points, size_t iterations)
{
    out->S_df = exp(u[0]);
    out->A_df = exp(u[1]);
    out->a2 = u[2];
    out->residuals = residuals;
    out->n_points = n_points;
    out->iterations = iterations;
}

/* R^2 and RMS residual of the fitted parameters in S on (lin_A, lin_S)
 * and in log S on (log_A, log_S). */
static void set_stats(dfle_eq2_fit *out, size_t n_lin, const double *lin_A, const double *lin_S,
                      size_t n_log, const double *log_A, const double *log_S)
{
    const double p[3] = { out->S_df, out->A_df, out->a2 };
    fit_stats(p, n_lin, lin_A, lin_S, DFLE_RESIDUALS_LINEAR, &out->r2, &out->rmse);
    fit_stats(p, n_log, log_A, log_S, DFLE_RESIDUALS_LOG, &out->r2_log, &out->rmse_log);
}

/* S_max, S_ch (the slope of the smallest area: ties, raw pixels, share
 * it) and S_max - S_ch of n points. */
static void set_extremes(dfle_eq2_fit *out, size_t n, const double *A, const double *S)
{
    double A_min = HUGE_VAL, S_max = 0.0, S_ch = 0.0;
    size_t n_ch = 0;
    for (size_t i = 0; i < n; i++) {
        A_min = fmin(A_min, A[i]);
        S_max = fmax(S_max, S[i]);
    }
    for (size_t i = 0; i < n; i++)
        if (A[i] == A_min) {
            S_ch += S[i];
            n_ch++;
        }
    out->S_max = n > 0 ? S_max : NAN;
    out->S_ch = n_ch > 0 ? S_ch / (double)n_ch : NAN;
    out->S_max_minus_S_ch = n > 0 ? fmax(0.0, out->S_max - out->S_ch) : NAN;
}

int dfle_fit_eq2_residuals(size_t n, const double *A, const double *S, dfle_residuals residuals,
                           dfle_eq2_fit *out, dfle_error *err)
{
    double u[EQ2_NPAR];
    size_t iterations = 0;
    int st;

    if (out == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "slope-area fit: output is NULL");
    memset(out, 0, sizeof *out);
    if ((st = fit_points(n, A, S, residuals, u, &iterations, err)) != DFLE_OK)
        return st;
    set_params(out, u, residuals, n, iterations);
    set_stats(out, n, A, S, n, A, S);
    set_extremes(out, n, A, S);
    return DFLE_OK;
}

int dfle_fit_eq2(size_t n, const double *A, const double *S,
                 dfle_eq2_fit *out, dfle_error *err)
{
    return dfle_fit_eq2_residuals(n, A, S, DFLE_RESIDUALS_LINEAR, out, err);
}

int dfle_slope_area_fit(size_t n, const double *A, const double *S,
                        size_t nbins, dfle_bins *bins, dfle_eq2_fit *fit,
                        dfle_error *err)
{
    return dfle_slope_area_fit_residuals(n, A, S, nbins, DFLE_RESIDUALS_LINEAR, bins, fit, err);
}

int dfle_slope_area_fit_residuals(size_t n, const double *A, const double *S, size_t nbins,
                                  dfle_residuals residuals, dfle_bins *bins, dfle_eq2_fit *fit,
                                  dfle_error *err)
{
    dfle_bins local;
    dfle_bins *b = bins != NULL ? bins : &local;
    if (fit == NULL) {
        if (bins != NULL)
            memset(bins, 0, sizeof *bins);
        return dfle_error_set(err, DFLE_EINVAL, "slope-area fit: output is NULL");
    }
    memset(fit, 0, sizeof *fit);
    if (residuals != DFLE_RESIDUALS_LINEAR && residuals != DFLE_RESIDUALS_LOG) {
        if (bins != NULL)
            memset(bins, 0, sizeof *bins);
        return dfle_error_set(err, DFLE_EINVAL, "slope-area fit: residuals %d is neither "
                              "linear (0) nor log (1)", (int)residuals);
    }
    int status = dfle_bins_compute(n, A, S, nbins, b, err);
    if (status != DFLE_OK)
        return status;

    /* Eq. (2) is positive for any positive S_df, so a bin whose mean slope
     * is zero or negative (flats, reverse slopes in noisy DEMs) can never
     * be matched in S, and one without a positive slope has no mean in
     * log S; such bins are left out of the fit but kept in the bins. */
    double *pts = malloc(4 * (b->n ? b->n : 1) * sizeof *pts);
    size_t m_lin = 0, m_log = 0;
    if (pts == NULL) {
        status = dfle_error_set(err, DFLE_ENOMEM,
                                "slope-area fit: out of memory for %zu bins", b->n);
    } else {
        double *lin_A = pts, *lin_S = pts + b->n, *log_A = pts + 2 * b->n, *log_S = pts + 3 * b->n;
        int lg = residuals == DFLE_RESIDUALS_LOG;
        double u[EQ2_NPAR];
        size_t iterations = 0, m;
        for (size_t k = 0; k < b->n; k++) {
            if (b->S_mean[k] > 0.0) {
                lin_A[m_lin] = b->A[k];
                lin_S[m_lin++] = b->S_mean[k];
            }
            if (b->S_geomean[k] > 0.0) {
                log_A[m_log] = b->A[k];
                log_S[m_log++] = b->S_geomean[k];
            }
        }
        m = lg ? m_log : m_lin;
        status = m < 4 ? dfle_error_set(err, DFLE_EFIT, "slope-area fit: %zu of %zu "
                                        "non-empty bins have a positive %s slope, "
                                        "need at least 4", m, b->n,
                                        lg ? "(geometric) mean" : "mean")
                       : fit_points(m, lg ? log_A : lin_A, lg ? log_S : lin_S, residuals, u,
                                    &iterations, err);
        if (status == DFLE_OK) {
            set_params(fit, u, residuals, m, iterations);
            set_stats(fit, m_lin, lin_A, lin_S, m_log, log_A, log_S);
            set_extremes(fit, m_lin, lin_A, lin_S);
        }
        free(pts);
    }
    /* On failure the caller has nothing to release, as with every other
     * dfle call; on success it owns the bins only if it asked for them. */
    if (status != DFLE_OK || bins == NULL)
        dfle_bins_release(b);
    if (status != DFLE_OK)
        memset(fit, 0, sizeof *fit);
    return status;
}
