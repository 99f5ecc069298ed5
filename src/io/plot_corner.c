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
 * diagonal gets the numbers.  A prior bound that holds the posterior is
 * drawn where it cuts the samples, with the side outside the prior
 * shaded: the edge of the marginal there is the prior's, not the data's.
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
 * large or small (by 10^e_axis when the axis is labelled with that
 * factor, so that the two agree), as enhanced text.  The scripts are set
 * at 0.8 of the font: at full size gnuplot stacks them into each other
 * and into the "×10" after them. */
static void fmt_interval(char *buf, size_t cap, double med, double lo, double hi, int factored,
                         int e_axis)
{
    double ref = fabs(med) > 0 ? fabs(med) : fmax(fabs(lo), fabs(hi));
    int e = ref > 0 ? (int)floor(log10(ref)) : 0, dec;
    double s, up, dn, small;
    if (e >= -2 && e <= 3)
        e = 0;
    if (factored)
        e = e_axis;
    s = pow(10.0, -e);
    up = (hi - med) * s;
    dn = (med - lo) * s;
    small = fmin(up, dn);
    dec = small > 0 ? 1 - (int)floor(log10(small)) : 2;
    if (dec < 0)
        dec = 0;
    if (dec > 5)
        dec = 5;
    {
        /* @ stacks the scripts, and what follows starts after the
         * second: the wider goes second, so nothing runs into it */
        char us[32], ds[32];
        snprintf(us, sizeof us, "+%.*f", dec, up);
        snprintf(ds, sizeof ds, "−%.*f", dec, dn);
        if (strlen(us) + 2 > strlen(ds)) /* "−" is 3 bytes, one glyph */
            snprintf(buf, cap, "%.*f@_{/*0.8 %s}^{/*0.8 %s}", dec, med * s, ds, us);
        else
            snprintf(buf, cap, "%.*f@^{/*0.8 %s}_{/*0.8 %s}", dec, med * s, us, ds);
        if (e != 0)
            snprintf(buf + strlen(buf), cap - strlen(buf), " ×10^{%d}", e);
    }
}

/* A label "symbol (unit)" split in two (unit "" when it has none). */
static void split_label(const char *label, char *sym, size_t scap, char *unit, size_t ucap)
{
    const char *open = strrchr(label, '(');
    size_t len = strlen(label);
    if (open != NULL && open > label && open[-1] == ' ' && len > 0 && label[len - 1] == ')') {
        snprintf(sym, scap, "%.*s", (int)(open - label - 1), label);
        snprintf(unit, ucap, "%.*s", (int)(label + len - 1 - open - 1), open + 1);
    } else {
        snprintf(sym, scap, "%s", label);
        unit[0] = '\0';
    }
}

/* An axis label too wide for its panel (w pt at font fs), broken before
 * its unit into two lines: buf holds "k_{df}", then "(×10^{-4} s^{-1}
 * yr^{-1})" after its NUL.  Returns the lines. */
static int wrap_label(const char *label, double w, double fs, char *buf, size_t cap)
{
    const char *open = strrchr(label, '(');
    snprintf(buf, cap, "%s", label);
    if (dfle_gp_text_em(label) * fs <= w || open == NULL || open == label || open[-1] != ' ' ||
        strlen(label) + 2 > cap)
        return 1;
    buf[open - label - 1] = '\0';
    return 2;
}

/* An axis label of one or two lines (wrap_label's buf): the first at
 * (x, y), the second 1.6 font sizes further from the label's start
 * (below it; right of it when rotated). */
static void put_axis_label(FILE *f, int tag, const char *buf, int lines, double x, double y,
                           double rot, const dfle_gp_frame *fr)
{
    dfle_gp_page_label(f, tag, buf, x, y, rot, 0, fr);
    if (lines > 1)
        dfle_gp_page_label(f, tag + 10, buf + strlen(buf) + 1, x + (rot != 0 ? 1.6 * fr->font_pt : 0),
                           y - (rot != 0 ? 0 : 1.6 * fr->font_pt), rot, 0, fr);
}

#define BOUND_RGB "#4d4d4d"
#define OUTSIDE_RGB "#d4d4d4"

