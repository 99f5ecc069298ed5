/*
 * plot_frame.c - a figure laid out here, drawn by gnuplot: panels over
 * one x axis, their ranges and ticks (plot_axes.c), the margins, the
 * axis labels, the colour box and the legend.
 *
 * gnuplot lays out margins from what it knows, which is not enough: it
 * does not count the colour box's label (clipped at the right edge), and
 * stacked panels get different margins unless they are fixed.  Since the
 * page size, font size and every tick label are known here, the margins
 * are computed and fixed (in screen coordinates), and the axis labels
 * placed on the page, so panels line up and nothing is clipped.
 *
 * The legend goes where it hides no data: every layer is sampled (its
 * points, and its line segments every 0.5 % of the frame) and counted
 * against the boxes the legend could take; with no empty box, it goes
 * below the frame.
 */
#include "io/plot_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double ax(double v, int lg) { return lg ? log10(v) : v; }

static int usable(double x, double y, int logx, int logy)
{
    return isfinite(x) && isfinite(y) && (!logx || x > 0) && (!logy || y > 0);
}

void dfle_gp_layer_of(dfle_gp_layer *l, const dfle_plot_series *s, size_t k,
                      const dfle_gp_frame *fr)
{
    int band = s->lo != NULL;
    memset(l, 0, sizeof *l);
    l->n = s->n;
    l->x = s->x;
    l->y = band ? NULL : s->y;
    l->lo = band ? s->lo : NULL;
    l->hi = band ? s->hi : NULL;
    l->c = band ? NULL : s->c;
    l->title = s->label;
    l->line = band || s->style != DFLE_PLOT_POINTS;
    l->marks = !band && s->style != DFLE_PLOT_LINES;
    dfle_gp_look_of(s, k, fr, &l->look);
}

/* A row is drawn when its x, y (and colour, if any) can be placed. */
static int row_ok(const dfle_gp_layer *l, size_t i, int logx, int logy, int logc)
{
    if (l->y == NULL) /* a band */
        return usable(l->x[i], l->lo[i], logx, logy) && usable(l->x[i], l->hi[i], logx, logy);
    if (!usable(l->x[i], l->y[i], logx, logy))
        return 0;
    return l->c == NULL || (isfinite(l->c[i]) && (!logc || l->c[i] > 0));
}

/* Extents of the usable rows: x, y (per panel) and colour. */
typedef struct extent {
    double lo, hi;
} extent;

static void grow(extent *e, double v)
{
    e->lo = fmin(e->lo, v);
    e->hi = fmax(e->hi, v);
}

/* Where things are on the page [pt from the bottom left]. */
typedef struct layout {
    dfle_gp_box box;          /* the figure's part of the page    */
    double fx0, fx1;          /* frame, left and right            */
    double top, bottom;       /* of the stack of panels           */
    double cb_x;              /* colour box's left edge           */
    double key_below;         /* height of a legend below [pt]    */
    int key_cols;             /* its columns                      */
    double key_right;         /* width of a legend at the right   */
} layout;

/* The legend, drawn here rather than by gnuplot's key: gnuplot sizes
 * its key from an estimate of the text that runs wider than the text,
 * and ignores a column count when the key is placed outside, so its key
 * would not take the space counted for it.  Sizes in font sizes: */
#define KEY_ROW 1.35    /* an entry's height */
#define KEY_PAD 0.5     /* inside the box */
#define KEY_SAMPLE 2.4  /* the line or marker drawn for an entry */
#define KEY_GAP 0.6     /* between sample and text */
#define KEY_COLGAP 1.5  /* between columns below the frame */

/* Size of a legend of layers L [pt] in one column; *em its widest text. */
static void key_size(const dfle_gp_layer *L, size_t nl, double fs, double *w, double *h,
                     size_t *entries, double *em)
{
    size_t k = 0;
    *em = 0;
    for (size_t i = 0; i < nl; i++)
        if (L[i].title != NULL && L[i].used > 0) {
            *em = fmax(*em, dfle_gp_text_em(L[i].title));
            k++;
        }
    *entries = k;
    *w = (2 * KEY_PAD + KEY_SAMPLE + KEY_GAP + *em) * fs;
    *h = (2 * KEY_PAD + (double)k * KEY_ROW - 0.3) * fs;
}

