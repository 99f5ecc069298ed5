/*
 * plot_opts.c - the options every figure shares (dfle_plot_opts), in one
 * place: the names a script may use (legend positions, units, styles,
 * dashes, markers, colours), their checks, the page a figure is drawn
 * on, the look of each series, and the house labels of quantities.
 *
 * The names are parsed here rather than in the Lua binding so that any
 * binding, and C callers, get the same vocabulary and the same messages.
 * Messages name an option as the Lua options table does ("xrange",
 * "size", "legend"), since that is where most users meet them.
 */
#include "io/plot_internal.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Okabe-Ito (Okabe and Ito 2008), ordered so that the first colours of
 * a figure differ most: blue and sky blue, the closest pair, are first
 * and last. */
const char *const dfle_gp_palette[DFLE_GP_NPALETTE] = {
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#000000", "#56B4E9"};

typedef struct named {
    const char *name;
    int value;
} named;

/* The value of s in table t (n entries), or DFLE_EINVAL naming `what`
 * and listing the names. */
static int lookup(const named *t, size_t n, const char *s, const char *what, const char *kind,
                  dfle_error *err)
{
    char list[400] = "";
    for (size_t i = 0; s != NULL && i < n; i++)
        if (strcmp(s, t[i].name) == 0)
            return t[i].value;
    for (size_t i = 0; i < n; i++) {
        size_t used = strlen(list);
        snprintf(list + used, sizeof list - used, "%s'%s'", i ? ", " : "", t[i].name);
    }
    return dfle_error_set(err, DFLE_EINVAL, "plot: %s '%s' is not a %s (use one of %s)", what,
                          s != NULL ? s : "(null)", kind, list);
}

#define LOOKUP(t, s, what, kind, err) lookup(t, sizeof t / sizeof t[0], s, what, kind, err)

int dfle_plot_parse_legend(const char *s, const char *what, dfle_error *err)
{
    static const named t[] = {
        {"auto", DFLE_LEGEND_AUTO},           {"none", DFLE_LEGEND_NONE},
        {"top left", DFLE_LEGEND_TOP_LEFT},   {"top right", DFLE_LEGEND_TOP_RIGHT},
        {"bottom left", DFLE_LEGEND_BOTTOM_LEFT}, {"bottom right", DFLE_LEGEND_BOTTOM_RIGHT},
        {"top", DFLE_LEGEND_TOP},             {"bottom", DFLE_LEGEND_BOTTOM},
        {"left", DFLE_LEGEND_LEFT},           {"right", DFLE_LEGEND_RIGHT},
        {"outside right", DFLE_LEGEND_OUTSIDE_RIGHT}, {"below", DFLE_LEGEND_BELOW}};
    return LOOKUP(t, s, what, "legend position", err);
}

int dfle_plot_parse_unit(const char *s, const char *what, dfle_error *err)
{
    static const named t[] = {{"cm", DFLE_PLOT_CM}, {"in", DFLE_PLOT_IN}, {"px", DFLE_PLOT_PX}};
    return LOOKUP(t, s, what, "unit of size", err);
}

int dfle_plot_parse_style(const char *s, const char *what, dfle_error *err)
{
    static const named t[] = {{"points", DFLE_PLOT_POINTS}, {"lines", DFLE_PLOT_LINES},
                              {"linespoints", DFLE_PLOT_LINESPOINTS}};
    return LOOKUP(t, s, what, "style", err);
}

int dfle_plot_parse_dash(const char *s, const char *what, dfle_error *err)
{
    static const named t[] = {{"solid", DFLE_DASH_SOLID}, {"dash", DFLE_DASH_DASH},
                              {"dot", DFLE_DASH_DOT}, {"dashdot", DFLE_DASH_DASHDOT},
                              {"dashdotdot", DFLE_DASH_DASHDOTDOT}};
    return LOOKUP(t, s, what, "dash pattern", err);
}

static const named markers[] = {
    {"circle", DFLE_MARKER_CIRCLE},
    {"square", DFLE_MARKER_SQUARE},
    {"triangle", DFLE_MARKER_TRIANGLE},
    {"down triangle", DFLE_MARKER_DOWN_TRIANGLE},
    {"diamond", DFLE_MARKER_DIAMOND},
    {"open circle", DFLE_MARKER_OPEN_CIRCLE},
    {"open square", DFLE_MARKER_OPEN_SQUARE},
    {"open triangle", DFLE_MARKER_OPEN_TRIANGLE},
    {"open down triangle", DFLE_MARKER_OPEN_DOWN_TRIANGLE},
    {"open diamond", DFLE_MARKER_OPEN_DIAMOND},
    {"plus", DFLE_MARKER_PLUS},
    {"cross", DFLE_MARKER_CROSS},
    {"star", DFLE_MARKER_STAR}};

int dfle_plot_parse_marker(const char *s, const char *what, dfle_error *err)
{
    return LOOKUP(markers, s, what, "marker", err);
}

/* gnuplot's point type of a marker (the cairo and svg terminals agree). */
static int point_type(int marker)
{
    static const int pt[] = {7, 7, 5, 9, 11, 13, 6, 4, 8, 10, 12, 1, 2, 3};
    return marker >= 0 && marker < (int)(sizeof pt / sizeof pt[0]) ? pt[marker] : 7;
}

int dfle_plot_colour(const char *s, const char *what, char out[8], dfle_error *err)
{
    static const struct {
        const char *name, *rgb;
    } t[] = {{"black", "#000000"},   {"orange", "#E69F00"}, {"sky blue", "#56B4E9"},
             {"green", "#009E73"},   {"yellow", "#F0E442"}, {"blue", "#0072B2"},
             {"vermillion", "#D55E00"}, {"purple", "#CC79A7"}, {"grey", "#999999"},
             {"gray", "#999999"}};
    size_t i;
    if (s != NULL && s[0] == '#' && strlen(s) == 7) {
        for (i = 1; i < 7 && isxdigit((unsigned char)s[i]); i++) {}
        if (i == 7) {
            memcpy(out, s, 8);
            return DFLE_OK;
        }
    }
    for (i = 0; s != NULL && i < sizeof t / sizeof t[0]; i++)
        if (strcmp(s, t[i].name) == 0) {
            memcpy(out, t[i].rgb, 8);
            return DFLE_OK;
        }
    return dfle_error_set(err, DFLE_EINVAL, "plot: %s '%s' is not a colour (use \"#rrggbb\" "
                          "or one of black, orange, sky blue, green, yellow, blue, "
                          "vermillion, purple, grey)", what, s != NULL ? s : "(null)");
}

/* The house labels: "Name, symbol (unit)", symbols italic, Greek
 * upright; rates in mm/yr, which reads better than 0.0005 m/yr. */
static const struct {
    const char *name, *label;
    double factor;
} labels[] = {
    {"x", "Distance from channel head, {/:Italic x} (m)", 1},
    {"z", "Elevation, {/:Italic z} (m)", 1},
    {"A", "Drainage area, {/:Italic A} (m^2)", 1},
    {"S", "Slope, {/:Italic S} (m/m)", 1},
    {"U", "Uplift rate, {/:Italic U} (mm/yr)", 1e3},
    {"E_f", "Fluvial erosion rate, {/:Italic E}_f (mm/yr)", 1e3},
    {"E_df", "Debris-flow erosion rate, {/:Italic E}_{df} (mm/yr)", 1e3},
    {"h", "Flow depth, {/:Italic h} (m)", 1},
    {"t", "Time, {/:Italic t} (kyr)", 1e-3},
    {"S_df", "Debris-flow slope, {/:Italic S}_{df} (m/m)", 1},
    {"A_df", "Transition area, {/:Italic A}_{df} (m^2)", 1},
    {"a2", "Exponent of Eq. (2), {/:Italic a}_2", 1},
    {"r2", "{/:Italic R}^2 of the Eq. (2) fit", 1},
    {"S_max_minus_S_ch", "{/:Italic S}_{max} − {/:Italic S}_{ch} (m/m)", 1},
    {"k_df", "Debris-flow erodibility, {/:Italic k}_{df} (m^{1−β} s^{−1} yr^{−1})", 1},
    {"k_e", "Fluvial erodibility, {/:Italic k}_e (m^{2.5} s^2 kg^{−1.5})", 1},
    {"M0", "Flow volume, {/:Italic M}_0 (m^3)", 1},
    {"gamma", "Volume-area exponent, γ", 1},
    {"mu", "Flow viscosity, μ (Pa s)", 1},
    {"tau_y", "Yield strength, τ_y (Pa)", 1},
    {"alpha", "Slope exponent, α", 1},
    {"beta", "Depth exponent, β", 1},
    {"D", "Pore-pressure diffusivity, {/:Italic D} (m^2/s)", 1},
    {"eta", "Pore-fluid viscosity, η (Pa s)", 1},
    {"mu2", "Limiting friction coefficient, μ_2", 1},
    {"sigma", "Noise scale, σ (in ln {/:Italic S})", 1},
};

const char *dfle_plot_label(const char *name, double *factor)
{
    for (size_t i = 0; name != NULL && i < sizeof labels / sizeof labels[0]; i++)
        if (strcmp(name, labels[i].name) == 0) {
            if (factor != NULL)
                *factor = labels[i].factor;
            return labels[i].label;
        }
    return NULL;
}

const char *dfle_plot_label_name(size_t i)
{
    return i < sizeof labels / sizeof labels[0] ? labels[i].name : NULL;
}

/* "x", "y" or "c" and a suffix: the option's name in messages. */
static const char *opt_name(char axis, const char *suffix, char *buf, size_t cap)
{
    snprintf(buf, cap, "%c%s", axis, suffix);
    return buf;
}

int dfle_gp_axis_ok(char name, const dfle_plot_axis *u, int log, dfle_error *err)
{
    char nm[16];
    opt_name(name, "range", nm, sizeof nm);
    if ((u->has_lo && !isfinite(u->lo)) || (u->has_hi && !isfinite(u->hi)))
        return dfle_error_set(err, DFLE_EINVAL, "plot: %s must be finite (got %g .. %g)", nm,
                              u->has_lo ? u->lo : NAN, u->has_hi ? u->hi : NAN);
    if (u->has_lo && u->has_hi && !(u->lo < u->hi))
        return dfle_error_set(err, DFLE_EINVAL, "plot: %s must be increasing, {lo, hi} with "
                              "lo < hi (got %g .. %g)", nm, u->lo, u->hi);
    if (log > 0 && ((u->has_lo && u->lo <= 0) || (u->has_hi && u->hi <= 0)))
        return dfle_error_set(err, DFLE_EINVAL, "plot: %s must be > 0 on a logarithmic axis "
                              "(got %g .. %g)", nm, u->has_lo ? u->lo : NAN,
                              u->has_hi ? u->hi : NAN);
    opt_name(name, "ticks", nm, sizeof nm);
    if (!isfinite(u->step) || u->step < 0)
        return dfle_error_set(err, DFLE_EINVAL, "plot: %s spacing must be > 0 (got %g)", nm,
                              u->step);
    if (u->step > 0 && log > 0)
        return dfle_error_set(err, DFLE_EINVAL, "plot: %s: a spacing (%g) needs a linear "
                              "axis; give a logarithmic axis its ticks as a list", nm, u->step);
    if (u->nticks > DFLE_GP_MAXTICKS || (u->nticks > 0 && u->ticks == NULL))
        return dfle_error_set(err, DFLE_EINVAL, "plot: %s: at most %d ticks, as an array "
                              "(got %zu)", nm, DFLE_GP_MAXTICKS, u->nticks);
    for (size_t i = 0; i < u->nticks; i++)
        if (!isfinite(u->ticks[i]) || (log > 0 && u->ticks[i] <= 0))
            return dfle_error_set(err, DFLE_EINVAL, "plot: %s[%zu] must be a finite number%s "
                                  "(got %g)", nm, i + 1, log > 0 ? " > 0 on a logarithmic axis"
                                  : "", u->ticks[i]);
    if (u->log < -1 || u->log > 1)
        return dfle_error_set(err, DFLE_EINVAL, "plot: %s log must be -1, 0 or 1 (got %d)",
                              opt_name(name, "", nm, sizeof nm), u->log);
    if (u->format != NULL && strlen(u->format) > 40)
        return dfle_error_set(err, DFLE_EINVAL, "plot: %s is longer than 40 characters",
                              opt_name(name, "format", nm, sizeof nm));
    return DFLE_OK;
}

/* "Family,size", "Family" or ",size": family (may be empty) and size
 * (0 when not given). */
static int parse_font(const char *s, char *family, size_t cap, double *size, dfle_error *err)
{
    const char *comma = strrchr(s, ',');
    size_t flen = comma != NULL ? (size_t)(comma - s) : strlen(s);
    *size = 0;
    for (const char *p = s; *p != '\0'; p++)
        if ((unsigned char)*p < 0x20 || *p == 0x7f)
            return dfle_error_set(err, DFLE_EINVAL, "plot: font contains a control character");
    if (flen >= cap)
        return dfle_error_set(err, DFLE_EINVAL, "plot: font family '%.*s' is longer than %zu "
                              "characters", (int)flen, s, cap - 1);
    memcpy(family, s, flen);
    family[flen] = '\0';
    if (comma != NULL) {
        char *end;
        *size = strtod(comma + 1, &end);
        while (*end == ' ')
            end++;
        if (end == comma + 1 || *end != '\0' || !(*size >= 4 && *size <= 72))
            return dfle_error_set(err, DFLE_EINVAL, "plot: font '%s': the size after the comma "
                                  "must be a number of points from 4 to 72", s);
    }
    return DFLE_OK;
}

int dfle_plot_opts_check(const dfle_plot_opts *o, dfle_error *err)
{
    static const char axes[3] = {'x', 'y', 'c'};
    const dfle_plot_axis *ax[3];
    char fam[64];
    double fs;
    int rc;
    if (o == NULL)
        return DFLE_OK;
    ax[0] = &o->x, ax[1] = &o->y, ax[2] = &o->c;
    for (int k = 0; k < 3; k++)
        if ((rc = dfle_gp_axis_ok(axes[k], ax[k], ax[k]->log, err)) < 0)
            return rc;
    if (o->unit < DFLE_PLOT_CM || o->unit > DFLE_PLOT_PX)
        return dfle_error_set(err, DFLE_EINVAL, "plot: size unit %d is not cm, in or px", o->unit);
    if (!isfinite(o->width) || !isfinite(o->height) || o->width < 0 || o->height < 0)
        return dfle_error_set(err, DFLE_EINVAL, "plot: size must be positive (got %g x %g)",
                              o->width, o->height);
    if (!isfinite(o->dpi) || (o->dpi != 0 && (o->dpi < 30 || o->dpi > 2400)))
        return dfle_error_set(err, DFLE_EINVAL, "plot: dpi must be from 30 to 2400 (got %g)",
                              o->dpi);
    if (o->legend < DFLE_LEGEND_AUTO || o->legend > DFLE_LEGEND_BELOW)
        return dfle_error_set(err, DFLE_EINVAL, "plot: legend %d is not a position", o->legend);
    if (o->font != NULL && (rc = parse_font(o->font, fam, sizeof fam, &fs, err)) < 0)
        return rc;
    return DFLE_OK;
}

int dfle_plot_series_check(const dfle_plot_series *series, size_t nseries, dfle_error *err)
{
    char rgb[8], what[40];
    if (series == NULL || nseries == 0)
        return dfle_error_set(err, DFLE_EINVAL, "plot: no series to plot");
    for (size_t k = 0; k < nseries; k++) {
        const dfle_plot_series *q = &series[k];
        int band = q->lo != NULL || q->hi != NULL;
        if (q->n > 0 && (q->x == NULL || (!band && q->y == NULL) ||
                         (band && (q->lo == NULL || q->hi == NULL))))
            return dfle_error_set(err, DFLE_EINVAL, "plot: series %zu has "
                                  "NULL x or y (or only one of lo, hi)", k + 1);
        if (q->style < DFLE_PLOT_POINTS || q->style > DFLE_PLOT_LINESPOINTS ||
            q->dash < DFLE_DASH_SOLID || q->dash > DFLE_DASH_DASHDOTDOT ||
            q->marker < DFLE_MARKER_AUTO || q->marker > DFLE_MARKER_STAR)
            return dfle_error_set(err, DFLE_EINVAL, "plot: series %zu: style %d, dash %d or "
                                  "marker %d is not one of the enum's", k + 1, q->style, q->dash,
                                  q->marker);
        if (!isfinite(q->width) || q->width < 0 || q->width > 20)
            return dfle_error_set(err, DFLE_EINVAL, "plot: series %zu: width must be from 0 to "
                                  "20 pt (got %g)", k + 1, q->width);
        if (!isfinite(q->marker_size) || q->marker_size < 0 || q->marker_size > 50)
            return dfle_error_set(err, DFLE_EINVAL, "plot: series %zu: marker_size must be from 0 "
                                  "to 50 pt (got %g)", k + 1, q->marker_size);
        snprintf(what, sizeof what, "series %zu: rgb", k + 1);
        if (q->rgb != NULL && dfle_plot_colour(q->rgb, what, rgb, err) < 0)
            return DFLE_EINVAL;
    }
    return DFLE_OK;
}

int dfle_gp_frame_of(const char *path, const dfle_plot_opts *o, double w_cm, double h_cm,
                     dfle_gp_frame *fr, dfle_error *err)
{
    static const dfle_plot_opts none = {0};
    double per_unit, w, h, px_w, px_h;
    int rc;
    if (o == NULL)
        o = &none;
    memset(fr, 0, sizeof *fr);
    if ((fr->fmt = dfle_gp_format(path, err)) < 0)
        return fr->fmt;
    if ((rc = dfle_plot_opts_check(o, err)) < 0)
        return rc;
    fr->dpi = o->dpi > 0 ? o->dpi : 150;
    per_unit = o->unit == DFLE_PLOT_IN ? 72.0 : o->unit == DFLE_PLOT_PX ? 72.0 / fr->dpi
                                                                       : 72.0 / 2.54;
    /* One side given: the other keeps the figure's own proportions. */
    w = o->width > 0 ? o->width * per_unit : 0;
    h = o->height > 0 ? o->height * per_unit : 0;
    if (w == 0 && h == 0)
        w = w_cm * 72 / 2.54, h = h_cm * 72 / 2.54;
    else if (w == 0)
        w = h * w_cm / h_cm;
    else if (h == 0)
        h = w * h_cm / w_cm;
    fr->w_pt = w, fr->h_pt = h;
    px_w = w / 72 * fr->dpi, px_h = h / 72 * fr->dpi;
    if (w < 2 / 2.54 * 72 || h < 2 / 2.54 * 72 || w > 200 / 2.54 * 72 || h > 200 / 2.54 * 72)
        return dfle_error_set(err, DFLE_EINVAL, "plot: size %.3g x %.3g cm is outside 2 to "
                              "200 cm", w / 72 * 2.54, h / 72 * 2.54);
    if (fr->fmt == FMT_PNG && (px_w > 20000 || px_h > 20000))
        return dfle_error_set(err, DFLE_EINVAL, "plot: size %.0f x %.0f px at %g dpi is more "
                              "than 20000 px a side", px_w, px_h, fr->dpi);
    strcpy(fr->family, "sans");
    fr->font_pt = 9;
    if (o->font != NULL) {
        char fam[64];
        double fs;
        parse_font(o->font, fam, sizeof fam, &fs, NULL); /* checked above */
        if (fam[0] != '\0')
            strcpy(fr->family, fam);
        if (fs > 0)
            fr->font_pt = fs;
    }
    return DFLE_OK;
}

double dfle_gp_ps(const dfle_gp_frame *fr, double size_pt)
{
    /* svg's points are 3/2 of the cairo terminals' (plot_run.c) */
    return size_pt / DFLE_GP_PS_PT * (fr->fmt == FMT_SVG ? 2.0 / 3.0 : 1.0);
}

void dfle_gp_look_set(dfle_gp_look *look, int kind, const char *rgb, double lw, int dt, int pt,
                      double ps, size_t every)
{
    look->kind = kind;
    memmove(look->rgb, rgb, 8);
    look->lw = lw, look->dt = dt, look->pt = pt, look->ps = ps;
    switch (kind) {
    case DFLE_GP_BAND:
        snprintf(look->with, sizeof look->with, "filledcurves fs transparent solid 0.3 noborder");
        break;
    case DFLE_GP_LINES:
        snprintf(look->with, sizeof look->with, "lines lw %.3g dt %d", lw, dt);
        break;
    case DFLE_GP_POINTS:
        snprintf(look->with, sizeof look->with, "points pt %d ps %.3g lw %.3g", pt, ps, lw);
        break;
    case DFLE_GP_BARS:
        snprintf(look->with, sizeof look->with, "yerrorbars pt %d ps %.3g lw %.3g", pt, ps, lw);
        break;
    default:
        snprintf(look->with, sizeof look->with, "linespoints lw %.3g dt %d pt %d ps %.3g pi %zu",
                 lw, dt, pt, ps, every > 0 ? every : 1);
    }
}

void dfle_gp_look_of(const dfle_plot_series *s, size_t k, const dfle_gp_frame *fr,
                     dfle_gp_look *look)
{
    /* linespoints: a shape per series, so curves that coincide can
     * still be told apart. */
    static const int cycle[] = {DFLE_MARKER_CIRCLE, DFLE_MARKER_SQUARE, DFLE_MARKER_TRIANGLE,
                                DFLE_MARKER_DIAMOND, DFLE_MARKER_DOWN_TRIANGLE,
                                DFLE_MARKER_OPEN_CIRCLE, DFLE_MARKER_OPEN_SQUARE};
    int dash = s->dash, marker = s->marker;
    double lw = (s->width > 0 ? s->width : 1.25) / DFLE_GP_LW_PT;
    double ms = s->marker_size > 0 ? s->marker_size : s->n > 2000 ? 2.5 : 4.0;
    if (s->rgb == NULL || dfle_plot_colour(s->rgb, "rgb", look->rgb, NULL) < 0)
        memcpy(look->rgb, dfle_gp_palette[k % DFLE_GP_NPALETTE], 8);
    /* Past the palette's length the colours repeat: dashes keep the
     * second round apart from the first. */
    if (dash == DFLE_DASH_SOLID && s->rgb == NULL && k >= DFLE_GP_NPALETTE)
        dash = 1 + (int)((k / DFLE_GP_NPALETTE - 1) % 4);
    if (marker == DFLE_MARKER_AUTO && s->style == DFLE_PLOT_LINESPOINTS)
        marker = cycle[k % (sizeof cycle / sizeof cycle[0])];
    if (s->lo != NULL)
        dfle_gp_look_set(look, DFLE_GP_BAND, look->rgb, 0, 1, 0, 0, 0);
    else if (s->style == DFLE_PLOT_LINES)
        dfle_gp_look_set(look, DFLE_GP_LINES, look->rgb, lw, dash + 1, 0, 0, 0);
    else if (s->style == DFLE_PLOT_POINTS)
        dfle_gp_look_set(look, DFLE_GP_POINTS, look->rgb, 2, 1, point_type(marker),
                         dfle_gp_ps(fr, ms), 0);
    else /* about a dozen markers along a line, not a smear of them */
        dfle_gp_look_set(look, DFLE_GP_LINESPOINTS, look->rgb, lw, dash + 1, point_type(marker),
                         dfle_gp_ps(fr, ms * 1.3), s->n > 24 ? (s->n + 11) / 12 : 1);
}
