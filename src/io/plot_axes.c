/*
 * plot_axes.c - ranges and ticks of an axis, chosen here rather than by
 * gnuplot.
 *
 * gnuplot picks ticks from the range alone: labels of small numbers run
 * together ("0.0000010.000002"), a log axis over two or three decades
 * gets two or three labels, and the range is widened to the next tick
 * (a 2010 m channel on an axis to 2500 m).  Here the range is the data's
 * (padded a little, or the caller's), and the ticks are the most, from 1,
 * 2 and 5 times powers of ten, whose labels keep a gap between them at
 * the axis's length and font size: that needs the label widths, so the
 * labels are made here too ("2×10^{-6}", "0.05", "10^{4}"), and written
 * as an explicit tick list.
 */
#include "io/plot_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Widths in em of DejaVu/Helvetica-like glyphs, near enough for spacing
 * decisions: digits and most letters 0.62, sub- and superscripts 0.8 of
 * that. */
double dfle_gp_text_em(const char *s)
{
    double em = 0, scale[16] = {1};
    int depth = 0, script_next = 0;
    for (const unsigned char *p = (const unsigned char *)s; p != NULL && *p != '\0'; p++) {
        if (*p == '{') {
            double sc = scale[depth] * (script_next ? 0.8 : 1.0);
            script_next = 0;
            if (depth < 15)
                scale[++depth] = sc;
            if (p[1] == '/') /* a font change "{/:Italic x}": not shown */
                while (p[1] != '\0' && p[1] != ' ' && p[1] != '}')
                    p++;
            if (p[1] == ' ')
                p++;
        } else if (*p == '}') {
            if (depth > 0)
                depth--;
        } else if (*p == '^' || *p == '_') {
            script_next = 1;
        } else if (*p == '@' || *p == '&' || *p == '\\' || (*p & 0xC0) == 0x80) {
            continue; /* markup, or a UTF-8 continuation byte */
        } else {
            em += 0.62 * scale[depth] * (script_next ? 0.8 : 1.0);
            script_next = 0;
        }
    }
    return em;
}

void dfle_plot_number(char *buf, size_t cap, double v)
{
    double a = fabs(v);
    if (!isfinite(v)) { /* "%.2e" of these has no exponent to split off */
        snprintf(buf, cap, "%s", isnan(v) ? "NaN" : v > 0 ? "inf" : "-inf");
        return;
    }
    if (a == 0 || (a >= 1e-3 && a < 1e4)) {
        snprintf(buf, cap, "%.3g", v);
        return;
    }
    char m[16];
    snprintf(m, sizeof m, "%.2e", v); /* rounds the mantissa for us */
    char *ep = strchr(m, 'e');
    int ex = (int)strtol(ep + 1, NULL, 10);
    *ep = '\0';
    while (ep > m && (ep[-1] == '0' || ep[-1] == '.')) *--ep = '\0';
    snprintf(buf, cap, "%s×10^{%d}", m, ex);
}

static double to_ax(double v, int log) { return log ? log10(v) : v; }
static double from_ax(double u, int log) { return log ? pow(10.0, u) : u; }

void dfle_gp_axis_range(dfle_gp_axis *a, int log, double dlo, double dhi, double pad,
                        const dfle_plot_axis *user)
{
    double ulo, uhi, span;
    memset(a, 0, sizeof *a);
    a->log = log;
    if (!(dlo <= dhi) || (log && !(dlo > 0))) { /* no data */
        ulo = 0, uhi = 1;
    } else {
        ulo = to_ax(dlo, log), uhi = to_ax(dhi, log);
        if (uhi - ulo <= 1e-12 * fmax(1, fabs(ulo))) { /* one value */
            double w = log ? 0.3 : fmax(fabs(ulo) * 0.1, 1e-300);
            if (!log && ulo == 0)
                w = 1;
            ulo -= w, uhi += w;
        } else {
            span = uhi - ulo;
            ulo -= pad * span, uhi += pad * span;
        }
    }
    span = uhi - ulo;
    if (user != NULL && user->has_lo)
        ulo = to_ax(user->lo, log);
    if (user != NULL && user->has_hi)
        uhi = to_ax(user->hi, log);
    if (!(ulo < uhi)) { /* one end given beyond the data: keep the span */
        if (user != NULL && user->has_lo)
            uhi = ulo + span;
        else
            ulo = uhi - span;
    }
    a->lo = from_ax(ulo, log);
    a->hi = from_ax(uhi, log);
    /* the ends the caller gave, exactly (not through log10 and back) */
    if (user != NULL && user->has_lo)
        a->lo = user->lo;
    if (user != NULL && user->has_hi)
        a->hi = user->hi;
}