/* Candidate places for a legend inside the frame, as frame fractions. */
enum { NPLACES = 6 };
static const int places[NPLACES] = {DFLE_LEGEND_TOP_RIGHT, DFLE_LEGEND_TOP_LEFT,
                                    DFLE_LEGEND_BOTTOM_LEFT, DFLE_LEGEND_BOTTOM_RIGHT,
                                    DFLE_LEGEND_TOP, DFLE_LEGEND_BOTTOM};

static void place_box(int where, double kw, double kh, double box[4])
{
    const double m = 0.035; /* the inset, and a clear gap to the data */
    int right = where == DFLE_LEGEND_TOP_RIGHT || where == DFLE_LEGEND_BOTTOM_RIGHT;
    int left = where == DFLE_LEGEND_TOP_LEFT || where == DFLE_LEGEND_BOTTOM_LEFT;
    int top = where == DFLE_LEGEND_TOP_RIGHT || where == DFLE_LEGEND_TOP_LEFT ||
              where == DFLE_LEGEND_TOP;
    box[0] = left ? 0 : right ? 1 - kw - m : 0.5 - kw / 2 - m;
    box[1] = left ? kw + m : right ? 1 : 0.5 + kw / 2 + m;
    box[2] = top ? 1 - kh - m : 0;
    box[3] = top ? 1 : kh + m;
}

/* Counts of samples of the layers inside each candidate box. */
typedef struct cover {
    double box[NPLACES][4];
    size_t hits[NPLACES];
} cover;

static void hit(cover *cv, double u, double v)
{
    for (int p = 0; p < NPLACES; p++)
        cv->hits[p] += u >= cv->box[p][0] && u <= cv->box[p][1] && v >= cv->box[p][2] &&
                       v <= cv->box[p][3];
}

/* Sample the segment (u0, v0)-(u1, v1) (frame fractions) every 0.5 %. */
static void hit_segment(cover *cv, double u0, double v0, double u1, double v1)
{
    double len = hypot(u1 - u0, v1 - v0);
    int k = (int)fmin(400, ceil(len / 0.005));
    for (int j = 0; j <= k; j++) {
        double t = k > 0 ? (double)j / k : 0;
        hit(cv, u0 + t * (u1 - u0), v0 + t * (v1 - v0));
    }
}

static double frac(double v, int lg, double lo, double hi)
{
    return (ax(v, lg) - ax(lo, lg)) / (ax(hi, lg) - ax(lo, lg));
}

/* The emptiest inside place for a legend of kw x kh (frame fractions)
 * in a panel; *hits how much it covers. */
static int best_place(const dfle_gp_panel *P, const dfle_gp_axis *xa, const dfle_gp_axis *ya,
                      int logc, double kw, double kh, size_t *hits)
{
    cover cv;
    int best = 0;
    memset(&cv, 0, sizeof cv);
    for (int p = 0; p < NPLACES; p++)
        place_box(places[p], kw, kh, cv.box[p]);
    for (size_t k = 0; k < P->nl; k++) {
        const dfle_gp_layer *l = &P->layers[k];
        int have = 0;
        double pu = 0, pv = 0, plo = 0, phi = 0;
        for (size_t i = 0; i < l->n; i++) {
            if (!row_ok(l, i, xa->log, ya->log, logc)) {
                have = 0; /* a gap in a line */
                continue;
            }
            double u = frac(l->x[i], xa->log, xa->lo, xa->hi);
            double v = l->y != NULL ? frac(l->y[i], ya->log, ya->lo, ya->hi) : 0;
            if (l->y == NULL || l->lo != NULL) { /* a band, or error bars */
                double a = frac(l->lo[i], ya->log, ya->lo, ya->hi);
                double b = frac(l->hi[i], ya->log, ya->lo, ya->hi);
                if (isfinite(a) && isfinite(b)) {
                    hit_segment(&cv, u, a, u, b);
                    if (l->y == NULL && have) { /* the band's area between rows */
                        hit_segment(&cv, pu, plo, u, a);
                        hit_segment(&cv, pu, phi, u, b);
                        hit_segment(&cv, pu, (plo + phi) / 2, u, (a + b) / 2);
                    }
                    plo = a, phi = b;
                }
            }
            if (l->y != NULL) {
                if (l->line && have)
                    hit_segment(&cv, pu, pv, u, v);
                else
                    hit(&cv, u, v);
            }
            pu = u, pv = v, have = 1;
        }
    }
    for (int p = 1; p < NPLACES; p++)
        if (cv.hits[p] < cv.hits[best])
            best = p;
    *hits = cv.hits[best];
    return places[best];
}

