/*
 * plot_map.c - maps: shaded relief, channels and debris-flow reach, or
 * a network's cells coloured by a value (k_sn), with the furniture a
 * map in a paper carries: axes in km named by the CRS, a scale bar, a
 * north arrow and a legend.
 *
 * The page is laid out here, like the figures of plot_frame.c: the frame
 * takes the page's width less the margins its tick labels and colour box
 * need, and its height follows at equal scales, so the page has no empty
 * band above or below a map of any shape.  The scale bar, the north arrow
 * and the legend go in the frame's corners that hold the fewest cells
 * with data (a catchment cut from a DEM leaves its corners empty); a
 * legend that would hide data goes below the frame, inside the page.
 */
#include "dfle/plot.h"

#include "io/plot_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_CELLS = 1500000 };

/* The hypsometric tint, in gnuplot's palette and in C alike. */
static const double tint_at[5] = {0.0, 0.25, 0.5, 0.75, 1.0};
static const unsigned tint_rgb[5] = {0x2f6b3a, 0x8fae5d, 0xd8c98e, 0xa9825a, 0xf4f1ea};
#define VIRIDIS "0 '#440154', 0.25 '#3b528b', 0.5 '#21918c', 0.75 '#5ec962', 1 '#fde725'"
#define CHANNEL_RGB "#0072B2"

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

/* What is drawn: the box of cells with data, in cells and in km. */
typedef struct view {
    size_t r0, r1, c0, c1, step;
    double xlo, xhi, ylo, yhi; /* km */
    double zmin, zmax;
} view;

/* Where things are on the page [pt]. */
typedef struct place {
    double fx0, fx1, fy0, fy1; /* the frame            */
    double cb_x;               /* the colour box's left */
    double key_below;          /* rows of a legend below the frame */
} place;

/* The fraction of the cells under the frame-fraction box u0..u1 x
 * v0..v1 that hold data. */
static double covered(const dfle_plot_map *m, const view *v, const double b[4])
{
    double x0 = (v->xlo + b[0] * (v->xhi - v->xlo)) * 1000, x1 = (v->xlo + b[1] * (v->xhi - v->xlo)) * 1000;
    double y0 = (v->ylo + b[2] * (v->yhi - v->ylo)) * 1000, y1 = (v->ylo + b[3] * (v->yhi - v->ylo)) * 1000;
    long c0 = (long)floor((x0 - m->x0) / m->dx), c1 = (long)floor((x1 - m->x0) / m->dx);
    long r0 = (long)floor((m->y0 - y1) / m->dy), r1 = (long)floor((m->y0 - y0) / m->dy);
    size_t all = 0, data = 0;
    for (long r = r0 < 0 ? 0 : r0; r <= r1 && r < (long)m->ny; r++)
        for (long c = c0 < 0 ? 0 : c0; c <= c1 && c < (long)m->nx; c++) {
            all++;
            data += !isnan(m->z[(size_t)r * m->nx + (size_t)c]);
        }
    return all > 0 ? (double)data / (double)all : 0;
}

/* A corner of the frame for a box of w x h pt, inset by `in` pt:
 * corner 0 top left, 1 top right, 2 bottom left, 3 bottom right;
 * b gets the box as frame fractions. */
static void corner_box(const place *p, int corner, double w, double h, double in, double b[4])
{
    double fw = p->fx1 - p->fx0, fh = p->fy1 - p->fy0;
    int right = corner & 1, bottom = corner >> 1;
    b[0] = right ? 1 - (w + in) / fw : in / fw;
    b[1] = b[0] + w / fw;
    b[2] = bottom ? in / fh : 1 - (h + in) / fh;
    b[3] = b[2] + h / fh;
}

/* The free corner among `allowed` (bit k: corner k) covering least data;
 * *cover its coverage.  -1 when none is free. */
static int best_corner(const dfle_plot_map *m, const view *v, const place *p, unsigned allowed,
                       unsigned *used, double w, double h, double in, double *cover)
{
    int best = -1;
    double bc = HUGE_VAL, b[4];
    for (int k = 0; k < 4; k++) {
        double c;
        if (!(allowed >> k & 1) || (*used >> k & 1))
            continue;
        corner_box(p, k, w, h, in, b);
        c = covered(m, v, b);
        if (c < bc - 1e-9)
            bc = c, best = k;
    }
    if (best >= 0)
        *used |= 1u << best;
    *cover = bc;
    return best;
}