/* A label of v in linear steps of `step`: fixed decimals for ordinary
 * magnitudes, "m×10^{e}" for tiny or huge ones.  Down to 0.001 decimals
 * read better ("0.003", not "3×10^{-3}"; slopes and rates in m/yr often
 * sit there); below it a run of zeros does not. */
static void label_linear(char *buf, size_t cap, double v, double step, double amax)
{
    int pstep = (int)floor(log10(step) + 1e-9);
    if (fabs(v) < step * 1e-6)
        v = 0;
    if (v == 0) {
        snprintf(buf, cap, "0");
    } else if (amax >= 1e5 || amax < 1e-3) {
        int e = (int)floor(log10(fabs(v)) + 1e-9), d = e - pstep;
        double m = v / pow(10.0, e);
        /* a mantissa of 2.5 needs one decimal more than its step */
        if (fabs(step / pow(10.0, pstep) - 2.5) < 1e-6)
            d++;
        char mant[24], *dot;
        snprintf(mant, sizeof mant, "%.*f", d > 0 ? d : 0, m);
        /* 1.0×10^{-5} among 2×10^{-6}, 4×10^{-6}: the zeros say nothing */
        if ((dot = strchr(mant, '.')) != NULL) {
            char *z = mant + strlen(mant);
            while (z > dot + 1 && z[-1] == '0')
                *--z = '\0';
            if (z == dot + 1)
                *dot = '\0';
        }
        snprintf(buf, cap, "%s×10^{%d}", mant, e);
    } else {
        int d = -pstep;
        if (fabs(step / pow(10.0, pstep) - 2.5) < 1e-6)
            d++;
        snprintf(buf, cap, "%.*f", d > 0 ? d : 0, v);
    }
}

/* The label of a tick on a log axis: plain numbers when every label is
 * between 0.001 and 10^4 ("0.05", "200"), powers of ten otherwise. */
static void label_log(char *buf, size_t cap, double v, int plain)
{
    int e = (int)floor(log10(v) + 1e-9);
    double m = v / pow(10.0, e);
    if (plain)
        snprintf(buf, cap, "%.10g", v);
    else if (fabs(m - 1) < 1e-9)
        snprintf(buf, cap, "10^{%d}", e);
    else
        snprintf(buf, cap, "%.10g×10^{%d}", m, e);
}

/* Room a tick label needs along the axis [pt]. */
static double label_need(const dfle_gp_axis *a, double font_pt, int vertical)
{
    return vertical ? 2.0 * font_pt : (a->max_em + 1.3) * font_pt;
}

/* The narrowest gap between neighbouring ticks [pt]. */
static double min_gap(const dfle_gp_axis *a, double len_pt)
{
    double g = HUGE_VAL, span = to_ax(a->hi, a->log) - to_ax(a->lo, a->log);
    for (size_t i = 1; i < a->n; i++)
        g = fmin(g, (to_ax(a->v[i], a->log) - to_ax(a->v[i - 1], a->log)) / span * len_pt);
    return g;
}

static void widest(dfle_gp_axis *a)
{
    a->max_em = 0;
    for (size_t i = 0; i < a->n; i++)
        a->max_em = fmax(a->max_em, dfle_gp_text_em(a->lab[i]));
}

/* Where the axis allows it (a->factor_ok), ticks of tiny or huge values
 * are labelled by mantissas (3, 4, 5) with one factor 10^e for the axis
 * label, rather than each as "3×10^{-14}": short labels fit narrow
 * panels.  `step` is the spacing to resolve (in data units); returns 1
 * if the labels were written so. */
static int label_factored(dfle_gp_axis *a, double step)
{
    double amax = 0;
    int e, d;
    for (size_t i = 0; i < a->n; i++)
        amax = fmax(amax, fabs(a->v[i]));
    a->factored = 0;
    if (!a->factor_ok || a->n == 0 || !(amax >= 1e5 || amax < 1e-3))
        return 0;
    /* the factor of the spacing, unless the labels would get long */
    e = (int)floor(log10(step) + 1e-9);
    if (amax / pow(10.0, e) >= 1000)
        e = (int)floor(log10(amax) + 1e-9) - 2;
    d = (int)floor(log10(step) + 1e-9) - e;
    d = d < 0 ? -d : 0;
    if (fabs(step / pow(10.0, floor(log10(step) + 1e-9)) - 2.5) < 1e-6)
        d++;
    for (size_t i = 0; i < a->n; i++)
        snprintf(a->lab[i], DFLE_GP_TICKLAB, "%.*f", d, a->v[i] / pow(10.0, e));
    a->factored = 1;
    a->factor_exp = e;
    return 1;
}