/* One legend entry's sample at (x, y) [pt], KEY_SAMPLE long. */
static void put_sample(FILE *f, int tag, const dfle_gp_layer *l, double x, double y,
                       const dfle_gp_frame *fr)
{
    const dfle_gp_look *k = &l->look;
    const double fs = fr->font_pt, W = fr->w_pt, H = fr->h_pt, len = KEY_SAMPLE * fs;
    /* a layer coloured by value shows the scale's middle colour */
    const char *rgb = l->c != NULL ? "#21918c" : k->rgb;
    if (k->kind == DFLE_GP_BAND)
        fprintf(f, "set object %d rect from screen %.5f, screen %.5f to screen %.5f, screen %.5f "
                "fc rgb '%s' fs transparent solid 0.3 noborder front\n", tag, x / W,
                (y - 0.35 * fs) / H, (x + len) / W, (y + 0.35 * fs) / H, rgb);
    if (k->kind == DFLE_GP_LINES || k->kind == DFLE_GP_LINESPOINTS)
        fprintf(f, "set arrow %d from screen %.5f, screen %.5f to screen %.5f, screen %.5f "
                "nohead lw %.3g dt %d lc rgb '%s' front\n", tag, x / W, y / H, (x + len) / W,
                y / H, k->lw, k->dt, rgb);
    if (k->kind == DFLE_GP_BARS)
        fprintf(f, "set arrow %d from screen %.5f, screen %.5f to screen %.5f, screen %.5f "
                "nohead lw %.3g lc rgb '%s' front\n", tag, (x + len / 2) / W,
                (y - 0.5 * fs) / H, (x + len / 2) / W, (y + 0.5 * fs) / H, k->lw, rgb);
    if (k->kind == DFLE_GP_POINTS || k->kind == DFLE_GP_LINESPOINTS || k->kind == DFLE_GP_BARS)
        fprintf(f, "set label %d '' at screen %.5f, screen %.5f point pt %d ps %.3g lw %.3g "
                "lc rgb '%s' front\n", tag, (x + len / 2) / W, y / H, k->pt, k->ps,
                k->lw > 0 ? k->lw : 1, rgb);
}

/* The legend of a panel at `where`; the panel's frame is x0..x1 by
 * y0..y1 [pt]; a legend below the frame goes in lay->key_below's rows. */
static void put_legend(FILE *f, const dfle_gp_panel *P, int where, const layout *lay,
                       double y0, double y1, const dfle_gp_frame *fr)
{
    const double fs = fr->font_pt, W = fr->w_pt, H = fr->h_pt, inset = 0.35 * fs;
    double w, h, em, bx, by, colw;
    size_t entries, cols = 1, e = 0;
    int tag = 200;
    if (where == DFLE_LEGEND_NONE)
        return;
    key_size(P->layers, P->nl, fs, &w, &h, &entries, &em);
    if (entries == 0)
        return;
    colw = (KEY_SAMPLE + KEY_GAP + em) * fs;
    if (where == DFLE_LEGEND_BELOW) {
        cols = (size_t)lay->key_cols;
        w = (double)cols * colw + (double)(cols - 1) * KEY_COLGAP * fs;
        bx = fmax(lay->box.x0 + 0.5 * fs,
                  fmin((lay->fx0 + lay->fx1) / 2 - w / 2, lay->box.x1 - w - 0.5 * fs));
        by = lay->box.y0 + lay->key_below; /* top of the rows */
    } else if (where == DFLE_LEGEND_OUTSIDE_RIGHT) {
        bx = lay->fx1 + 0.8 * fs;
        by = y1;
    } else {
        int left = where == DFLE_LEGEND_TOP_LEFT || where == DFLE_LEGEND_BOTTOM_LEFT ||
                   where == DFLE_LEGEND_LEFT;
        int right = where == DFLE_LEGEND_TOP_RIGHT || where == DFLE_LEGEND_BOTTOM_RIGHT ||
                    where == DFLE_LEGEND_RIGHT;
        int top = where == DFLE_LEGEND_TOP_LEFT || where == DFLE_LEGEND_TOP_RIGHT ||
                  where == DFLE_LEGEND_TOP;
        int bottom = where == DFLE_LEGEND_BOTTOM_LEFT || where == DFLE_LEGEND_BOTTOM_RIGHT ||
                     where == DFLE_LEGEND_BOTTOM;
        bx = left ? lay->fx0 + inset : right ? lay->fx1 - inset - w
                                             : (lay->fx0 + lay->fx1) / 2 - w / 2;
        by = top ? y1 - inset : bottom ? y0 + inset + h : (y0 + y1) / 2 + h / 2;
        /* an opaque box: what it covers is hidden, not mixed with text */
        fprintf(f, "set object %d rect from screen %.5f, screen %.5f to screen %.5f, screen %.5f "
                "fc rgb '#ffffff' fs solid 1.0 border lc rgb '#b0b0b0' lw 1.2 front\n", tag++,
                bx / W, (by - h) / H, (bx + w) / W, by / H);
        bx += KEY_PAD * fs;
        by -= KEY_PAD * fs;
    }
    for (size_t i = 0; i < P->nl; i++) {
        const dfle_gp_layer *l = &P->layers[i];
        double x, y;
        if (l->title == NULL || l->used == 0)
            continue;
        /* below the frame: rows left to right; elsewhere one column */
        x = bx + (double)(e % cols) * (colw + KEY_COLGAP * fs);
        y = by - ((double)(e / cols) + 0.5) * KEY_ROW * fs;
        put_sample(f, tag++, l, x, y, fr); /* its point is a label: the text needs another tag */
        fprintf(f, "set label %d ", tag++);
        dfle_gp_str(f, l->title);
        fprintf(f, " at screen %.5f, screen %.5f left front\n", (x + (KEY_SAMPLE + KEY_GAP) * fs) / W,
                y / H);
        e++;
    }
}