/* The largest 1, 2 or 5 x 10^k metres not over `target` m. */
static double nice_length(double target)
{
    double p = pow(10.0, floor(log10(target))), best = p;
    static const double mant[3] = {1, 2, 5};
    for (int k = 0; k < 3; k++)
        if (mant[k] * p <= target * (1 + 1e-9))
            best = mant[k] * p;
    return best;
}

static void label_at(FILE *f, int tag, const char *text, double x, double y, const char *align,
                     double scale, int plain, const dfle_gp_frame *fr)
{
    fprintf(f, "set label %d ", tag);
    dfle_gp_str(f, text);
    fprintf(f, " at screen %.5f, screen %.5f %s front%s", x / fr->w_pt, y / fr->h_pt, align,
            plain ? " noenhanced" : "");
    if (scale != 1) {
        char font[96];
        snprintf(font, sizeof font, "%s,%g", fr->family, fr->font_pt * scale);
        fputs(" font ", f);
        dfle_gp_str(f, font);
    }
    fputs("\n", f);
}

static void rect(FILE *f, int tag, double x0, double y0, double x1, double y1, const char *fill,
                 const char *style, const dfle_gp_frame *fr)
{
    fprintf(f, "set object %d rect from screen %.5f, screen %.5f to screen %.5f, screen %.5f "
            "fc rgb '%s' %s front\n", tag, x0 / fr->w_pt, y0 / fr->h_pt, x1 / fr->w_pt,
            y1 / fr->h_pt, fill, style);
}

/* The scale bar: two segments, black and white, "0  L/2  L" above and
 * the unit beside, the CRS's name below. */
typedef struct scalebar {
    double len_m, len_pt, w, h;
    char lab[3][24], unit[4];
} scalebar;

static void scalebar_size(scalebar *s, const view *v, const place *p, const char *crs_name,
                          double fs)
{
    double wm = (v->xhi - v->xlo) * 1000, name_w;
    s->len_m = nice_length(0.25 * wm);
    s->len_pt = s->len_m / wm * (p->fx1 - p->fx0);
    int km = s->len_m >= 1000;
    double u = km ? s->len_m / 1000 : s->len_m;
    snprintf(s->unit, sizeof s->unit, "%s", km ? "km" : "m");
    snprintf(s->lab[0], sizeof s->lab[0], "0");
    snprintf(s->lab[1], sizeof s->lab[1], "%g", u / 2);
    snprintf(s->lab[2], sizeof s->lab[2], "%g", u);
    /* the middle label where it keeps clear of its neighbours */
    if (s->len_pt / 2 < (0.5 * dfle_gp_text_em(s->lab[1]) + 0.5 * dfle_gp_text_em(s->lab[2]) +
                         0.6) * fs)
        s->lab[1][0] = '\0';
    name_w = crs_name[0] != '\0' ? 0.85 * dfle_gp_text_em(crs_name) * fs : 0;
    s->w = fmax(s->len_pt + (0.5 * dfle_gp_text_em(s->lab[2]) + 0.4 +
                             dfle_gp_text_em(s->unit)) * fs, name_w) + 1.2 * fs;
    s->h = (0.5 + 1.1 + 0.45 + 0.5) * fs + (crs_name[0] != '\0' ? 1.1 * fs : 0);
}

static void put_scalebar(FILE *f, const scalebar *s, const double b[4], const place *p,
                         const char *crs_name, int backing, const dfle_gp_frame *fr)
{
    const double fs = fr->font_pt;
    double x = p->fx0 + b[0] * (p->fx1 - p->fx0), y = p->fy0 + b[2] * (p->fy1 - p->fy0);
    double bx = x + 0.6 * fs, by = y + 0.5 * fs + (crs_name[0] != '\0' ? 1.1 * fs : 0);
    if (backing)
        rect(f, 300, x, y, x + s->w, y + s->h, "#ffffff", "fs transparent solid 0.8 noborder", fr);
    rect(f, 301, bx, by, bx + s->len_pt / 2, by + 0.45 * fs, "#000000",
         "fs solid 1.0 border lc rgb '#000000' lw 1", fr);
    rect(f, 302, bx + s->len_pt / 2, by, bx + s->len_pt, by + 0.45 * fs, "#ffffff",
         "fs solid 1.0 border lc rgb '#000000' lw 1", fr);
    for (int k = 0; k < 3; k++)
        if (s->lab[k][0] != '\0')
            label_at(f, 303 + k, s->lab[k], bx + s->len_pt * k / 2.0, by + 0.45 * fs + 0.65 * fs,
                     "center", 1, 1, fr);
    label_at(f, 306, s->unit, bx + s->len_pt + (0.5 * dfle_gp_text_em(s->lab[2]) + 0.4) * fs,
             by + 0.225 * fs, "left", 1, 1, fr);
    if (crs_name[0] != '\0')
        label_at(f, 307, crs_name, bx, y + 0.5 * fs + 0.45 * fs, "left", 0.85, 1, fr);
}