/* Ticks at multiples of step within the range; 0 if too many. */
static size_t linear_ticks(dfle_gp_axis *a, double step)
{
    double amax = fmax(fabs(a->lo), fabs(a->hi));
    double first = ceil(a->lo / step - 1e-9);
    a->n = 0;
    for (double k = first; k * step <= a->hi + 1e-9 * step; k++) {
        if (a->n == DFLE_GP_MAXTICKS)
            return a->n = 0;
        a->v[a->n] = k * step;
        label_linear(a->lab[a->n], DFLE_GP_TICKLAB, k * step, step, amax);
        a->n++;
    }
    label_factored(a, step);
    widest(a);
    return a->n;
}

/* Minor ticks between the majors of a linear axis: fifths of a 1 or 5
 * step, quarters of a 2 step, if they are at least 3 pt apart. */
static void linear_minor(dfle_gp_axis *a, double step, double len_pt)
{
    double m = step / pow(10.0, floor(log10(step) + 1e-9));
    double sub = step / (fabs(m - 2) < 1e-6 ? 4 : 5);
    double span = to_ax(a->hi, a->log) - to_ax(a->lo, a->log);
    a->nminor = 0;
    if (a->log || sub / span * len_pt < 3)
        return;
    for (double k = ceil(a->lo / sub - 1e-9); k * sub <= a->hi + 1e-9 * sub; k++) {
        double v = k * sub, r = v / step;
        if (fabs(r - floor(r + 0.5)) < 1e-6 || a->nminor == DFLE_GP_MAXMINOR)
            continue;
        a->minor[a->nminor++] = v;
    }
}

/* How much room the ticks now in a leave between labels beyond what
 * they need [pt] (negative: they touch), on an axis len_pt long. */
static double slack(const dfle_gp_axis *a, double len_pt, double font_pt, int vertical,
                    double per)
{
    double sl = min_gap(a, len_pt) - fmax(label_need(a, font_pt, vertical), len_pt / per);
    if (a->end_room > 0 && a->n > 0) { /* the end labels stay out of the neighbours' */
        double ulo = to_ax(a->lo, a->log), span = to_ax(a->hi, a->log) - ulo;
        for (size_t i = 0; i < a->n; i += a->n - 1) {
            double from = (to_ax(a->v[i], a->log) - ulo) / span * len_pt;
            double half = vertical ? 0.6 * font_pt : 0.5 * dfle_gp_text_em(a->lab[i]) * font_pt;
            sl = fmin(sl, fmin(from, len_pt - from) + a->end_room - half);
            if (a->n == 1)
                break;
        }
    }
    return sl;
}

/* The smallest 1, 2, 5 x 10^e step of at least two ticks whose labels
 * keep a gap, and no more than about nine ticks; *best_step the step
 * that came closest (0: none had two ticks).  Returns 1 if one fits. */
static int linear_steps(dfle_gp_axis *a, double len_pt, double font_pt, int vertical, double per,
                        double *best_step, double *best_slack)
{
    static const double mant[3] = {1, 2, 5};
    int e0 = (int)floor(log10(a->hi - a->lo)) - 2;
    for (int e = e0; e < e0 + 6; e++)
        for (int k = 0; k < 3; k++) {
            double step = mant[k] * pow(10.0, e), sl;
            if (linear_ticks(a, step) < 2)
                continue;
            sl = slack(a, len_pt, font_pt, vertical, per);
            if (sl >= 0)
                return 1;
            if (sl > *best_slack)
                *best_slack = sl, *best_step = step;
        }
    return 0;
}

/* The automatic linear ticks; on an axis too short for any set to keep
 * its gap, the set that comes closest, and at worst the two ends. */
static void auto_linear(dfle_gp_axis *a, double len_pt, double font_pt, int vertical)
{
    double best = 0, best_slack = -HUGE_VAL, span = a->hi - a->lo;
    if (linear_steps(a, len_pt, font_pt, vertical, 9, &best, &best_slack) ||
        (best > 0 && linear_ticks(a, best) >= 2)) {
        linear_minor(a, a->v[1] - a->v[0], len_pt);
        return;
    }
    a->n = 2;
    a->nminor = 0;
    a->v[0] = a->lo, a->v[1] = a->hi;
    label_linear(a->lab[0], DFLE_GP_TICKLAB, a->lo, span, fmax(fabs(a->lo), fabs(a->hi)));
    label_linear(a->lab[1], DFLE_GP_TICKLAB, a->hi, span, fmax(fabs(a->lo), fabs(a->hi)));
    label_factored(a, span);
    widest(a);
}

