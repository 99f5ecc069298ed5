/*
 * plot.c - the figures: x-y, stacked panels, slope-area, long profile
 * (through plot_frame.c), and the shaded-relief map.
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

enum { FIT_SAMPLES = 200 };

static void put_label(FILE *f, const char *what, const char *text)
{
    if (text == NULL) return;
    fprintf(f, "set %s ", what);
    dfle_gp_str(f, text);
    fputs("\n", f);
}

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

int dfle_plot_slope_area(const char *path, const dfle_plot_opts *opts, size_t n,
                         const double *A, const double *S,
                         const dfle_bins *bins, const dfle_eq2_fit *fit,
                         dfle_error *err)
{
    dfle_gp_frame fr;
    int rc = dfle_gp_frame_of(path, opts, 16, 11, &fr, err);
    if (rc < 0) return rc;
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

    dfle_gp_layer L[4];
    size_t nl = 0;
    /* Thousands of DEM cells: small dots, grey, under everything. */
    layer_set(&L[nl++], n, A, S, "Data", DFLE_GP_POINTS, DFLE_GP_GREY, 1, 7,
              dfle_gp_ps(&fr, n > 2000 ? 1.8 : 2.6));
    if (bins != NULL && bins->n > 0) {
        int bars = bins->S_q25 != NULL && bins->S_q75 != NULL;
        layer_set(&L[nl], bins->n, bins->A, bins->S_mean,
                  bars ? "Binned mean (quartiles)" : "Binned mean",
                  bars ? DFLE_GP_BARS : DFLE_GP_POINTS, "#000000", 2, 7, dfle_gp_ps(&fr, 4.2));
        if (bars)
            L[nl].lo = bins->S_q25, L[nl].hi = bins->S_q75;
        nl++;
    }
    /* The curve spans the data's areas; A_df is marked only inside it. */
    double fa[FIT_SAMPLES], fs[FIT_SAMPLES], mark_a = 0, mark_s = 0;
    char ftitle[320] = "", mtitle[96] = "", extra[200] = "";
    if (fit != NULL) {
        char sdf[40], adf[40], a2[40], r2[32] = "";
        for (int i = 0; i < FIT_SAMPLES; i++) {
            fa[i] = amin * pow(amax / amin, i / (FIT_SAMPLES - 1.0));
            fs[i] = eq2(fit, fa[i]);
        }
        dfle_plot_number(sdf, sizeof sdf, fit->S_df);
        dfle_plot_number(adf, sizeof adf, fit->A_df);
        dfle_plot_number(a2, sizeof a2, fit->a2);
        if (isfinite(fit->r2))
            snprintf(r2, sizeof r2, ", {/:Italic R}^2 = %.3f", fit->r2);
        int mark = fit->A_df >= amin && fit->A_df <= amax;
        snprintf(ftitle, sizeof ftitle, "Eq. (2): {/:Italic S}_{df} = %s, "
                 "{/:Italic a}_2 = %s%s%s%s%s", sdf, a2, r2,
                 mark ? "" : ", {/:Italic A}_{df} = ", mark ? "" : adf,
                 mark ? "" : " m^2");
        layer_set(&L[nl++], FIT_SAMPLES, fa, fs, ftitle, DFLE_GP_LINES, DFLE_GP_FIT, 2.5, 0, 0);
        if (mark) { /* as in the paper's Fig. 1: open circle at (A_df,
                     * S_df/2) on the curve and a dashed line at A_df */
            mark_a = fit->A_df;
            mark_s = eq2(fit, fit->A_df);
            snprintf(mtitle, sizeof mtitle, "{/:Italic A}_{df} = %s m^2", adf);
            layer_set(&L[nl++], 1, &mark_a, &mark_s, mtitle, DFLE_GP_POINTS, DFLE_GP_FIT, 3, 6,
                      dfle_gp_ps(&fr, 10));
            snprintf(extra, sizeof extra, "set arrow from %.17g, graph 0 to "
                     "%.17g, graph 1 nohead dt 2 lw 1.5 lc rgb '%s' back\n",
                     mark_a, mark_a, DFLE_GP_FIT);
        }
    }
    dfle_gp_panel panel;
    memset(&panel, 0, sizeof panel);
    panel.layers = L;
    panel.nl = nl;
    panel.y = opts != NULL ? &opts->y : NULL;
    panel.ylog = 1;
    panel.ylabel = dfle_plot_label("S", NULL);
    panel.extra = extra[0] != '\0' ? extra : NULL;
    return dfle_gp_figure(path, &fr, opts, 1, dfle_plot_label("A", NULL), &panel, 1, err);
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

/* ---------------------------------------------------------------- */
/* Maps: shaded relief, channels, debris-flow reach                  */
/* ---------------------------------------------------------------- */

