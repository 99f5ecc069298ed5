/*
 * plot_corner.c - the corner plot of posterior samples (see
 * dfle_plot_corner in dfle/plot.h): marginals on the diagonal, every pair
 * below it as a scatter with 68 % and 95 % contours.
 *
 * The contours are highest-density regions of a smoothed 2-D histogram:
 * the level enclosing 68 % (95 %) of the samples is found by sorting the
 * cells by density and summing down, then gnuplot traces that level
 * ("set table" of a contoured splot, before the multiplot starts).  The
 * grid lives in axis units (log10 on logarithmic axes), so a parameter
 * sampled in ln x gets round contours where its posterior is log-normal.
 * A corner plot is where trade-offs between parameters show (the paper's
 * Sect. 4.3: k_df, gamma and U), so the pairs get the space and the
 * diagonal gets the numbers.
 */
#include "dfle/plot.h"

#include "dfle/mcmc_diag.h"
#include "io/plot_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_SCATTER = 5000, GRID = 36 };

static double to_axis(double v, int lg) { return lg ? log10(v) : v; }
static double from_axis(double u, int lg) { return lg ? pow(10.0, u) : u; }

static int cmp_desc(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x < y) - (x > y);
}

/* median^{+up}_{-down}, scaled by a power of ten when the numbers are
 * large or small, as enhanced text. */
static void fmt_interval(char *buf, size_t cap, double med, double lo, double hi)
{
    double ref = fabs(med) > 0 ? fabs(med) : fmax(fabs(lo), fabs(hi));
    int e = ref > 0 ? (int)floor(log10(ref)) : 0, dec;
    double s, up, dn, small;
    if (e >= -2 && e <= 3)
        e = 0;
    s = pow(10.0, -e);
    up = (hi - med) * s;
    dn = (med - lo) * s;
    small = fmin(up, dn);
    dec = small > 0 ? 1 - (int)floor(log10(small)) : 2;
    if (dec < 0)
        dec = 0;
    if (dec > 5)
        dec = 5;
    if (e != 0)
        snprintf(buf, cap, "%.*f@^{+%.*f}_{-%.*f} ×10^{%d}", dec, med * s, dec, up, dec, dn, e);
    else
        snprintf(buf, cap, "%.*f@^{+%.*f}_{-%.*f}", dec, med * s, dec, up, dec, dn);
}

/* The axis range of parameter j in axis units, padded 4 %. */
static void axis_range(size_t n, size_t d, const double *x, size_t j, int lg, double truth,
                       double *lo, double *hi)
{
    *lo = HUGE_VAL;
    *hi = -HUGE_VAL;
    for (size_t i = 0; i < n; i++) {
        double v = x[i * d + j];
        if (isfinite(v) && (!lg || v > 0)) {
            *lo = fmin(*lo, to_axis(v, lg));
            *hi = fmax(*hi, to_axis(v, lg));
        }
    }
    if (isfinite(truth) && (!lg || truth > 0)) {
        *lo = fmin(*lo, to_axis(truth, lg));
        *hi = fmax(*hi, to_axis(truth, lg));
    }
    if (!(*hi > *lo)) {
        double c = isfinite(*lo) ? *lo : 0;
        *lo = c - (lg ? 0.1 : fmax(fabs(c) * 0.05, 1e-12));
        *hi = c + (lg ? 0.1 : fmax(fabs(c) * 0.05, 1e-12));
    }
    {
        double pad = 0.04 * (*hi - *lo);
        *lo -= pad;
        *hi += pad;
    }
}

/* Smoothed 2-D histogram of (x_a, x_b) on GRID x GRID cells of the
 * ranges; the levels enclosing 68 % and 95 % of the samples. */