/* Log ticks at the mantissas `mant` of every `every`-th decade. */
static size_t log_ticks(dfle_gp_axis *a, const double *mant, int nm, int every)
{
    double dlo = log10(a->lo), dhi = log10(a->hi);
    int plain = 1;
    a->n = 0;
    for (int d = (int)floor(dlo) - 1; d <= (int)ceil(dhi); d++) {
        if (((d % every) + every) % every != 0)
            continue;
        for (int k = 0; k < nm; k++) {
            double v = mant[k] * pow(10.0, d);
            if (log10(v) < dlo - 1e-9 || log10(v) > dhi + 1e-9)
                continue;
            if (a->n == DFLE_GP_MAXTICKS)
                return a->n = 0;
            a->v[a->n++] = v;
            plain &= v >= 1e-3 * (1 - 1e-9) && v < 1e4;
        }
    }
    for (size_t i = 0; i < a->n; i++)
        label_log(a->lab[i], DFLE_GP_TICKLAB, a->v[i], plain);
    /* within a decade or so a factor reads better than powers of ten */
    a->factored = 0;
    if (!plain && dhi - dlo < 1.3 && a->n > 0) {
        double step = a->v[0];
        for (size_t i = 1; i < a->n; i++)
            step = fmin(step, a->v[i] - a->v[i - 1]);
        label_factored(a, step);
    }
    widest(a);
    return a->n;
}

/* Minor ticks of a log axis: 2..9 x 10^d where not labelled, while the
 * axis spans at most six decades; beyond, the unlabelled decades. */
static void log_minor(dfle_gp_axis *a)
{
    double dlo = log10(a->lo), dhi = log10(a->hi);
    int fine = dhi - dlo <= 6;
    a->nminor = 0;
    for (int d = (int)floor(dlo); d <= (int)ceil(dhi); d++)
        for (int m = 1; m <= (fine ? 9 : 1); m++) {
            double v = m * pow(10.0, d);
            int major = 0;
            if (log10(v) < dlo - 1e-9 || log10(v) > dhi + 1e-9)
                continue;
            for (size_t i = 0; i < a->n && !major; i++)
                major = fabs(a->v[i] / v - 1) < 1e-9;
            if (!major && a->nminor < DFLE_GP_MAXMINOR)
                a->minor[a->nminor++] = v;
        }
}

static void auto_log(dfle_gp_axis *a, double len_pt, double font_pt, int vertical)
{
    static const double m12357[5] = {1, 2, 3, 5, 7}, m125[3] = {1, 2, 5}, m13[2] = {1, 3},
                        m1[1] = {1};
    const struct {
        const double *m;
        int nm, every;
    } cand[] = {{m12357, 5, 1}, {m125, 3, 1}, {m13, 2, 1}, {m1, 1, 1}, {m1, 1, 2},
                {m1, 1, 3},     {m1, 1, 5},   {m1, 1, 10}};
    const size_t ncand = sizeof cand / sizeof cand[0];
    double span = log10(a->hi) - log10(a->lo), best_slack = -HUGE_VAL, best_step = 0;
    size_t best = ncand;
    /* Decades alone read best when there are four or more of them. */
    if (log_ticks(a, m1, 1, 1) >= 4 && a->n <= 9 && slack(a, len_pt, font_pt, vertical, 10) >= 0) {
        log_minor(a);
        return;
    }
    /* Otherwise the richest set whose labels keep their gap; under a
     * decade or so round values at even linear steps may give more. */
    for (size_t c = span < 1.3 ? 0 : 1; c < ncand; c++) {
        double sl;
        if (log_ticks(a, cand[c].m, cand[c].nm, cand[c].every) < 2)
            break; /* sparser sets give fewer still */
        sl = slack(a, len_pt, font_pt, vertical, 10);
        if (a->n <= 9 && sl >= 0) {
            size_t n_log = a->n;
            if (span < 1 && linear_steps(a, len_pt, font_pt, vertical, 14, &best_step, &best_slack) &&
                a->n > n_log) {
                log_minor(a);
                return;
            }
            log_ticks(a, cand[c].m, cand[c].nm, cand[c].every);
            log_minor(a);
            return;
        }
        if (sl > best_slack)
            best_slack = sl, best = c;
    }
    /* even steps on a log axis crowd only at its top: allow more */
    if (linear_steps(a, len_pt, font_pt, vertical, 14, &best_step, &best_slack)) {
        log_minor(a);
        return;
    }
    /* Nothing keeps its gap (a short axis): what comes closest. */
    if (best_step > 0 && linear_ticks(a, best_step) >= 2) {
        log_minor(a);
        return;
    }
    if (best < ncand && log_ticks(a, cand[best].m, cand[best].nm, cand[best].every) >= 2) {
        log_minor(a);
        return;
    }
    auto_linear(a, len_pt, font_pt, vertical);
}

