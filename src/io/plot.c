/*
 * plot.c - the figures: x-y, stacked panels, slope-area, long profile
 * (through plot_frame.c); maps are plot_map.c's.
 *
 * Each checks its data and options before gnuplot starts, so a bad call
 * never starts gnuplot or touches a file.  Labels and titles are gnuplot
 * "enhanced text": m^2 and S_{df} render as super- and subscripts, which
 * is what the figures need; the default labels are the house labels of
 * dfle_plot_label ("Slope, S (m/m)").
 */
#include "dfle/plot.h"

#include "io/plot_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


/* Layers of series, coloured from the palette in order except where a
 * series names its colour (so an explicit grey does not use up blue). */
static dfle_gp_layer *layers_of(const dfle_plot_series *s, size_t n, const dfle_gp_frame *fr,
                                dfle_error *err)
{
    dfle_gp_layer *L = malloc(n * sizeof *L);
    size_t k = 0;
    if (L == NULL) {
        dfle_error_set(err, DFLE_ENOMEM, "plot: out of memory");
        return NULL;
    }
    for (size_t i = 0; i < n; i++)
        dfle_gp_layer_of(&L[i], &s[i], s[i].rgb != NULL ? i : k++, fr);
    return L;
}

int dfle_plot_xy(const char *path, const dfle_plot_opts *opts,
                 const dfle_plot_series *series, size_t nseries,
                 dfle_error *err)
{
    dfle_gp_frame fr;
    dfle_gp_panel panel;
    dfle_gp_layer *L;
    int rc;
    if ((rc = dfle_gp_frame_of(path, opts, 16, 10, &fr, err)) < 0 ||
        (rc = dfle_plot_series_check(series, nseries, err)) < 0)
        return rc;
    if ((L = layers_of(series, nseries, &fr, err)) == NULL)
        return DFLE_ENOMEM;
    memset(&panel, 0, sizeof panel);
    panel.layers = L;
    panel.nl = nseries;
    panel.y = opts != NULL ? &opts->y : NULL;
    rc = dfle_gp_figure(path, &fr, opts, 0, NULL, &panel, 1, err);
    free(L);
    return rc;
}