/* The plot command of a panel's layers (datablocks $<pre>p<panel>_<layer>). */
static void put_plot(FILE *f, const char *pre, size_t pi, const dfle_gp_panel *P)
{
    int first = 1;
    fputs("plot", f);
    for (size_t k = 0; k < P->nl; k++) {
        const dfle_gp_layer *l = &P->layers[k];
        if (l->used == 0)
            continue; /* gnuplot refuses an empty block */
        if (l->c != NULL)
            fprintf(f, "%s $%sp%zu_%zu using 1:2:3 with %s lc palette", first ? "" : ",", pre,
                    pi, k, l->look.with);
        else
            fprintf(f, "%s $%sp%zu_%zu using %s with %s lc rgb '%s'", first ? "" : ",", pre, pi, k,
                    l->y == NULL ? "1:3:4" : l->lo != NULL ? "1:2:3:4" : "1:2", l->look.with,
                    l->look.rgb);
        if (l->title != NULL) {
            fputs(" title ", f);
            dfle_gp_str(f, l->title);
        } else {
            fputs(" notitle", f);
        }
        first = 0;
    }
    fputs("\n", f);
}

/* Datablocks of the usable rows: x, y (a band: hi), then lo hi, then c. */
static void put_blocks(FILE *f, const char *pre, size_t pi, const dfle_gp_panel *P, int logx,
                       int logy, int logc)
{
    for (size_t k = 0; k < P->nl; k++) {
        const dfle_gp_layer *l = &P->layers[k];
        int gap = 0;
        if (l->used == 0)
            continue;
        fprintf(f, "$%sp%zu_%zu << EOD\n", pre, pi, k);
        for (size_t i = 0; i < l->n; i++) {
            double x = l->x[i], y = l->y != NULL ? l->y[i] : l->hi[i];
            if (!row_ok(l, i, logx, logy, logc)) {
                if (gap) fputs("\n", f); /* a blank line breaks a line */
                gap = 0;
                continue;
            }
            gap = 1;
            fprintf(f, "%.17g %.17g", x, y);
            if (l->lo != NULL) { /* a bad quartile draws no bar */
                double lo = l->lo[i], hi = l->hi[i];
                fprintf(f, " %.17g %.17g", usable(x, lo, 0, logy) ? lo : y,
                        usable(x, hi, 0, logy) ? hi : y);
            }
            if (l->c != NULL)
                fprintf(f, " %.17g", l->c[i]);
            fputs("\n", f);
        }
        fputs("EOD\n", f);
    }
}

void dfle_gp_page_label(FILE *f, int tag, const char *text, double x, double y, double rot,
                        int plain, const dfle_gp_frame *fr)
{
    if (text == NULL)
        return;
    fprintf(f, "set label %d ", tag);
    dfle_gp_str(f, text);
    fprintf(f, " at screen %.5f, screen %.5f center rotate by %g front%s\n", x / fr->w_pt,
            y / fr->h_pt, rot, plain ? " noenhanced" : "");
}