void dfle_gp_axis_ticks(dfle_gp_axis *a, double len_pt, double font_pt, int vertical,
                        const dfle_plot_axis *user)
{
    a->format = user != NULL ? user->format : NULL;
    a->n = a->nminor = 0;
    a->factored = 0;
    if (user != NULL && user->ticks != NULL) {
        double gap = HUGE_VAL, amax = 0;
        for (size_t i = 1; i < user->nticks; i++)
            gap = fmin(gap, fabs(user->ticks[i] - user->ticks[i - 1]));
        for (size_t i = 0; i < user->nticks; i++)
            amax = fmax(amax, fabs(user->ticks[i]));
        if (!(gap > 0 && gap < HUGE_VAL))
            gap = amax > 0 ? amax : 1;
        for (size_t i = 0; i < user->nticks && i < DFLE_GP_MAXTICKS; i++) {
            const char *l = user->tick_labels != NULL ? user->tick_labels[i] : NULL;
            a->v[a->n] = user->ticks[i];
            if (l != NULL)
                snprintf(a->lab[a->n], DFLE_GP_TICKLAB, "%s", l);
            else if (a->log)
                label_log(a->lab[a->n], DFLE_GP_TICKLAB, user->ticks[i], 0);
            else
                label_linear(a->lab[a->n], DFLE_GP_TICKLAB, user->ticks[i],
                             pow(10.0, floor(log10(gap))), amax);
            a->n++;
        }
        widest(a);
        return;
    }
    if (user != NULL && user->step > 0 && !a->log) {
        double step = user->step;
        while (linear_ticks(a, step) == 0) /* more than the list holds */
            step *= 2;
        linear_minor(a, step, len_pt);
        return;
    }
    if (a->log)
        auto_log(a, len_pt, font_pt, vertical);
    else
        auto_linear(a, len_pt, font_pt, vertical);
}

const char *dfle_gp_axis_label(const dfle_gp_axis *a, const char *label, char *buf, size_t cap)
{
    const char *open = label != NULL ? strrchr(label, '(') : NULL;
    size_t len = label != NULL ? strlen(label) : 0;
    if (!a->factored || label == NULL)
        return label;
    if (open != NULL && len > 0 && label[len - 1] == ')') /* "D (m^2/s)": "D (×10^{-6} m^2/s)" */
        snprintf(buf, cap, "%.*s×10^{%d} %s", (int)(open - label + 1), label, a->factor_exp,
                 open + 1);
    else
        snprintf(buf, cap, "%s (×10^{%d})", label, a->factor_exp);
    return buf;
}

void dfle_gp_axis_put(FILE *f, const char *name, const dfle_gp_axis *a, int labels)
{
    if (a->log)
        fprintf(f, "set logscale %s 10\n", name);
    else
        fprintf(f, "unset logscale %s\n", name);
    fprintf(f, "set %srange [%.17g:%.17g]\n", name, a->lo, a->hi);
    if (a->format != NULL && labels) {
        fprintf(f, "set format %s ", name);
        dfle_gp_str(f, a->format);
        fputs("\n", f);
    }
    if (a->n == 0 && a->nminor == 0) {
        fprintf(f, "unset %stics\n", name);
        return;
    }
    fprintf(f, "set %stics (", name);
    for (size_t i = 0; i < a->n; i++) {
        fputs(i ? ", " : "", f);
        if (!labels)
            fputs("'' ", f);
        else if (a->format == NULL) {
            dfle_gp_str(f, a->lab[i]);
            fputc(' ', f);
        }
        fprintf(f, "%.17g", a->v[i]);
    }
    for (size_t i = 0; i < a->nminor; i++)
        fprintf(f, "%s'' %.17g 1", i || a->n ? ", " : "", a->minor[i]);
    fputs(")\n", f);
}