int dfle_plot_panels(const char *path, const dfle_plot_opts *opts,
                     const dfle_plot_panel *panels, size_t npanels, dfle_error *err)
{
    dfle_gp_frame fr;
    dfle_gp_panel *P = NULL;
    int rc;
    if (panels == NULL || npanels == 0 || npanels > 16)
        return dfle_error_set(err, DFLE_EINVAL, "plot: 1 to 16 panels (got %zu)", npanels);
    if ((rc = dfle_gp_frame_of(path, opts, 16, 5 + 4.5 * (double)npanels, &fr, err)) < 0)
        return rc;
    for (size_t p = 0; p < npanels; p++) {
        if ((rc = dfle_plot_series_check(panels[p].series, panels[p].nseries, err)) < 0)
            return rc;
        if (!isfinite(panels[p].weight) || panels[p].weight < 0)
            return dfle_error_set(err, DFLE_EINVAL, "plot: panel %zu: weight must be >= 0 "
                                  "(got %g)", p + 1, panels[p].weight);
    }
    if ((P = calloc(npanels, sizeof *P)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "plot: out of memory");
    for (size_t p = 0; p < npanels && rc == DFLE_OK; p++) {
        P[p].layers = layers_of(panels[p].series, panels[p].nseries, &fr, err);
        P[p].nl = panels[p].nseries;
        P[p].y = &panels[p].y;
        P[p].weight = panels[p].weight;
        if (P[p].layers == NULL)
            rc = DFLE_ENOMEM;
    }
    if (rc == DFLE_OK)
        rc = dfle_gp_figure(path, &fr, opts, 0, NULL, P, npanels, err);
    for (size_t p = 0; p < npanels; p++)
        free(P[p].layers);
    free(P);
    return rc;
}

/* Eq. (2), S = S_df / (1 + (A/A_df)^a2), here rather than from
 * analysis.c so that plotting does not depend on the fitting code. */
static double eq2(const dfle_eq2_fit *fit, double A)
{
    return fit->S_df / (1.0 + pow(A / fit->A_df, fit->a2));
}

/* A layer drawn as the caller says (not as a series). */
static void layer_set(dfle_gp_layer *l, size_t n, const double *x, const double *y,
                      const char *title, int kind, const char *rgb, double lw, int pt, double ps)
{
    memset(l, 0, sizeof *l);
    l->n = n;
    l->x = x;
    l->y = y;
    l->title = title;
    l->line = kind == DFLE_GP_LINES;
    l->marks = !l->line;
    dfle_gp_look_set(&l->look, kind, rgb, lw, 1, pt, ps, 0);
}

int dfle_gp_slope_area_panel(dfle_gp_sa_panel *sp, const dfle_gp_frame *fr, const char *path,
                             size_t n, const double *A, const double *S, const dfle_bins *bins,
                             const dfle_eq2_fit *fit, const dfle_plot_axis *y, dfle_error *err)
{
    dfle_gp_layer *L = sp->L;
    size_t nl = 0;
    memset(sp, 0, sizeof *sp);
    if (n == 0 || A == NULL || S == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "plot: slope-area data "
                              "missing (n = %zu, A or S NULL)", n);
    if (bins != NULL && bins->n > 0 && (bins->A == NULL || !bins->S_mean))
        return dfle_error_set(err, DFLE_EINVAL, "plot: bins have NULL A or "
                              "S_mean");
    if (fit != NULL && !(isfinite(fit->S_df) && fit->S_df > 0 &&
                         isfinite(fit->A_df) && fit->A_df > 0 &&
                         isfinite(fit->a2)))
        return dfle_error_set(err, DFLE_EINVAL, "plot: fit cannot be drawn "
                              "(S_df = %g, A_df = %g, a2 = %g)", fit->S_df,
                              fit->A_df, fit->a2);
    double amin = HUGE_VAL, amax = -HUGE_VAL;
    for (size_t i = 0; i < n; i++)
        if (isfinite(A[i]) && isfinite(S[i]) && A[i] > 0 && S[i] > 0) {
            amin = fmin(amin, A[i]);
            amax = fmax(amax, A[i]);
        }
    if (amin > amax)
        return dfle_error_set(err, DFLE_EINVAL, "plot: no slope-area pair "
                              "with finite A > 0 and S > 0 for '%s'", path);

    /* Thousands of DEM cells: small dots, grey, under everything. */
    layer_set(&L[nl++], n, A, S, "Data", DFLE_GP_POINTS, DFLE_GP_GREY, 1, 7,
              dfle_gp_ps(fr, n > 2000 ? 1.8 : 2.6));
    if (bins != NULL && bins->n > 0) {
        int bars = bins->S_q25 != NULL && bins->S_q75 != NULL;
        layer_set(&L[nl], bins->n, bins->A, bins->S_mean,
                  bars ? "Binned mean (quartiles)" : "Binned mean",
                  bars ? DFLE_GP_BARS : DFLE_GP_POINTS, "#000000", 2, 7, dfle_gp_ps(fr, 4.2));
        if (bars)
            L[nl].lo = bins->S_q25, L[nl].hi = bins->S_q75;
        nl++;
    }
    /* The curve spans the data's areas; A_df is marked only inside it. */
    if (fit != NULL) {
        char sdf[40], adf[40], a2[40], r2[32] = "";
        for (int i = 0; i < DFLE_GP_FIT_SAMPLES; i++) {
            sp->fa[i] = amin * pow(amax / amin, i / (DFLE_GP_FIT_SAMPLES - 1.0));
            sp->fs[i] = eq2(fit, sp->fa[i]);
        }
        dfle_plot_number(sdf, sizeof sdf, fit->S_df);
        dfle_plot_number(adf, sizeof adf, fit->A_df);
        dfle_plot_number(a2, sizeof a2, fit->a2);
        if (isfinite(fit->r2))
            snprintf(r2, sizeof r2, ", {/:Italic R}^2 = %.3f", fit->r2);
        int mark = fit->A_df >= amin && fit->A_df <= amax;
        snprintf(sp->ftitle, sizeof sp->ftitle, "Eq. (2): {/:Italic S}_{df} = %s, "
                 "{/:Italic a}_2 = %s%s%s%s%s", sdf, a2, r2,
                 mark ? "" : ", {/:Italic A}_{df} = ", mark ? "" : adf,
                 mark ? "" : " m^2");
        layer_set(&L[nl++], DFLE_GP_FIT_SAMPLES, sp->fa, sp->fs, sp->ftitle, DFLE_GP_LINES,
                  DFLE_GP_FIT, 2.5, 0, 0);
        if (mark) { /* as in the paper's Fig. 1: open circle at (A_df,
                     * S_df/2) on the curve and a dashed line at A_df */
            sp->mark_a = fit->A_df;
            sp->mark_s = eq2(fit, fit->A_df);
            snprintf(sp->mtitle, sizeof sp->mtitle, "{/:Italic A}_{df} = %s m^2", adf);
            layer_set(&L[nl++], 1, &sp->mark_a, &sp->mark_s, sp->mtitle, DFLE_GP_POINTS,
                      DFLE_GP_FIT, 3, 6, dfle_gp_ps(fr, 10));
            snprintf(sp->extra, sizeof sp->extra, "set arrow from %.17g, graph 0 to "
                     "%.17g, graph 1 nohead dt 2 lw 1.5 lc rgb '%s' back\n",
                     sp->mark_a, sp->mark_a, DFLE_GP_FIT);
        }
    }
    sp->panel.layers = L;
    sp->panel.nl = nl;
    sp->panel.y = y;
    sp->panel.ylog = 1;
    sp->panel.ylabel = dfle_plot_label("S", NULL);
    sp->panel.extra = sp->extra[0] != '\0' ? sp->extra : NULL;
    return DFLE_OK;
}

int dfle_plot_slope_area(const char *path, const dfle_plot_opts *opts, size_t n,
                         const double *A, const double *S,
                         const dfle_bins *bins, const dfle_eq2_fit *fit,
                         dfle_error *err)
{
    dfle_gp_frame fr;
    dfle_gp_sa_panel sp;
    int rc = dfle_gp_frame_of(path, opts, 16, 11, &fr, err);
    if (rc < 0 || (rc = dfle_gp_slope_area_panel(&sp, &fr, path, n, A, S, bins, fit,
                                                 opts != NULL ? &opts->y : NULL, err)) < 0)
        return rc;
    return dfle_gp_figure(path, &fr, opts, 1, dfle_plot_label("A", NULL), &sp.panel, 1, err);
}

int dfle_plot_profile(const char *path, const dfle_plot_opts *opts, size_t n,
                      const double *x, const double *z, const double *S,
                      dfle_error *err)
{
    dfle_gp_frame fr;
    dfle_gp_layer top, bot;
    dfle_gp_panel P[2];
    int rc = dfle_gp_frame_of(path, opts, 16, S != NULL ? 13 : 9, &fr, err);
    if (rc < 0) return rc;
    if (n == 0 || x == NULL || z == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "plot: profile data missing "
                              "(n = %zu, x or z NULL)", n);
    layer_set(&top, n, x, z, NULL, DFLE_GP_LINES, "#0072B2", 3, 0, 0);
    memset(P, 0, sizeof P);
    P[0].layers = &top;
    P[0].nl = 1;
    P[0].y = opts != NULL ? &opts->y : NULL;
    P[0].ylabel = dfle_plot_label("z", NULL);
    if (S != NULL) {
        int logS = 1; /* log slope axis unless some finite slope is <= 0 */
        for (size_t i = 0; i < n; i++)
            if (isfinite(x[i]) && isfinite(S[i]) && S[i] <= 0) logS = 0;
        layer_set(&bot, n, x, S, NULL, DFLE_GP_LINES, "#D55E00", 2.5, 0, 0);
        P[1].layers = &bot;
        P[1].nl = 1;
        P[1].ylog = logS;
        P[1].ylabel = dfle_plot_label("S", NULL);
    }
    return dfle_gp_figure(path, &fr, opts, 0, dfle_plot_label("x", NULL), P, S != NULL ? 2 : 1,
                          err);
}