static void density(size_t n, size_t d, const double *x, size_t a, size_t b, const int *lg,
                    const double *lo, const double *hi, double *g, double *lev68, double *lev95)
{
    double tmp[GRID * GRID], sorted[GRID * GRID], tot = 0, cum = 0;
    memset(g, 0, sizeof tmp);
    for (size_t i = 0; i < n; i++) {
        double u = to_axis(x[i * d + a], lg[a]), v = to_axis(x[i * d + b], lg[b]);
        long p = (long)floor((u - lo[a]) / (hi[a] - lo[a]) * GRID);
        long q = (long)floor((v - lo[b]) / (hi[b] - lo[b]) * GRID);
        if (p >= 0 && p < GRID && q >= 0 && q < GRID)
            g[p * GRID + q] += 1;
    }
    /* Two passes of a 1-2-1 kernel each way: contours without the
     * jitter of single cells. */
    for (int pass = 0; pass < 2; pass++) {
        for (int p = 0; p < GRID; p++)
            for (int q = 0; q < GRID; q++) {
                double s = 2 * g[p * GRID + q], w = 2;
                if (p > 0) s += g[(p - 1) * GRID + q], w += 1;
                if (p + 1 < GRID) s += g[(p + 1) * GRID + q], w += 1;
                tmp[p * GRID + q] = s / w;
            }
        for (int p = 0; p < GRID; p++)
            for (int q = 0; q < GRID; q++) {
                double s = 2 * tmp[p * GRID + q], w = 2;
                if (q > 0) s += tmp[p * GRID + q - 1], w += 1;
                if (q + 1 < GRID) s += tmp[p * GRID + q + 1], w += 1;
                g[p * GRID + q] = s / w;
            }
    }
    memcpy(sorted, g, sizeof sorted);
    qsort(sorted, GRID * GRID, sizeof *sorted, cmp_desc);
    for (int k = 0; k < GRID * GRID; k++)
        tot += sorted[k];
    *lev68 = *lev95 = 0;
    for (int k = 0; k < GRID * GRID && tot > 0; k++) {
        cum += sorted[k];
        if (*lev68 == 0 && cum >= 0.68 * tot)
            *lev68 = sorted[k];
        if (cum >= 0.95 * tot) {
            *lev95 = sorted[k];
            break;
        }
    }
}

/* Parameter j's axis label: the caller's, or "x_{j}". */
static const char *axis_label(const dfle_corner_opts *o, size_t j, char *buf, size_t cap)
{
    if (o->labels != NULL && o->labels[j] != NULL)
        return o->labels[j];
    snprintf(buf, cap, "x_{%zu}", j + 1);
    return buf;
}

/* "set xlabel ..." or "set ylabel ..." with an offset. */
static void put_axis_label(FILE *f, char axis, const char *text, const char *offset)
{
    fprintf(f, "set %clabel ", axis);
    dfle_gp_str(f, text);
    fprintf(f, " offset %s\n", offset);
}

static void put_ticks(FILE *f, char axis, int lg, double lo, double hi, int labels)
{
    if (lg) {
        dfle_gp_log_axis(f, axis, lo, hi, labels);
        return;
    }
    fprintf(f, "unset logscale %c\nset %crange [%.17g:%.17g]\nset format %c '%s'\n"
            "set %ctics autofreq\nset m%ctics 2\n", axis, axis, lo, hi, axis,
            labels ? "%.3g" : "", axis, axis);
}