/* The north arrow: an arrow to the top of the grid with N above it. */
static void put_north(FILE *f, const double b[4], const place *p, int backing,
                      const dfle_gp_frame *fr)
{
    const double fs = fr->font_pt, W = fr->w_pt, H = fr->h_pt;
    double x = p->fx0 + b[0] * (p->fx1 - p->fx0), y = p->fy0 + b[2] * (p->fy1 - p->fy0);
    double cx = x + 1.2 * fs;
    if (backing)
        rect(f, 310, x, y, x + 2.4 * fs, y + 4.2 * fs, "#ffffff",
             "fs transparent solid 0.8 noborder", fr);
    fprintf(f, "set arrow 311 from screen %.5f, screen %.5f to screen %.5f, screen %.5f head "
            "filled size screen %.5f,24 lw 2.5 lc rgb '#000000' front\n", cx / W,
            (y + 0.4 * fs) / H, cx / W, (y + 2.9 * fs) / H, 1.1 * fs / W);
    label_at(f, 312, "{/:Bold N}", cx, y + 3.5 * fs, "center", 1, 0, fr);
}

int dfle_plot_hillshade(const char *path, const dfle_plot_map *map, dfle_error *err)
{
    return dfle_plot_map_draw(path, NULL, map, err);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The points' colour range: the caller's, or the 2nd to 98th
 * percentile of the finite values (positive on a log scale). */
static int value_range(const dfle_plot_map_points *pt, const dfle_plot_axis *c, int log,
                       double *lo, double *hi, dfle_error *err)
{
    double *v = malloc((pt->n ? pt->n : 1) * sizeof *v);
    size_t k = 0;
    if (v == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "plot: out of memory");
    for (size_t i = 0; i < pt->n; i++)
        if (isfinite(pt->value[i]) && (!log || pt->value[i] > 0))
            v[k++] = pt->value[i];
    if (k == 0) {
        free(v);
        return dfle_error_set(err, DFLE_EINVAL, "plot: no point of the map has a finite value%s",
                              log ? " > 0 (log colour scale)" : "");
    }
    qsort(v, k, sizeof *v, cmp_double);
    *lo = v[(size_t)floor(0.02 * (double)(k - 1))];
    *hi = v[(size_t)ceil(0.98 * (double)(k - 1))];
    free(v);
    if (c->has_lo)
        *lo = c->lo;
    if (c->has_hi)
        *hi = c->hi;
    if (!(*hi > *lo))
        *hi = *lo + (log ? *lo : fmax(fabs(*lo) * 0.1, 1));
    return DFLE_OK;
}

/* Margins, frame and page for the map's proportions, the y ticks (which
 * set the left margin) and the colour box's ticks for the frame's
 * height.  A side of the page the caller gave is kept; the others shrink
 * to the frame, with a default page of at most 16 x 16 cm, or a height of
 * at most 1.6 times a given width. */
static void lay_out(place *p, dfle_gp_frame *fr, int fixed_w, int fixed_h, const view *v,
                    int title_lines, const char *cb_label, dfle_gp_axis *ya,
                    dfle_gp_axis *ca, const dfle_plot_axis *cuser, double key_below,
                    double min_w)
{
    const double fs = fr->font_pt, aspect = (v->yhi - v->ylo) / (v->xhi - v->xlo);
    const double W = fr->w_pt, H = fixed_h ? fr->h_pt : fixed_w ? 1.6 * W : 16 / 2.54 * 72;
    double top = title_lines > 0 ? (1.15 + 1.25 * title_lines) * fs : 0.9 * fs;
    double bottom = (1.25 + 1.3 + 0.45 + 1.2) * fs + key_below, fh = 0.6 * W, fw = 0;
    double left = 0, right = 0;
    for (int pass = 0; pass < 2; pass++) {
        dfle_gp_axis_ticks(ya, fh, fs, 1, NULL);
        left = (0.5 + 1.5 + 0.7 + 0.3) * fs + ya->max_em * fs;
        dfle_gp_axis_ticks(ca, fh, fs, 1, cuser);
        right = (cb_label != NULL ? 1.6 * fs : 0) + ca->max_em * fs + 0.6 * fs + 1.1 * fs +
                1.0 * fs + 0.5 * fs;
        fw = fmin(W - left - right, (H - top - bottom) / aspect);
        fh = fw * aspect;
    }
    if (!fixed_w) /* as wide as the frame, or the title or legend if wider */
        fr->w_pt = fmax(left + fw + right, min_w);
    if (!fixed_h)
        fr->h_pt = top + fh + bottom;
    p->fx0 = left + (fr->w_pt - left - right - fw) / 2;
    p->fx1 = p->fx0 + fw;
    p->cb_x = p->fx1 + 1.0 * fs;
    p->fy0 = bottom + (fr->h_pt - top - bottom - fh) / 2;
    p->fy1 = p->fy0 + fh;
    p->key_below = key_below;
}

/* title in two lines (into buf), broken at the ": ", ", " or space
 * nearest its middle; returns the wider line's width [em]. */
static double wrap_title(const char *title, char *buf, size_t cap)
{
    static const char *const seps[] = {": ", ", ", " "};
    size_t len = strlen(title), best = 0;
    double bd = HUGE_VAL, em0, em1;
    snprintf(buf, cap, "%s", title);
    if (len >= cap)
        return dfle_gp_text_em(buf);
    for (int k = 0; k < 3 && best == 0; k++) {
        size_t sl = strlen(seps[k]);
        for (const char *q = strstr(title, seps[k]); q != NULL; q = strstr(q + 1, seps[k])) {
            double d = fabs((double)(q - title) - (double)len / 2);
            /* the break is the separator's space (": " keeps its colon) */
            if (d < bd && d < 0.3 * (double)len)
                bd = d, best = (size_t)(q - title) + sl - 1;
        }
    }
    if (best == 0)
        return dfle_gp_text_em(buf);
    buf[best] = '\n';
    {
        char first[600];
        snprintf(first, sizeof first, "%.*s", (int)best, buf);
        em0 = dfle_gp_text_em(first);
        em1 = dfle_gp_text_em(buf + best + 1);
    }
    return fmax(em0, em1);
}

/* A legend entry's colour and text; n of them. */
typedef struct entry {
    const char *rgb, *text;
} entry;

static void put_legend(FILE *f, const entry *e, size_t n, double x, double y, double w, double h,
                       int boxed, const dfle_gp_frame *fr)
{
    const double fs = fr->font_pt, W = fr->w_pt, H = fr->h_pt;
    if (boxed)
        rect(f, 320, x, y - h, x + w, y, "#ffffff",
             "fs solid 1.0 border lc rgb '#b0b0b0' lw 1.2", fr);
    x += 0.5 * fs;
    y -= 0.5 * fs;
    for (size_t k = 0; k < n; k++) {
        double yy = boxed ? y - ((double)k + 0.5) * 1.35 * fs : y - 0.5 * 1.35 * fs;
        double xx = boxed ? x : x + (double)k * w / (double)n;
        fprintf(f, "set arrow %zu from screen %.5f, screen %.5f to screen %.5f, screen %.5f "
                "nohead lw 5 lc rgb '%s' front\n", 321 + 2 * k, xx / W, yy / H,
                (xx + 2.4 * fs) / W, yy / H, e[k].rgb);
        label_at(f, (int)(322 + 2 * k), e[k].text, xx + 3.0 * fs, yy, "left", 1, 0, fr);
    }
}

int dfle_plot_map_draw(const char *path, const dfle_plot_opts *opts, const dfle_plot_map *m,
                       dfle_error *err)
{
    static const dfle_plot_opts none = {0};
    const dfle_plot_opts *o = opts != NULL ? opts : &none;
    const dfle_plot_map_points *pt = m != NULL ? m->points : NULL;
    dfle_gp_frame fr;
    dfle_gp_axis xa, ya, ca;
    dfle_plot_axis box_x = {0}, box_y = {0};
    view v;
    place p;
    scalebar sb;
    entry ent[2];
    size_t nent = 0;
    char code[64], name[160], xl[160], yl[160];
    const char *title, *cb_label;
    double fs, lo = 0, hi = 1, kw = 0, kh = 0, in, cov, b[4], min_w = 0;
    char tbuf[600];
    int tl;
    int rc, logc = pt != NULL && o->c.log > 0, fixed_w = o->width > 0, fixed_h = o->height > 0;
    int leg = -1, sc, no;
    unsigned used = 0;
    dfle_gp_run r;

    if ((rc = dfle_gp_frame_of(path, o, 16, 12, &fr, err)) < 0)
        return rc;
    if (m == NULL || m->z == NULL || m->nx < 2 || m->ny < 2 || !(m->dx > 0) || !(m->dy > 0) ||
        !isfinite(m->x0) || !isfinite(m->y0) || !isfinite(m->dx) || !isfinite(m->dy))
        return dfle_error_set(err, DFLE_EINVAL, "plot: a map needs at least 2 x 2 cells of "
                              "finite, positive size and elevations");
    if (pt != NULL && (pt->n == 0 || pt->x == NULL || pt->y == NULL || pt->value == NULL))
        return dfle_error_set(err, DFLE_EINVAL, "plot: the map's points need x, y and a value "
                              "each (n = %zu)", pt->n);
    fs = fr.font_pt;
    memset(&v, 0, sizeof v);
    v.zmin = HUGE_VAL, v.zmax = -HUGE_VAL;
    v.r0 = m->ny, v.c0 = m->nx;
    for (size_t i = 0; i < m->nx * m->ny; i++)
        if (!isnan(m->z[i])) {
            size_t rr = i / m->nx, cc = i % m->nx;
            v.zmin = fmin(v.zmin, m->z[i]);
            v.zmax = fmax(v.zmax, m->z[i]);
            v.r0 = rr < v.r0 ? rr : v.r0, v.r1 = rr > v.r1 ? rr : v.r1;
            v.c0 = cc < v.c0 ? cc : v.c0, v.c1 = cc > v.c1 ? cc : v.c1;
        }
    if (v.zmin > v.zmax)
        return dfle_error_set(err, DFLE_EINVAL, "plot: every cell of the map is NoData");
    v.step = 1;
    while ((m->nx / v.step) * (m->ny / v.step) > MAX_CELLS)
        v.step++;
    /* The map frames the data: the box of the cells with elevations. */
    v.xlo = (m->x0 + (double)v.c0 * m->dx) / 1000, v.xhi = (m->x0 + (double)(v.c1 + 1) * m->dx) / 1000;
    v.ylo = (m->y0 - (double)(v.r1 + 1) * m->dy) / 1000, v.yhi = (m->y0 - (double)v.r0 * m->dy) / 1000;
    if ((rc = dfle_gp_crs_names(m->crs, code, sizeof code, name, sizeof name, err)) < 0)
        return rc;
    if (pt != NULL && (rc = value_range(pt, &o->c, logc, &lo, &hi, err)) < 0)
        return rc;

    if (o->x.label != NULL)
        snprintf(xl, sizeof xl, "%s", o->x.label);
    else if (m->crs == NULL || m->crs[0] == '\0')
        snprintf(xl, sizeof xl, "{/:Italic x} (km)");
    else
        snprintf(xl, sizeof xl, "Easting (km%s%s)", code[0] ? ", " : "", code);
    if (o->y.label != NULL)
        snprintf(yl, sizeof yl, "%s", o->y.label);
    else if (m->crs == NULL || m->crs[0] == '\0')
        snprintf(yl, sizeof yl, "{/:Italic y} (km)");
    else
        snprintf(yl, sizeof yl, "Northing (km%s%s)", code[0] ? ", " : "", code);
    title = o->title != NULL ? o->title : m->title;
    tl = title != NULL;
    cb_label = pt != NULL ? o->c.label : o->c.label != NULL ? o->c.label : "Elevation (m)";

    box_x = (dfle_plot_axis){.has_lo = 1, .lo = v.xlo, .has_hi = 1, .hi = v.xhi};
    box_y = (dfle_plot_axis){.has_lo = 1, .lo = v.ylo, .has_hi = 1, .hi = v.yhi};
    dfle_gp_axis_range(&xa, 0, v.xlo, v.xhi, 0, &box_x);
    dfle_gp_axis_range(&ya, 0, v.ylo, v.yhi, 0, &box_y);
    if (pt != NULL)
        dfle_gp_axis_range(&ca, logc, lo, hi, 0, NULL);
    else
        dfle_gp_axis_range(&ca, 0, v.zmin, v.zmax > v.zmin ? v.zmax : v.zmin + 1, 0, NULL);

    /* Reach is painted over channels, so the channel colour shows only
     * where no debris flow goes: no legend entry for a colour the map
     * does not show (every channel reached). */
    {
        int channel_seen = 0;
        for (size_t i = 0; m->channel != NULL && !channel_seen && i < m->nx * m->ny; i++)
            channel_seen = m->channel[i] > 0 && !(m->reach != NULL && m->reach[i] > 0);
        if (channel_seen)
            ent[nent++] = (entry){CHANNEL_RGB, m->channel_label != NULL ? m->channel_label
                                  : m->reach != NULL ? "Channels beyond the debris-flow reach"
                                                     : "Channel network"};
        if (m->reach != NULL)
            ent[nent++] = (entry){DFLE_GP_FIT, m->reach_label != NULL ? m->reach_label
                                                                       : "Debris-flow reach"};
    }
    lay_out(&p, &fr, fixed_w, fixed_h, &v, tl, cb_label, &ya, &ca, &o->c, 0, min_w);
    if (title != NULL && dfle_gp_text_em(title) * fs > fr.w_pt - 2 * fs) {
        /* a title wider than the map: two lines, the page as wide as they need */
        min_w = (wrap_title(title, tbuf, sizeof tbuf) + 2) * fs;
        title = tbuf, tl = 2;
        lay_out(&p, &fr, fixed_w, fixed_h, &v, tl, cb_label, &ya, &ca, &o->c, 0, min_w);
    }
    in = 0.35 * fs;
    if (nent > 0) {
        double em = 0;
        for (size_t k = 0; k < nent; k++)
            em = fmax(em, dfle_gp_text_em(ent[k].text));
        kw = (1.0 + 3.0 + em) * fs;
        kh = (1.0 + (double)nent * 1.35 - 0.3) * fs;
        leg = best_corner(m, &v, &p, 0xF, &used, kw, kh, in, &cov);
        if (cov > 0.01 || kw > 0.6 * (p.fx1 - p.fx0) || kh > 0.45 * (p.fy1 - p.fy0)) {
            /* below the frame, in one row (the page at least as wide) */
            used = 0, leg = -1;
            lay_out(&p, &fr, fixed_w, fixed_h, &v, tl, cb_label, &ya, &ca, &o->c,
                    1.35 * fs + 0.9 * fs,
                    fmax(min_w, (double)nent * kw + (double)(nent - 1) * fs + 2 * fs));
        }
    }
    scalebar_size(&sb, &v, &p, name, fs);
    if ((sc = best_corner(m, &v, &p, 0xC, &used, sb.w, sb.h, in, &cov)) < 0)
        sc = best_corner(m, &v, &p, 0xF, &used, sb.w, sb.h, in, &cov);
    int sc_back = cov > 0;
    if ((no = best_corner(m, &v, &p, 0x3, &used, 2.4 * fs, 4.2 * fs, in, &cov)) < 0)
        no = best_corner(m, &v, &p, 0xF, &used, 2.4 * fs, 4.2 * fs, in, &cov);
    int no_back = cov > 0;
    if (fr.w_pt > 200 / 2.54 * 72 || fr.h_pt > 200 / 2.54 * 72 ||
        (fr.fmt == FMT_PNG && fmax(fr.w_pt, fr.h_pt) / 72 * fr.dpi > 20000))
        return dfle_error_set(err, DFLE_EINVAL, "plot: the map's page (%.3g x %.3g cm at %g dpi) "
                              "is over 200 cm or 20000 px a side", fr.w_pt / 72 * 2.54,
                              fr.h_pt / 72 * 2.54, fr.dpi);
    if (p.fx1 - p.fx0 < 4 * fs || p.fy1 - p.fy0 < 3 * fs)
        return dfle_error_set(err, DFLE_EINVAL, "plot: a %.3g x %.3g km map does not fit a "
                              "%.3g cm wide page at a %g pt font", v.xhi - v.xlo, v.yhi - v.ylo,
                              fr.w_pt / 72 * 2.54, fs);
    dfle_gp_axis_ticks(&xa, p.fx1 - p.fx0, fs, 0, NULL);

    if ((rc = dfle_gp_begin_frame(&r, path, &fr, err)) < 0)
        return rc;
    /* One packed RGB value per cell (0xRRGGBB), a matrix datablock; under
     * points the relief is grey, so that the colours are the points'. */
    {
        size_t cols_img = (m->nx + v.step - 1) / v.step, rows_img = (m->ny + v.step - 1) / v.step;
        fputs("$img << EOD\n", r.f);
        for (size_t rr = 0; rr < rows_img; rr++) {
            for (size_t cc = 0; cc < cols_img; cc++) {
                size_t i = rr * v.step * m->nx + cc * v.step;
                unsigned rgb = 0xffffff;
                if (!isnan(m->z[i])) {
                    double fz = v.zmax > v.zmin ? (m->z[i] - v.zmin) / (v.zmax - v.zmin) : 0.5;
                    double sh = shade_at(m, rr * v.step, cc * v.step, v.step);
                    unsigned R, G, B;
                    if (pt != NULL) {
                        R = G = B = (unsigned)(255 * (0.42 + 0.5 * sh));
                    } else {
                        sh = 0.35 + 0.65 * sh;
                        R = (unsigned)(tint_channel(fz, 16) * sh);
                        G = (unsigned)(tint_channel(fz, 8) * sh);
                        B = (unsigned)(tint_channel(fz, 0) * sh);
                    }
                    if (m->channel != NULL && m->channel[i] > 0) R = 0x00, G = 0x72, B = 0xB2;
                    if (m->reach != NULL && m->reach[i] > 0) R = 0xD5, G = 0x5E, B = 0x00;
                    rgb = (R << 16) | (G << 8) | B;
                }
                fprintf(r.f, "%s%u", cc ? " " : "", rgb);
            }
            fputs("\n", r.f);
        }
        fputs("EOD\n", r.f);
    }
    if (pt != NULL) {
        /* small points first, so the trunk's lie on top */
        double smin = HUGE_VAL, smax = -HUGE_VAL, cell = (p.fx1 - p.fx0) / ((v.xhi - v.xlo) * 1000 / m->dx);
        double lo_pt = fmin(3.0, fmax(1.0, 0.9 * cell)), hi_pt = fmin(6.0, fmax(2.5, 2.2 * cell));
        double *key = malloc(pt->n * 2 * sizeof *key);
        if (key == NULL) {
            dfle_gp_end(&r, NULL);
            return dfle_error_set(err, DFLE_ENOMEM, "plot: out of memory");
        }
        for (size_t i = 0; i < pt->n; i++)
            if (pt->size != NULL && pt->size[i] > 0 && isfinite(pt->size[i])) {
                smin = fmin(smin, log(pt->size[i]));
                smax = fmax(smax, log(pt->size[i]));
            }
        for (size_t i = 0; i < pt->n; i++) {
            double s = pt->size != NULL && pt->size[i] > 0 && isfinite(pt->size[i]) &&
                               smax > smin
                           ? (log(pt->size[i]) - smin) / (smax - smin) : 0.5;
            key[2 * i] = s, key[2 * i + 1] = (double)i;
        }
        qsort(key, pt->n, 2 * sizeof *key, cmp_double);
        fputs("$pts << EOD\n", r.f);
        for (size_t k = 0; k < pt->n; k++) {
            size_t i = (size_t)key[2 * k + 1];
            double val = pt->value[i];
            if (!isfinite(val) || (logc && !(val > 0)) || !isfinite(pt->x[i]) || !isfinite(pt->y[i]))
                continue;
            fprintf(r.f, "%.10g %.10g %.10g %.4g\n", pt->x[i] / 1000, pt->y[i] / 1000, val,
                    dfle_gp_ps(&fr, lo_pt + key[2 * k] * (hi_pt - lo_pt)));
        }
        fputs("EOD\n", r.f);
        free(key);
    } else {
        /* A 2 x 2 image off the map gives the colour box its scale. */
        double fx = m->x0 / 1000 - 1e6, fy = m->y0 / 1000 + 1e6;
        fprintf(r.f, "$cb << EOD\n%.17g %.17g %.17g\n%.17g %.17g %.17g\n\n%.17g %.17g %.17g\n"
                "%.17g %.17g %.17g\nEOD\n", fx, fy, v.zmin, fx + 1, fy, v.zmax, fx, fy + 1, v.zmin,
                fx + 1, fy + 1, v.zmax);
    }
    fprintf(r.f, "set lmargin at screen %.5f\nset rmargin at screen %.5f\n"
            "set tmargin at screen %.5f\nset bmargin at screen %.5f\nunset key\n",
            p.fx0 / fr.w_pt, p.fx1 / fr.w_pt, p.fy1 / fr.h_pt, p.fy0 / fr.h_pt);
    fputs("set xtics out nomirror\nset ytics out nomirror\nunset grid\n", r.f);
    dfle_gp_axis_put(r.f, "x", &xa, 1);
    dfle_gp_axis_put(r.f, "y", &ya, 1);
    ca.nminor = 0;
    dfle_gp_axis_put(r.f, "cb", &ca, 1);
    if (pt != NULL)
        fputs("set palette defined (" VIRIDIS ")\n", r.f);
    else {
        fputs("set palette defined (", r.f);
        for (int k = 0; k < 5; k++)
            fprintf(r.f, "%s%g '#%06x'", k ? ", " : "", tint_at[k], tint_rgb[k]);
        fputs(")\n", r.f);
    }
    fprintf(r.f, "set colorbox user origin screen %.5f, screen %.5f size screen %.5f, screen %.5f "
            "front bdefault\n", p.cb_x / fr.w_pt, p.fy0 / fr.h_pt, 1.1 * fs / fr.w_pt,
            (p.fy1 - p.fy0) / fr.h_pt);
    {
        double lx = p.fx0 - (3.0 + ya.max_em) * fs + 1.1 * fs;
        if (title != NULL)
            dfle_gp_page_label(r.f, 100, title, (p.fx0 + p.fx1) / 2, fr.h_pt - 1.25 * fs, 0, 0, &fr);
        dfle_gp_page_label(r.f, 101, xl, (p.fx0 + p.fx1) / 2, p.key_below + 0.95 * fs, 0, 0, &fr);
        dfle_gp_page_label(r.f, 102, yl, lx, (p.fy0 + p.fy1) / 2, 90, 0, &fr);
        if (cb_label != NULL)
            dfle_gp_page_label(r.f, 103, cb_label,
                               p.cb_x + (1.1 + 0.6 + ca.max_em + 0.9) * fs,
                               (p.fy0 + p.fy1) / 2, 90, 0, &fr);
    }
    if (sc >= 0) {
        corner_box(&p, sc, sb.w, sb.h, in, b);
        put_scalebar(r.f, &sb, b, &p, name, sc_back, &fr);
    }
    if (no >= 0) {
        corner_box(&p, no, 2.4 * fs, 4.2 * fs, in, b);
        put_north(r.f, b, &p, no_back, &fr);
    }
    if (nent > 0 && leg >= 0) {
        corner_box(&p, leg, kw, kh, in, b);
        put_legend(r.f, ent, nent, p.fx0 + b[0] * (p.fx1 - p.fx0),
                   p.fy0 + b[3] * (p.fy1 - p.fy0), kw, kh, 1, &fr);
    } else if (nent > 0) {
        double w = (double)nent * (kw - 1.0 * fs) + (double)(nent - 1) * fs;
        put_legend(r.f, ent, nent, (p.fx0 + p.fx1) / 2 - w / 2 - 0.5 * fs,
                   p.key_below + 0.25 * fs, w + fs, 0, 0, &fr);
    }
    /* Cell centres in km: column c at x0 + (c + 0.5) dx (every step-th). */
    fprintf(r.f, "plot $img matrix using (%.17g + ($1 + 0.5) * %.17g):(%.17g - ($2 + 0.5) * "
            "%.17g):(int($3) >> 16 & 255):(int($3) >> 8 & 255):(int($3) & 255) with rgbimage "
            "notitle", m->x0 / 1000, m->dx * (double)v.step / 1000, m->y0 / 1000,
            m->dy * (double)v.step / 1000);
    if (pt != NULL)
        fputs(", $pts using 1:2:4:3 with points pt 7 ps variable lc palette notitle\n", r.f);
    else
        fputs(", $cb using 1:2:3 with image notitle\n", r.f);
    return dfle_gp_end(&r, err);
}