/* The hypsometric tint, in gnuplot's palette and in C alike. */
static const double tint_at[5] = {0.0, 0.25, 0.5, 0.75, 1.0};
static const unsigned tint_rgb[5] = {0x2f6b3a, 0x8fae5d, 0xd8c98e, 0xa9825a, 0xf4f1ea};

static double tint_channel(double f, int shift)
{
    int k = 0;
    while (k < 3 && f > tint_at[k + 1])
        k++;
    double u = (f - tint_at[k]) / (tint_at[k + 1] - tint_at[k]);
    double a = (tint_rgb[k] >> shift) & 255, b = (tint_rgb[k + 1] >> shift) & 255;
    return a + u * (b - a);
}

/* Horn's hillshade of cell (r, c) in [0, 1], from the neighbours that
 * have data (a missing one takes the centre's elevation). */
static double shade_at(const dfle_plot_map *m, size_t r, size_t c, size_t step)
{
    double zz[3][3], zc = m->z[r * m->nx + c];
    for (int i = -1; i <= 1; i++)
        for (int j = -1; j <= 1; j++) {
            long long rr = (long long)r + i * (long long)step, cc = (long long)c + j * (long long)step;
            double v = zc;
            if (rr >= 0 && cc >= 0 && rr < (long long)m->ny && cc < (long long)m->nx &&
                !isnan(m->z[rr * (long long)m->nx + cc]))
                v = m->z[rr * (long long)m->nx + cc];
            zz[i + 1][j + 1] = v;
        }
    /* ESRI's formulation: rows of zz run north to south. */
    const double pi = 3.14159265358979323846;
    const double zenith = (90.0 - 45.0) * pi / 180.0, azimuth = (360.0 - 315.0 + 90.0) * pi / 180.0;
    double hx = 8.0 * m->dx * (double)step, hy = 8.0 * m->dy * (double)step;
    double dzdx = ((zz[0][2] + 2 * zz[1][2] + zz[2][2]) - (zz[0][0] + 2 * zz[1][0] + zz[2][0])) / hx;
    double dzdy = ((zz[2][0] + 2 * zz[2][1] + zz[2][2]) - (zz[0][0] + 2 * zz[0][1] + zz[0][2])) / hy;
    double slope = atan(hypot(dzdx, dzdy)), aspect = atan2(dzdy, -dzdx);
    double v = cos(zenith) * cos(slope) + sin(zenith) * sin(slope) * cos(azimuth - aspect);
    return v < 0 ? 0 : v > 1 ? 1 : v;
}