/* Bound b of parameter j (bound_lo or bound_hi) is drawn. */
static int bound_shown(const double *b, size_t j, int lg)
{
    return b != NULL && isfinite(b[j]) && (!lg || b[j] > 0);
}

/* The axis range of parameter j in axis units, padded 4 %, holding the
 * bounds blo, bhi drawn (NaN: none). */
static void axis_range(size_t n, size_t d, const double *x, size_t j, int lg, double truth,
                       double blo, double bhi, double *lo, double *hi)
{
    *lo = HUGE_VAL;
    *hi = -HUGE_VAL;
    if (isfinite(blo) && (!lg || blo > 0))
        *lo = *hi = to_axis(blo, lg);
    if (isfinite(bhi) && (!lg || bhi > 0)) {
        *lo = fmin(*lo, to_axis(bhi, lg));
        *hi = fmax(*hi, to_axis(bhi, lg));
    }
    for (size_t i = 0; i < n; i++) {
        double v = x[i * d + j];
        if (isfinite(v) && (!lg || v > 0)) {
            *lo = fmin(*lo, to_axis(v, lg));
            *hi = fmax(*hi, to_axis(v, lg));
        }
    }
    if (isfinite(truth) && (!lg || truth > 0)) {
        double t = to_axis(truth, lg);
        *lo = fmin(*lo, t);
        *hi = fmax(*hi, t);
    }
    if (!(*hi > *lo)) {
        double c = isfinite(*lo) ? *lo : 0;
        *lo = c - (lg ? 0.1 : fmax(fabs(c) * 0.05, 1e-12));
        *hi = c + (lg ? 0.1 : fmax(fabs(c) * 0.05, 1e-12));
    }
    {
        double span = *hi - *lo;
        *lo -= 0.04 * span;
        *hi += 0.04 * span;
    }
    /* A bound keeps an eighth of the axis outside it, where its note
     * goes (and which is shaded: outside the prior). */
    if (isfinite(bhi) && (!lg || bhi > 0) && *hi - to_axis(bhi, lg) < 0.125 * (*hi - *lo))
        *hi = (to_axis(bhi, lg) - 0.125 * *lo) / (1 - 0.125);
    if (isfinite(blo) && (!lg || blo > 0) && to_axis(blo, lg) - *lo < 0.125 * (*hi - *lo))
        *lo = (to_axis(blo, lg) - 0.125 * *hi) / (1 - 0.125);
    /* A truth near an end of the samples stands a tenth of the axis
     * clear of the frame, so that its line is not read as the frame (or
     * as drawn clamped to it). */
    if (isfinite(truth) && (!lg || truth > 0)) {
        const double room = 0.1;
        double t = to_axis(truth, lg);
        if (*hi - t < room * (*hi - *lo))
            *hi = (t - room * *lo) / (1 - room);
        if (t - *lo < room * (*hi - *lo))
            *lo = (t - room * *hi) / (1 - room);
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

/* Parameter j has a truth its axis can show. */
static int truth_shown(const dfle_corner_opts *o, size_t j, const int *lg)
{
    return o->truth != NULL && isfinite(o->truth[j]) && (!lg[j] || o->truth[j] > 0);
}

/* Parameter j's prior bounds on the x axis (tags 6, 7) or the y axis
 * (8, 9) of a panel: a line, the side outside the prior shaded behind
 * the samples, and on the diagonal (note) the words "prior bound". */
static void put_bounds(FILE *f, const dfle_corner_opts *o, size_t j, const int *lg, int y,
                       int note, double o_font_pt)
{
    for (int side = 0; side < 2; side++) {
        const double *b = side == 0 ? o->bound_lo : o->bound_hi;
        const int tag = (y ? 8 : 6) + side;
        const char *edge = side == 0 ? "graph 0" : "graph 1";
        if (!bound_shown(b, j, lg[j]))
            continue;
        if (y) {
            fprintf(f, "set object %d rect from graph 0, %s to graph 1, first %.10g fc rgb '%s' "
                    "fs solid 0.7 noborder behind\n", tag, edge, b[j], OUTSIDE_RGB);
            fprintf(f, "set arrow %d from graph 0, first %.10g to graph 1, first %.10g nohead "
                    "lc rgb '%s' lw 2 dt 2 front\n", tag, b[j], b[j], BOUND_RGB);
        } else {
            fprintf(f, "set object %d rect from %s, graph 0 to first %.10g, graph 1 fc rgb '%s' "
                    "fs solid 0.7 noborder behind\n", tag, edge, b[j], OUTSIDE_RGB);
            fprintf(f, "set arrow %d from first %.10g, graph 0 to first %.10g, graph 1 nohead "
                    "lc rgb '%s' lw 2 dt 2 front\n", tag, b[j], b[j], BOUND_RGB);
        }
        if (note) /* upright beside the line, on the side outside the prior */
            fprintf(f, "set label %d \"prior bound\" at first %.10g, graph 0.06 rotate by 90 "
                    "left offset character %.1f, 0 tc rgb '%s' font ',%.3g' front\n", tag, b[j],
                    side == 0 ? -0.9 : 1.1, BOUND_RGB, 0.8 * o_font_pt);
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

int dfle_plot_corner(const char *path, const dfle_plot_opts *opts,
                     const dfle_corner_opts *corner, size_t d, size_t n, const double *x,
                     dfle_error *err)
{
    static const dfle_corner_opts none = {0};
    const dfle_corner_opts *o = corner != NULL ? corner : &none;
    const char *title = opts != NULL ? opts->title : NULL;
    size_t nb = o->nbins > 0 ? o->nbins : 30, thin;
    double *lo = NULL, *hi = NULL, *g = NULL;
    int *lg = NULL, rc;
    unsigned char *have = NULL; /* d x d: contours traced */
    dfle_gp_axis *tx = NULL, *ty = NULL; /* each parameter's ticks as x and as y */
    dfle_gp_frame fr;
    dfle_gp_run r;
    double fs, left, right, bottom, top, gap, w, yem = 0;
    int wrap_x = 0, wrap_y = 0;

    if (d < 1 || d > 12)
        return dfle_error_set(err, DFLE_EINVAL, "plot: a corner plot takes 1 to 12 parameters "
                              "(got %zu)", d);
    /* 4 cm a panel, and room for the labels */
    if ((rc = dfle_gp_frame_of(path, opts, 4.0 * (double)d + 2.8, 4.0 * (double)d + 2.8, &fr,
                               err)) < 0)
        return rc;
    if (n < 2 || x == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "plot: a corner plot needs at least 2 samples "
                              "(got %zu)", n);
    fs = fr.font_pt;
    lo = malloc(d * sizeof *lo);
    hi = malloc(d * sizeof *hi);
    lg = calloc(d, sizeof *lg);
    have = calloc(d * d, 1);
    g = malloc(GRID * GRID * sizeof *g);
    tx = calloc(d, sizeof *tx);
    ty = calloc(d, sizeof *ty);
    if (lo == NULL || hi == NULL || lg == NULL || have == NULL || g == NULL || tx == NULL ||
        ty == NULL) {
        rc = dfle_error_set(err, DFLE_ENOMEM, "plot: out of memory");
        goto done;
    }
    for (size_t j = 0; j < d; j++) {
        lg[j] = o->logaxis != NULL && o->logaxis[j];
        axis_range(n, d, x, j, lg[j], o->truth != NULL ? o->truth[j] : NAN,
                   o->bound_lo != NULL ? o->bound_lo[j] : NAN,
                   o->bound_hi != NULL ? o->bound_hi[j] : NAN, &lo[j], &hi[j]);
    }
    /* The panels' size sets the ticks, whose labels set the margins. */
    gap = 1.2 * fs; /* room for the end labels of neighbouring panels */
    bottom = (1.25 + 1.3 + 0.45 + 1.2) * fs;
    top = fr.h_pt - (title != NULL ? 2.4 * fs : 0.6 * fs) - 1.6 * fs; /* the top header */
    w = (fmin(fr.w_pt - 6 * fs, top - bottom) - gap * (double)(d - 1)) / (double)d;
    for (size_t j = 0; j < d; j++) {
        dfle_gp_axis_range(&tx[j], lg[j], from_axis(lo[j], lg[j]), from_axis(hi[j], lg[j]), 0,
                           NULL);
        tx[j].end_room = gap / 2; /* panels side by side: labels keep to their own */
        tx[j].factor_ok = 1;      /* ...and short: 3, 4, 5 with ×10^{-14} in the label */
        ty[j] = tx[j];
        dfle_gp_axis_ticks(&tx[j], w, fs, 0, NULL);
        dfle_gp_axis_ticks(&ty[j], w, fs, 1, NULL);
        if (j > 0)
            yem = fmax(yem, ty[j].max_em);
    }
    left = (0.5 + 1.5 + 0.7 + 0.3) * fs + yem * fs;
    right = fr.w_pt - 1.5 * fs;
    w = (fmin(right - left, top - bottom) - gap * (double)(d - 1)) / (double)d;
    /* axis labels too wide for a panel take two lines, and room for them */
    for (size_t j = 0; j < d; j++) {
        char bj[32], fx[320], wr[320];
        const char *lab = axis_label(o, j, bj, sizeof bj);
        wrap_x |= wrap_label(dfle_gp_axis_label(&tx[j], lab, fx, sizeof fx), w + 0.8 * gap, fs,
                             wr, sizeof wr) > 1;
        if (j > 0)
            wrap_y |= wrap_label(dfle_gp_axis_label(&ty[j], lab, fx, sizeof fx), w + 0.8 * gap,
                                 fs, wr, sizeof wr) > 1;
    }
    if (wrap_x || wrap_y) {
        bottom += wrap_x ? 1.6 * fs : 0;
        left += wrap_y ? 1.6 * fs : 0;
        w = (fmin(right - left, top - bottom) - gap * (double)(d - 1)) / (double)d;
    }

    if (!(w > 3 * fs)) {
        rc = dfle_error_set(err, DFLE_EINVAL, "plot: the page (%.3g x %.3g cm) is too small for "
                            "%zu panels at a %g pt font", fr.w_pt / 72 * 2.54,
                            fr.h_pt / 72 * 2.54, d, fs);
        goto done;
    }
    if ((rc = dfle_gp_begin_frame(&r, path, &fr, err)) < 0)
        goto done;

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

    fputs("set multiplot\nunset key\n", r.f);
    for (size_t i = 0; i < d; i++)         /* row, top to bottom */
        for (size_t j = 0; j <= i; j++) {  /* column */
            double L0 = left + (double)j * (w + gap), T0 = top - (double)i * (w + gap);
            char bj[32], bi[32], fx[320];
            const char *lab_j = axis_label(o, j, bj, sizeof bj);
            const char *lab_i = axis_label(o, i, bi, sizeof bi);
            fprintf(r.f, "set lmargin at screen %.5f\nset rmargin at screen %.5f\n"
                    "set tmargin at screen %.5f\nset bmargin at screen %.5f\n",
                    L0 / fr.w_pt, (L0 + w) / fr.w_pt, T0 / fr.h_pt, (T0 - w) / fr.h_pt);
            fputs("unset arrow\nunset label\nunset title\nunset object\n", r.f);
            fprintf(r.f, "set grid xtics ytics back lc rgb '#e4e4e4' lw 1\n");
            dfle_gp_axis_put(r.f, "x", &tx[j], i == d - 1);
            if (i == 0 && j == 0 && title != NULL)
                dfle_gp_page_label(r.f, 100, title, fr.w_pt / 2, fr.h_pt - 1.25 * fs, 0, 0, &fr);
            if (i == d - 1) {
                char wr[320];
                int lines = wrap_label(dfle_gp_axis_label(&tx[j], lab_j, fx, sizeof fx),
                                       w + 0.8 * gap, fs, wr, sizeof wr);
                put_axis_label(r.f, 101, wr, lines, L0 + w / 2, (lines > 1 ? 2.55 : 0.95) * fs,
                               0, &fr);
            }
            if (i == j) {
                dfle_summary s;
                char txt[200], head[600];
                dfle_summarize(x + j, n, d, &s, NULL);
                fputs("unset logscale y\nset yrange [0:1.12]\nunset ytics\n", r.f);
                char sym[160], unit[160];
                split_label(lab_j, sym, sizeof sym, unit, sizeof unit);
                fmt_interval(txt, sizeof txt, s.median, s.lo68, s.hi68, tx[j].factored,
                             tx[j].factor_exp);
                /* "k_df = 1.1^{+0.4}_{-0.2} ×10^{-4} s^{-1} yr^{-1}", the unit
                 * left out where the header would run off the page */
                snprintf(head, sizeof head, "%s = %s%s%s", sym, txt, unit[0] ? " " : "", unit);
                if (j == d - 1 && dfle_gp_text_em(head) * fs > w + 2.4 * fs)
                    snprintf(head, sizeof head, "%s = %s", sym, txt);
                /* centred where it keeps within the panel (the width
                 * estimate can be a tenth short), else from its left edge */
                if (j == d - 1 || 1.1 * dfle_gp_text_em(head) * fs <= w) {
                    dfle_gp_page_label(r.f, 1, head, L0 + w / 2, T0 + 0.9 * fs, 0, 0, &fr);
                } else { /* from the panel's left edge over the empty upper triangle */
                    fputs("set label 1 ", r.f);
                    dfle_gp_str(r.f, head);
                    fprintf(r.f, " at screen %.5f, screen %.5f left front\n", L0 / fr.w_pt,
                            (T0 + 0.9 * fs) / fr.h_pt);
                }
                fprintf(r.f, "set arrow 1 from %.10g, graph 0 to %.10g, graph 1 nohead lc rgb "
                        "'#1f3b73' lw 3 front\n", s.median, s.median);
                fprintf(r.f, "set arrow 2 from %.10g, graph 0 to %.10g, graph 1 nohead lc rgb "
                        "'#1f3b73' lw 2 dt 2 front\n", s.lo68, s.lo68);
                fprintf(r.f, "set arrow 3 from %.10g, graph 0 to %.10g, graph 1 nohead lc rgb "
                        "'#1f3b73' lw 2 dt 2 front\n", s.hi68, s.hi68);
                if (truth_shown(o, j, lg))
                    fprintf(r.f, "set arrow 4 from %.10g, graph 0 to %.10g, graph 1 nohead lc "
                            "rgb '%s' lw 3 front\n", o->truth[j], o->truth[j], DFLE_GP_FIT);
                put_bounds(r.f, o, j, lg, 0, 1, fs);
                fprintf(r.f, "plot $h%zu using 1:2 with filledcurves y1=0 fs transparent solid "
                        "0.35 noborder lc rgb '#0072B2', $h%zu using 1:2 with lines lw 2.4 lc rgb "
                        "'#0a4a78'\n", j, j);
            } else {
                dfle_gp_axis_put(r.f, "y", &ty[i], j == 0);
                if (j == 0) {
                    char wr[320];
                    int lines = wrap_label(dfle_gp_axis_label(&ty[i], lab_i, fx, sizeof fx),
                                           w + 0.8 * gap, fs, wr, sizeof wr);
                    put_axis_label(r.f, 102, wr, lines, 1.1 * fs, T0 - w / 2, 90, &fr);
                }
                if (truth_shown(o, j, lg))
                    fprintf(r.f, "set arrow 4 from %.10g, graph 0 to %.10g, graph 1 nohead lc "
                            "rgb '%s' lw 2.5 front\n", o->truth[j], o->truth[j], DFLE_GP_FIT);
                if (truth_shown(o, i, lg))
                    fprintf(r.f, "set arrow 5 from graph 0, first %.10g to graph 1, first %.10g "
                            "nohead lc rgb '%s' lw 2.5 front\n", o->truth[i], o->truth[i],
                            DFLE_GP_FIT);
                put_bounds(r.f, o, j, lg, 0, 0, fs);
                put_bounds(r.f, o, i, lg, 1, 0, fs);
                fprintf(r.f, "plot $s using %zu:%zu with points pt 7 ps %.3g lc rgb '#A00072B2'",
                        j + 1, i + 1, dfle_gp_ps(&fr, 1.4));
                /* contours of (x_j, x_i): the grid was (a = j, b = i) */
                if (have[j * d + i])
                    fprintf(r.f, ", $c%zu_%zu using (%s):(%s) with lines lw 2.6 lc rgb "
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
    free(tx);
    free(ty);
    return rc;
}