static void put_page_label(FILE *f, int tag, const char *text, double x, double y, double rot,
                           const dfle_gp_frame *fr)
{
    dfle_gp_page_label(f, tag, text, x, y, rot, 0, fr);
}

/* Margins and the colour box for the panels' ticks and labels: the
 * panels' heights set their y ticks, whose labels set the left margin. */
static void compute_layout(layout *lay, const dfle_gp_frame *fr, const dfle_plot_opts *o,
                           const char *xl, dfle_gp_panel *P, size_t np, dfle_gp_axis *ya,
                           dfle_gp_axis *ca, int any_c, double weights, double gap)
{
    const double fs = fr->font_pt;
    const dfle_gp_box *b = &lay->box;
    double yem = 0, stack_h;
    lay->top = b->y1 - (o->title != NULL ? 2.4 * fs : 0.9 * fs);
    lay->bottom = b->y0 + (1.25 + 1.3 + 0.45) * fs + (xl != NULL ? 1.2 * fs : 0) +
                  lay->key_below;
    stack_h = lay->top - lay->bottom - gap * (double)(np - 1);
    for (size_t p = 0; p < np; p++) {
        double h = stack_h * (P[p].weight > 0 ? P[p].weight : 1) / weights;
        dfle_gp_axis_ticks(&ya[p], h, fs, 1, P[p].y);
        yem = fmax(yem, ya[p].max_em);
    }
    lay->fx0 = b->x0 + (0.5 + 1.5 + 0.7 + 0.3) * fs + yem * fs;
    lay->fx1 = b->x1 - 1.6 * fs - lay->key_right;
    if (any_c) {
        /* box, its tick labels, its label, all fixed on the page */
        dfle_gp_axis_ticks(ca, lay->top - lay->bottom, fs, 1, &o->c);
        lay->cb_x = lay->fx1 - (o->c.label != NULL ? 1.6 * fs : 0) - ca->max_em * fs -
                    0.6 * fs - 1.1 * fs;
        lay->fx1 = lay->cb_x - 1.0 * fs;
    }
}

static double panel_h(const layout *lay, const dfle_gp_panel *P, size_t np, size_t p,
                      double weights, double gap)
{
    double stack_h = lay->top - lay->bottom - gap * (double)(np - 1);
    return stack_h * (P[p].weight > 0 ? P[p].weight : 1) / weights;
}

/* Everything a figure needs before gnuplot starts: ranges, ticks, the
 * layout and where each legend goes. */
struct dfle_gp_plan {
    const dfle_gp_frame *fr;
    const dfle_plot_opts *o;
    dfle_gp_panel *P;
    size_t np;
    int xlog, logc, any_c;
    const char *xl;
    double weights, gap;
    dfle_gp_axis *xa, *ya, *ca;
    int key_where[16];
    layout lay;
};

void dfle_gp_plan_free(dfle_gp_plan *pl)
{
    if (pl == NULL)
        return;
    free(pl->xa);
    free(pl->ya);
    free(pl->ca);
    free(pl);
}

/* The x ticks for the frame's width; the last label, centred on the
 * frame's edge, must fit on the page. */
static void x_ticks(dfle_gp_plan *pl)
{
    layout *lay = &pl->lay;
    const double fs = pl->fr->font_pt;
    dfle_gp_axis_ticks(pl->xa, lay->fx1 - lay->fx0, fs, 0, &pl->o->x);
    if (pl->xa->n > 0 && !pl->any_c)
        lay->fx1 = fmin(lay->fx1, lay->box.x1 - lay->key_right -
                        0.5 * dfle_gp_text_em(pl->xa->lab[pl->xa->n - 1]) * fs - 0.3 * fs);
}

double dfle_gp_plan_key_below(const dfle_gp_plan *pl)
{
    return pl->lay.key_below;
}

void dfle_gp_plan_set_key_below(dfle_gp_plan *pl, double key_below)
{
    if (!(key_below > pl->lay.key_below))
        return;
    pl->lay.key_below = key_below;
    compute_layout(&pl->lay, pl->fr, pl->o, pl->xl, pl->P, pl->np, pl->ya, pl->ca, pl->any_c,
                   pl->weights, pl->gap);
    x_ticks(pl);
}