int dfle_plot_hillshade(const char *path, const dfle_plot_map *m, dfle_error *err)
{
    int fmt = dfle_gp_format(path, err);
    double zmin = HUGE_VAL, zmax = -HUGE_VAL;
    size_t step = 1, cols, rows;
    if (fmt < 0) return fmt;
    if (m == NULL || m->z == NULL || m->nx < 2 || m->ny < 2 || !(m->dx > 0) || !(m->dy > 0))
        return dfle_error_set(err, DFLE_EINVAL, "plot: a map needs at least 2 x 2 cells of "
                              "positive size and elevations");
    for (size_t i = 0; i < m->nx * m->ny; i++)
        if (!isnan(m->z[i])) {
            zmin = fmin(zmin, m->z[i]);
            zmax = fmax(zmax, m->z[i]);
        }
    if (zmin > zmax)
        return dfle_error_set(err, DFLE_EINVAL, "plot: every cell of the map is NoData");
    /* The map frames the data: the box of the cells with elevations. */
    size_t r0 = m->ny, r1 = 0, c0 = m->nx, c1 = 0;
    for (size_t i = 0; i < m->nx * m->ny; i++)
        if (!isnan(m->z[i])) {
            size_t rr = i / m->nx, cc = i % m->nx;
            r0 = rr < r0 ? rr : r0, r1 = rr > r1 ? rr : r1;
            c0 = cc < c0 ? cc : c0, c1 = cc > c1 ? cc : c1;
        }
    while ((m->nx / step) * (m->ny / step) > 1500000)
        step++;
    cols = (m->nx + step - 1) / step;
    rows = (m->ny + step - 1) / step;
    /* Pixels: the map's aspect, about 900 wide plus room for the key. */
    double wkm = (double)(c1 - c0 + 1) * m->dx, hkm = (double)(r1 - r0 + 1) * m->dy;
    int w = 1000, h = (int)(80 + 820.0 * hkm / wkm);
    if (h > 1400) { h = 1400; w = (int)(150 + 1250.0 * wkm / hkm); }
    if (h < 400) h = 400;
    dfle_gp_run r;
    int rc = dfle_gp_begin(&r, path, fmt, w, h, err);
    if (rc < 0) return rc;
    /* One packed RGB value per cell (0xRRGGBB), a matrix datablock. */
    fputs("$img << EOD\n", r.f);
    for (size_t rr = 0; rr < rows; rr++) {
        for (size_t cc = 0; cc < cols; cc++) {
            size_t i = rr * step * m->nx + cc * step;
            unsigned rgb = 0xffffff;
            if (!isnan(m->z[i])) {
                double f = zmax > zmin ? (m->z[i] - zmin) / (zmax - zmin) : 0.5;
                double sh = 0.35 + 0.65 * shade_at(m, rr * step, cc * step, step);
                unsigned R = (unsigned)(tint_channel(f, 16) * sh), G = (unsigned)(tint_channel(f, 8) * sh),
                         B = (unsigned)(tint_channel(f, 0) * sh);
                if (m->channel != NULL && m->channel[i] > 0) R = 0x00, G = 0x72, B = 0xB2;
                if (m->reach != NULL && m->reach[i] > 0) R = 0xD5, G = 0x5E, B = 0x00;
                rgb = (R << 16) | (G << 8) | B;
            }
            fprintf(r.f, "%s%u", cc ? " " : "", rgb);
        }
        fputs("\n", r.f);
    }
    fputs("EOD\n", r.f);
    /* A 2 x 2 image off the map gives the colour box its scale. */
    {
        double fx = m->x0 / 1000 - 1e6, fy = m->y0 / 1000 + 1e6;
        fprintf(r.f, "$cb << EOD\n%.17g %.17g %.17g\n%.17g %.17g %.17g\n\n%.17g %.17g %.17g\n"
                "%.17g %.17g %.17g\nEOD\n", fx, fy, zmin, fx + 1, fy, zmax, fx, fy + 1, zmin,
                fx + 1, fy + 1, zmax);
    }
    put_label(r.f, "title", m->title);
    fputs("set xlabel 'Easting (km)'\nset ylabel 'Northing (km)'\n", r.f);
    fputs("set size ratio -1\nset tics out nomirror\nset format x '%.1f'\nset format y '%.1f'\n", r.f);
    fprintf(r.f, "set xrange [%.17g:%.17g]\nset yrange [%.17g:%.17g]\n",
            (m->x0 + (double)c0 * m->dx) / 1000, (m->x0 + (double)(c1 + 1) * m->dx) / 1000,
            (m->y0 - (double)(r1 + 1) * m->dy) / 1000, (m->y0 - (double)r0 * m->dy) / 1000);
    fprintf(r.f, "set cbrange [%.17g:%.17g]\nset cblabel 'Elevation (m)'\nset colorbox\n", zmin,
            zmax > zmin ? zmax : zmin + 1);
    fputs("set palette defined (", r.f);
    for (int k = 0; k < 5; k++)
        fprintf(r.f, "%s%g '#%06x'", k ? ", " : "", tint_at[k], tint_rgb[k]);
    fputs(")\n", r.f);
    fputs("set bmargin 6\nset key at screen 0.5, screen 0.015 center bottom horizontal Left "
          "reverse samplen 1.5 spacing 1.2 width 2 box lt 1 lc rgb '#b0b0b0'\n", r.f);
    /* Cell centres in km: column c at x0 + (c + 0.5) dx (every step-th). */
    double sx = m->dx * (double)step / 1000, sy = m->dy * (double)step / 1000;
    fprintf(r.f, "plot $img matrix using (%.17g + ($1 + 0.5) * %.17g):(%.17g - ($2 + 0.5) * "
            "%.17g):(int($3) >> 16 & 255):(int($3) >> 8 & 255):(int($3) & 255) with rgbimage "
            "notitle, ", m->x0 / 1000, sx, m->y0 / 1000, sy);
    fputs("$cb using 1:2:3 with image notitle", r.f); /* the colour box's scale */
    /* Reach is painted over channels, so the channel colour shows only
     * where no debris flow goes: no legend entry for a colour the map
     * does not show (every channel reached). */
    int channel_seen = 0;
    for (size_t i = 0; m->channel != NULL && !channel_seen && i < m->nx * m->ny; i++)
        channel_seen = m->channel[i] > 0 && !(m->reach != NULL && m->reach[i] > 0);
    if (channel_seen) {
        fputs(", NaN with lines lw 6 lc rgb '#0072B2' title ", r.f);
        dfle_gp_str(r.f, m->channel_label != NULL ? m->channel_label
                         : m->reach != NULL ? "Channels beyond the debris-flow reach"
                                            : "Channel network");
    }
    if (m->reach != NULL) {
        fputs(", NaN with lines lw 6 lc rgb '#D55E00' title ", r.f);
        dfle_gp_str(r.f, m->reach_label != NULL ? m->reach_label : "Debris-flow reach");
    }
    fputs("\n", r.f);
    return dfle_gp_end(&r, err);
}