int dfle_plot_corner(const char *path, const dfle_corner_opts *opts, size_t d, size_t n,
                     const double *x, dfle_error *err)
{
    static const dfle_corner_opts none = {0};
    const dfle_corner_opts *o = opts != NULL ? opts : &none;
    int fmt = dfle_gp_format(path, err), rc, panel, W;
    size_t nb = o->nbins > 0 ? o->nbins : 30, thin;
    double *lo = NULL, *hi = NULL, *g = NULL;
    int *lg = NULL;
    unsigned char *have = NULL; /* d x d: contours traced */
    dfle_gp_run r;
    double left = 0.11, right = 0.975, bottom = 0.125, top, gap = 0.012, w;

    if (fmt < 0)
        return fmt;
    if (d < 1 || d > 12)
        return dfle_error_set(err, DFLE_EINVAL, "plot: a corner plot takes 1 to 12 parameters "
                              "(got %zu)", d);
    if (n < 2 || x == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "plot: a corner plot needs at least 2 samples "
                              "(got %zu)", n);
    panel = o->panel > 0 ? o->panel : 250;
    W = (int)(panel * (int)d / (right - left)) + 20;
    if (W < 600)
        W = 600;
    if (W > 6000)
        W = 6000;
    lo = malloc(d * sizeof *lo);
    hi = malloc(d * sizeof *hi);
    lg = calloc(d, sizeof *lg);
    have = calloc(d * d, 1);
    g = malloc(GRID * GRID * sizeof *g);
    if (lo == NULL || hi == NULL || lg == NULL || have == NULL || g == NULL) {
        rc = dfle_error_set(err, DFLE_ENOMEM, "plot: out of memory");
        goto done;
    }
    for (size_t j = 0; j < d; j++) {
        lg[j] = o->logaxis != NULL && o->logaxis[j];
        axis_range(n, d, x, j, lg[j], o->truth != NULL ? o->truth[j] : NAN, &lo[j], &hi[j]);
    }
    if ((rc = dfle_gp_begin(&r, path, fmt, W, W, err)) < 0)
        goto done;
    top = o->title != NULL ? 0.93 : 0.965;
    w = (fmin(right - left, top - bottom) - gap * (double)(d - 1)) / (double)d;

    /* The samples, thinned evenly for the scatter. */
    thin = n > MAX_SCATTER ? (n + MAX_SCATTER - 1) / MAX_SCATTER : 1;
    fputs("$s << EOD\n", r.f);
    for (size_t i = 0; i < n; i += thin) {
        for (size_t j = 0; j < d; j++)
            fprintf(r.f, "%s%.10g", j ? " " : "", x[i * d + j]);
        fputs("\n", r.f);
    }
    fputs("EOD\n", r.f);
    /* Histograms as step outlines (edges repeated), normalised to 1. */
    for (size_t j = 0; j < d; j++) {
        double *cnt = calloc(nb, sizeof *cnt), mx = 0, bw = (hi[j] - lo[j]) / (double)nb;
        if (cnt == NULL) {
            rc = dfle_error_set(err, DFLE_ENOMEM, "plot: out of memory");
            dfle_gp_end(&r, NULL);
            goto done;
        }
        for (size_t i = 0; i < n; i++) {
            double u = to_axis(x[i * d + j], lg[j]);
            long k = (long)floor((u - lo[j]) / bw);
            if (k >= 0 && k < (long)nb)
                cnt[k] += 1;
        }
        for (size_t k = 0; k < nb; k++)
            mx = fmax(mx, cnt[k]);
        fprintf(r.f, "$h%zu << EOD\n", j);
        for (size_t k = 0; k < nb; k++) {
            double c = mx > 0 ? cnt[k] / mx : 0;
            fprintf(r.f, "%.10g %.6g\n%.10g %.6g\n", from_axis(lo[j] + bw * (double)k, lg[j]), c,
                    from_axis(lo[j] + bw * (double)(k + 1), lg[j]), c);
        }
        fputs("EOD\n", r.f);
        free(cnt);
    }
    /* Contours, traced before the multiplot starts. */
    fputs("set contour base\nunset surface\nset view map\nunset logscale\n", r.f);
    for (size_t a = 0; a < d; a++)
        for (size_t b = a + 1; b < d; b++) {
            double l68, l95;
            density(n, d, x, a, b, lg, lo, hi, g, &l68, &l95);
            if (!(l95 > 0 && l68 > l95))
                continue;
            fprintf(r.f, "$g%zu_%zu << EOD\n", a, b);
            for (int p = 0; p < GRID; p++) {
                for (int q = 0; q < GRID; q++)
                    fprintf(r.f, "%.10g %.10g %.6g\n",
                            lo[a] + (hi[a] - lo[a]) * (p + 0.5) / GRID,
                            lo[b] + (hi[b] - lo[b]) * (q + 0.5) / GRID, g[p * GRID + q]);
                fputs("\n", r.f);
            }
            fputs("EOD\n", r.f);
            fprintf(r.f, "set cntrparam levels discrete %.10g, %.10g\nset table $c%zu_%zu\n"
                    "splot $g%zu_%zu using 1:2:3 with lines\nunset table\n", l95, l68, a, b, a, b);
            have[a * d + b] = 1;
        }
    fputs("unset contour\nset surface\nunset view\n", r.f);

    fputs("set multiplot\nunset key\nset tics scale 0.8,0.4 front\nset tics font ',9'\n", r.f);
    if (o->title != NULL) {
        fputs("set label 100 ", r.f);
        dfle_gp_str(r.f, o->title);
        fprintf(r.f, " at screen 0.5, screen %.4f center font ',14'\n", top + (1 - top) / 2 + 0.005);
    }
    for (size_t i = 0; i < d; i++)         /* row, top to bottom */
        for (size_t j = 0; j <= i; j++) {  /* column */
            double L0 = left + (double)j * (w + gap), T0 = top - (double)i * (w + gap);
            char bj[32], bi[32];
            const char *lab_j = axis_label(o, j, bj, sizeof bj);
            const char *lab_i = axis_label(o, i, bi, sizeof bi);
            fprintf(r.f, "set lmargin at screen %.5f\nset rmargin at screen %.5f\n"
                    "set tmargin at screen %.5f\nset bmargin at screen %.5f\n", L0, L0 + w, T0,
                    T0 - w);
            fputs("unset arrow\nunset label 1\nunset xlabel\nunset ylabel\nunset title\n", r.f);
            fprintf(r.f, "set grid xtics ytics back lc rgb '#e4e4e4' lw 0.6\n");
            put_ticks(r.f, 'x', lg[j], lo[j], hi[j], i == d - 1);
            /* slanted: neighbouring panels' end labels would touch */
            fputs("set xtics rotate by 35 right offset 0.4,0.2\n", r.f);
            if (i == d - 1)
                put_axis_label(r.f, 'x', lab_j, "0,-0.2");
            if (i == j) {
                dfle_summary s;
                char txt[200], head[320];
                dfle_summarize(x + j, n, d, &s, NULL);
                fputs("unset logscale y\nset yrange [0:1.12]\nunset ytics\nunset mytics\n", r.f);
                fmt_interval(txt, sizeof txt, s.median, s.lo68, s.hi68);
                snprintf(head, sizeof head, "%s = %s", lab_j, txt);
                fputs("set label 1 ", r.f);
                dfle_gp_str(r.f, head);
                fputs(" at graph 0.5, graph 1.1 center font ',10'\n", r.f);
                fprintf(r.f, "set arrow 1 from %.10g, graph 0 to %.10g, graph 1 nohead lc rgb "
                        "'#1f3b73' lw 1.6 front\n", s.median, s.median);
                fprintf(r.f, "set arrow 2 from %.10g, graph 0 to %.10g, graph 1 nohead lc rgb "
                        "'#1f3b73' lw 1.1 dt 2 front\n", s.lo68, s.lo68);
                fprintf(r.f, "set arrow 3 from %.10g, graph 0 to %.10g, graph 1 nohead lc rgb "
                        "'#1f3b73' lw 1.1 dt 2 front\n", s.hi68, s.hi68);
                if (o->truth != NULL && isfinite(o->truth[j]))
                    fprintf(r.f, "set arrow 4 from %.10g, graph 0 to %.10g, graph 1 nohead lc "
                            "rgb '#d01c1c' lw 1.8 front\n", o->truth[j], o->truth[j]);
                fprintf(r.f, "plot $h%zu using 1:2 with filledcurves y1=0 fs transparent solid "
                        "0.35 noborder lc rgb '#0072B2', $h%zu using 1:2 with lines lw 1.4 lc rgb "
                        "'#0a4a78'\n", j, j);
            } else {
                put_ticks(r.f, 'y', lg[i], lo[i], hi[i], j == 0);
                if (j == 0)
                    put_axis_label(r.f, 'y', lab_i, "0.6,0");
                if (o->truth != NULL && isfinite(o->truth[j]))
                    fprintf(r.f, "set arrow 4 from %.10g, graph 0 to %.10g, graph 1 nohead lc "
                            "rgb '#d01c1c' lw 1.4 front\n", o->truth[j], o->truth[j]);
                if (o->truth != NULL && isfinite(o->truth[i]))
                    fprintf(r.f, "set arrow 5 from graph 0, first %.10g to graph 1, first %.10g "
                            "nohead lc rgb '#d01c1c' lw 1.4 front\n", o->truth[i], o->truth[i]);
                fprintf(r.f, "plot $s using %zu:%zu with points pt 7 ps 0.22 lc rgb '#A00072B2'",
                        j + 1, i + 1);
                /* contours of (x_j, x_i): the grid was (a = j, b = i) */
                if (have[j * d + i])
                    fprintf(r.f, ", $c%zu_%zu using (%s):(%s) with lines lw 1.5 lc rgb "
                            "'#0a2a4a'", j, i, lg[j] ? "10**$1" : "$1", lg[i] ? "10**$2" : "$2");
                fputs("\n", r.f);
            }
        }
    fputs("unset multiplot\n", r.f);
    rc = dfle_gp_end(&r, err);
done:
    free(lo);
    free(hi);
    free(lg);
    free(have);
    free(g);
    return rc;
}