int dfle_gp_plan_new(const char *path, const dfle_gp_frame *fr, const dfle_gp_box *box,
                     const dfle_plot_opts *opts, int xlog, const char *xlabel, dfle_gp_panel *P,
                     size_t np, dfle_gp_plan **out, dfle_error *err)
{
    static const dfle_plot_opts none = {0};
    const dfle_plot_opts *o = opts != NULL ? opts : &none;
    const double fs = fr->font_pt, gap = 0.9 * fs;
    dfle_gp_plan *pl;
    dfle_gp_axis *xa, *ya, *ca;
    extent ex = {HUGE_VAL, -HUGE_VAL}, ec = {HUGE_VAL, -HUGE_VAL};
    int logc = o->c.log > 0, any_c = 0, marks = 0, rc = DFLE_OK, have_below = 0;
    int *key_where;
    const char *xl = o->x.label != NULL ? o->x.label : xlabel;
    double weights = 0;
    layout *lay;

    *out = NULL;
    if (np == 0 || np > 16)
        return dfle_error_set(err, DFLE_EINVAL, "plot: 1 to 16 panels (got %zu)", np);
    if (o->x.log != 0)
        xlog = o->x.log > 0;
    if ((rc = dfle_gp_axis_ok('x', &o->x, xlog, err)) < 0 ||
        (rc = dfle_gp_axis_ok('c', &o->c, logc, err)) < 0)
        return rc;
    if ((pl = calloc(1, sizeof *pl)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "plot: out of memory");
    pl->xa = xa = calloc(1, sizeof *xa);
    pl->ya = ya = calloc(np, sizeof *ya);
    pl->ca = ca = calloc(1, sizeof *ca);
    if (xa == NULL || ya == NULL || ca == NULL) {
        rc = dfle_error_set(err, DFLE_ENOMEM, "plot: out of memory");
        goto done;
    }
    key_where = pl->key_where;
    lay = &pl->lay;

    /* Extents: x over every panel, y per panel, colour over all. */
    for (size_t p = 0; p < np; p++) {
        extent ey = {HUGE_VAL, -HUGE_VAL};
        const dfle_plot_axis *yu = P[p].y;
        int ylog = yu != NULL && yu->log != 0 ? yu->log > 0 : P[p].ylog;
        size_t used = 0;
        P[p].ylog = ylog;
        if (yu != NULL && (rc = dfle_gp_axis_ok('y', yu, ylog, err)) < 0)
            goto done;
        for (size_t k = 0; k < P[p].nl; k++) {
            dfle_gp_layer *l = &P[p].layers[k];
            l->used = 0;
            any_c |= l->c != NULL;
            marks |= l->marks;
            for (size_t i = 0; i < l->n; i++) {
                if (!row_ok(l, i, xlog, ylog, logc))
                    continue;
                grow(&ex, ax(l->x[i], xlog));
                l->used++;
                /* zoomed in x: y and colour fit what is in view */
                if ((o->x.has_lo && l->x[i] < o->x.lo) || (o->x.has_hi && l->x[i] > o->x.hi))
                    continue;
                if (l->y != NULL)
                    grow(&ey, ax(l->y[i], ylog));
                if (l->lo != NULL) { /* bars and bands count where they end */
                    if (usable(l->x[i], l->lo[i], xlog, ylog)) grow(&ey, ax(l->lo[i], ylog));
                    if (usable(l->x[i], l->hi[i], xlog, ylog)) grow(&ey, ax(l->hi[i], ylog));
                }
                if (l->c != NULL)
                    grow(&ec, ax(l->c[i], logc));
            }
            used += l->used;
        }
        if (used == 0) {
            rc = dfle_error_set(err, DFLE_EINVAL, "plot: no finite points%s to plot%s in '%s'",
                                xlog || ylog ? " (positive on log axes)" : "",
                                np > 1 ? " in a panel" : "", path);
            goto done;
        }
        /* Data do not sit on the frame: 4 % more range at each end. */
        dfle_gp_axis_range(&ya[p], ylog, ylog ? pow(10, ey.lo) : ey.lo,
                           ylog ? pow(10, ey.hi) : ey.hi, 0.04, yu);
        weights += P[p].weight > 0 ? P[p].weight : 1;
    }
    /* Lines run from frame to frame; markers keep off it. */
    dfle_gp_axis_range(xa, xlog, xlog ? pow(10, ex.lo) : ex.lo, xlog ? pow(10, ex.hi) : ex.hi,
                       marks ? 0.025 : 0, &o->x);
    if (any_c)
        dfle_gp_axis_range(ca, logc, logc ? pow(10, ec.lo) : ec.lo,
                           logc ? pow(10, ec.hi) : ec.hi, 0, &o->c);

    /* Layout without outside legends, then where the legends go (inside
     * where no data are; one panel's legend below the frame when every
     * inside place would hide data), then the layout with them. */
    memset(lay, 0, sizeof *lay);
    lay->box = box != NULL ? *box : (dfle_gp_box){0, 0, fr->w_pt, fr->h_pt};
    compute_layout(lay, fr, o, xl, P, np, ya, ca, any_c, weights, gap);
    for (size_t p = 0; p < np; p++) {
        double kw, kh, em;
        size_t entries, hits;
        key_size(P[p].layers, P[p].nl, fs, &kw, &kh, &entries, &em);
        key_where[p] = entries == 0 ? DFLE_LEGEND_NONE : o->legend;
        if (key_where[p] == DFLE_LEGEND_BELOW && have_below)
            key_where[p] = DFLE_LEGEND_AUTO; /* one legend fits below */
        if (key_where[p] == DFLE_LEGEND_AUTO) {
            double fw = lay->fx1 - lay->fx0, fh = panel_h(lay, P, np, p, weights, gap);
            key_where[p] = kw > 0.9 * fw || kh > 0.9 * fh
                               ? DFLE_LEGEND_BELOW
                               : best_place(&P[p], xa, &ya[p], logc, kw / fw, kh / fh, &hits);
            if (key_where[p] != DFLE_LEGEND_BELOW && hits > 0 && !have_below && np == 1)
                key_where[p] = DFLE_LEGEND_BELOW;
            if (key_where[p] == DFLE_LEGEND_BELOW && have_below)
                key_where[p] = DFLE_LEGEND_TOP_RIGHT;
        }
        if (key_where[p] == DFLE_LEGEND_BELOW) {
            /* rows of columns as wide as the widest entry */
            double colw = (KEY_SAMPLE + KEY_GAP + em + KEY_COLGAP) * fs;
            double cols = fmax(1, fmin((double)entries,
                                       floor((lay->box.x1 - lay->box.x0 - fs) / colw)));
            lay->key_cols = (int)cols;
            lay->key_below = ceil((double)entries / cols) * KEY_ROW * fs + 0.5 * fs;
            have_below = 1;
        }
        if (key_where[p] == DFLE_LEGEND_OUTSIDE_RIGHT)
            lay->key_right = fmax(lay->key_right, kw - 2 * KEY_PAD * fs + 1.2 * fs);
    }
    if (lay->key_below > 0 || lay->key_right > 0)
        compute_layout(lay, fr, o, xl, P, np, ya, ca, any_c, weights, gap);
    if (lay->fx1 - lay->fx0 < 4 * fs || panel_h(lay, P, np, 0, weights, gap) < 3 * fs) {
        rc = dfle_error_set(err, DFLE_EINVAL, "plot: the page (%.3g x %.3g cm) is too small for "
                            "its labels at a %g pt font", fr->w_pt / 72 * 2.54,
                            fr->h_pt / 72 * 2.54, fs);
        goto done;
    }
    pl->fr = fr, pl->o = o, pl->P = P, pl->np = np, pl->xlog = xlog, pl->logc = logc;
    pl->any_c = any_c, pl->xl = xl, pl->weights = weights, pl->gap = gap;
    x_ticks(pl);
done:
    if (rc < 0) {
        dfle_gp_plan_free(pl);
        return rc;
    }
    *out = pl;
    return DFLE_OK;
}

void dfle_gp_plan_frame(const dfle_gp_plan *pl, size_t p, double frame[4])
{
    double t = pl->lay.top;
    for (size_t q = 0; q < p; q++)
        t -= panel_h(&pl->lay, pl->P, pl->np, q, pl->weights, pl->gap) + pl->gap;
    frame[0] = pl->lay.fx0, frame[1] = t - panel_h(&pl->lay, pl->P, pl->np, p, pl->weights,
                                                   pl->gap);
    frame[2] = pl->lay.fx1, frame[3] = t;
}

void dfle_gp_plan_put(FILE *f, const dfle_gp_plan *pl, int cell, int in_multiplot)
{
    const dfle_gp_frame *fr = pl->fr;
    const dfle_plot_opts *o = pl->o;
    const layout *lay = &pl->lay;
    const double fs = fr->font_pt;
    dfle_gp_panel *P = pl->P;
    const size_t np = pl->np;
    char pre[16];
    snprintf(pre, sizeof pre, "c%d", cell);
    for (size_t p = 0; p < np; p++)
        put_blocks(f, pre, p, &P[p], pl->xlog, P[p].ylog, pl->logc);
    if (pl->any_c) {
        fputs("set palette defined (0 '#440154', 0.25 '#3b528b', 0.5 '#21918c', "
              "0.75 '#5ec962', 1 '#fde725')\n", f);
        fprintf(f, "set colorbox user origin screen %.5f, screen %.5f size screen %.5f, "
                "screen %.5f front bdefault\n", lay->cb_x / fr->w_pt, lay->bottom / fr->h_pt,
                1.1 * fs / fr->w_pt, (lay->top - lay->bottom) / fr->h_pt);
        pl->ca->nminor = 0; /* a colour box reads by its labelled ticks */
        dfle_gp_axis_put(f, "cb", pl->ca, 1);
    } else {
        fputs("unset colorbox\n", f);
    }
    fputs("unset key\n", f); /* the legend is drawn by put_legend */
    if (np > 1 && !in_multiplot)
        fputs("set multiplot\n", f);
    {
        double t = lay->top;
        for (size_t p = 0; p < np; p++) {
            double h = panel_h(lay, P, np, p, pl->weights, pl->gap);
            const char *yl = P[p].y != NULL && P[p].y->label != NULL ? P[p].y->label
                                                                      : P[p].ylabel;
            fprintf(f, "set lmargin at screen %.5f\nset rmargin at screen %.5f\n"
                    "set tmargin at screen %.5f\nset bmargin at screen %.5f\n",
                    lay->fx0 / fr->w_pt, lay->fx1 / fr->w_pt, t / fr->h_pt, (t - h) / fr->h_pt);
            dfle_gp_axis_put(f, "x", pl->xa, p == np - 1);
            dfle_gp_axis_put(f, "y", &pl->ya[p], 1);
            fprintf(f, "set grid xtics ytics%s%s back ls 81, ls 82\n",
                    pl->xlog ? " mxtics" : "", pl->ya[p].log ? " mytics" : "");
            /* The page's labels go with the first panel drawn (title,
             * colour box) or the last (x), each panel its own y. */
            if (p == 0 && o->title != NULL)
                put_page_label(f, 100, o->title, (lay->fx0 + lay->fx1) / 2,
                               lay->box.y1 - 1.25 * fs, 0, fr);
            if (p == 0 && pl->any_c)
                put_page_label(f, 103, o->c.label, lay->box.x1 - 0.9 * fs,
                               (lay->top + lay->bottom) / 2, 90, fr);
            if (p == np - 1)
                put_page_label(f, 101, pl->xl, (lay->fx0 + lay->fx1) / 2,
                               lay->box.y0 + lay->key_below + 0.95 * fs, 0, fr);
            put_page_label(f, 102, yl, lay->box.x0 + 1.1 * fs, t - h / 2, 90, fr);
            put_legend(f, &P[p], pl->key_where[p], lay, t - h, t, fr);
            if (P[p].extra != NULL)
                fputs(P[p].extra, f);
            put_plot(f, pre, p, &P[p]);
            fputs("unset label\nunset arrow\nunset object\n", f);
            t -= h + pl->gap;
        }
    }
    if (np > 1 && !in_multiplot)
        fputs("unset multiplot\n", f);
}

int dfle_gp_figure(const char *path, const dfle_gp_frame *fr, const dfle_plot_opts *opts,
                   int xlog, const char *xlabel, dfle_gp_panel *P, size_t np,
                   dfle_error *err)
{
    dfle_gp_plan *pl;
    dfle_gp_run r;
    int rc = dfle_gp_plan_new(path, fr, NULL, opts, xlog, xlabel, P, np, &pl, err);
    if (rc < 0)
        return rc;
    if ((rc = dfle_gp_begin_frame(&r, path, fr, err)) == DFLE_OK) {
        dfle_gp_plan_put(r.f, pl, 0, 0);
        rc = dfle_gp_end(&r, err);
    }
    dfle_gp_plan_free(pl);
    return rc;
}
