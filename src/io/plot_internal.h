/*
 * plot_internal.h - what the plot files share (not installed):
 *   plot_run.c    the gnuplot run: format, terminal, temporary image,
 *                 completeness, rename;
 *   plot_opts.c   the options' names, checks, defaults, palette, labels;
 *   plot_axes.c   ranges, ticks whose labels do not touch, numbers;
 *   plot_frame.c  layers of data, the legend's place, colour box, the
 *                 single- and multi-panel figures;
 *   plot.c        the figures: x-y, panels, slope-area, profile;
 *   plot_map.c    maps (plot_crs.c names their CRS through GDAL);
 *   plot_corner.c the corner plot; plot_sheet.c the contact sheet.
 *
 * A figure is one gnuplot run: dfle_gp_begin_frame starts gnuplot
 * writing to a temporary file beside the image and sets the terminal
 * and house style; the caller writes the script to r.f; dfle_gp_end
 * checks gnuplot's exit, the image's completeness, and renames it over
 * the target.
 *
 * Units inside: the page is measured in points (1/72 in).  A line width
 * of 1 in the script is 0.5 pt and a point size of 1 is 6 pt across, in
 * every format (the terminal line scales them).
 */
#ifndef DFLE_PLOT_INTERNAL_H
#define DFLE_PLOT_INTERNAL_H

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/types.h>

#include "dfle/error.h"
#include "dfle/file.h"
#include "dfle/plot.h"

enum { FMT_PNG, FMT_SVG, FMT_PDF };

/* Okabe-Ito colours, ordered so that neighbours differ most:
 * distinguishable with colour-blindness and in print. */
#define DFLE_GP_NPALETTE 7
extern const char *const dfle_gp_palette[DFLE_GP_NPALETTE];
/* The house greys and the fit colour (vermillion). */
#define DFLE_GP_GREY "#a0a0a0"
#define DFLE_GP_FIT "#D55E00"

/* Line width of 1 in the script, in pt. */
#define DFLE_GP_LW_PT 0.5
/* Point size of 1 in the script, in pt across. */
#define DFLE_GP_PS_PT 6.0

/* A figure's page: format, size and font, resolved from the options. */
typedef struct dfle_gp_frame {
    int fmt;             /* FMT_*                          */
    double w_pt, h_pt;   /* page size [pt]                 */
    double dpi;          /* PNG pixels per inch            */
    char family[64];     /* font family ("sans" by default) */
    double font_pt;      /* font size [pt]                 */
} dfle_gp_frame;

/* One gnuplot run.  SIGPIPE is blocked for this thread while we write, so
 * a gnuplot that is missing or dies early gives EPIPE, not a dead caller. */
typedef struct dfle_gp_run {
    FILE *f;              /* the script, to gnuplot's standard input */
    pid_t pid;            /* gnuplot's process */
    const char *prog, *out;
    const char *write_to; /* where gnuplot writes: a temporary file beside out */
    dfle_file file;       /* renamed over out once the image is checked */
    int fmt;
    double svg_w_pt, svg_h_pt; /* an SVG's size, written into its header */
    int errfd;            /* gnuplot's messages: an unlinked file */
    sigset_t pipeset, oldmask;
    int pipe_pending; /* SIGPIPE was pending before us: not ours to eat */
} dfle_gp_run;

/* --- plot_run.c --- */

/* The image format named by the path's extension (FMT_PNG, FMT_SVG,
 * FMT_PDF), or a negative status. */
int dfle_gp_format(const char *path, dfle_error *err);
/* s as a gnuplot single-quoted string (no substitution of any kind). */
void dfle_gp_str(FILE *f, const char *s);
/* Start gnuplot on the page fr. */
int dfle_gp_begin_frame(dfle_gp_run *r, const char *path, const dfle_gp_frame *fr,
                        dfle_error *err);
int dfle_gp_end(dfle_gp_run *r, dfle_error *err);

/* --- plot_opts.c --- */

/* The page of a figure from its options: default w_cm x h_cm; font,
 * dpi and size checked. */
int dfle_gp_frame_of(const char *path, const dfle_plot_opts *o, double w_cm, double h_cm,
                     dfle_gp_frame *fr, dfle_error *err);
/* Point size (gnuplot's ps) of a marker size_pt across on page fr. */
double dfle_gp_ps(const dfle_gp_frame *fr, double size_pt);
/* Option `what` of axis u ("xrange", ...) is usable on a logarithmic
 * (log = 1) or linear axis: finite, increasing, positive when log. */
int dfle_gp_axis_ok(char name, const dfle_plot_axis *u, int log, dfle_error *err);
/* A series' look, resolved: what is drawn, colour, line width and dash
 * (script units), marker (gnuplot point type and size), and the
 * gnuplot "with" clause made of them; the legend draws its sample from
 * the same fields. */
enum { DFLE_GP_LINES, DFLE_GP_POINTS, DFLE_GP_LINESPOINTS, DFLE_GP_BAND, DFLE_GP_BARS };
typedef struct dfle_gp_look {
    int kind;
    char rgb[8];
    double lw, ps;
    int dt, pt;
    char with[160];
} dfle_gp_look;
/* Fill look from its fields (ps: gnuplot's point size; every: draw a
 * marker every so many points, linespoints only). */
void dfle_gp_look_set(dfle_gp_look *look, int kind, const char *rgb, double lw, int dt, int pt,
                      double ps, size_t every);
/* Series k of a figure (its style, dash, width, marker and colour, or
 * the house default for the k-th series). */
void dfle_gp_look_of(const dfle_plot_series *s, size_t k, const dfle_gp_frame *fr,
                     dfle_gp_look *look);

/* --- plot_axes.c --- */

/* Width of enhanced text in em (markup not counted): for margins, the
 * legend and the spacing of tick labels. */
double dfle_gp_text_em(const char *s);

/* An axis as drawn: its range (data units), whether it is logarithmic,
 * its length on the page, and the ticks chosen for it. */
enum { DFLE_GP_MAXTICKS = DFLE_PLOT_MAXTICKS, DFLE_GP_MAXMINOR = 600, DFLE_GP_TICKLAB = 48 };
typedef struct dfle_gp_axis {
    int log;
    double lo, hi;          /* range, data units */
    size_t n, nminor;
    double v[DFLE_GP_MAXTICKS];
    char lab[DFLE_GP_MAXTICKS][DFLE_GP_TICKLAB];
    double minor[DFLE_GP_MAXMINOR];
    const char *format;     /* the caller's format: labels left to gnuplot */
    double max_em;          /* widest tick label [em] */
    double end_room;        /* > 0: how far labels may reach beyond the axis's
                             * ends [pt] (panels side by side); 0: any */
    int factor_ok;          /* tiny or huge values may be labelled by
                             * mantissas with one factor for the axis */
    int factored, factor_exp; /* they are: the axis label says ×10^{e} */
} dfle_gp_axis;

/* The range of an axis from the data's extent [dlo, dhi] (data units;
 * dlo > dhi: no data) and the caller's axis options: the caller's ends
 * where given, else the data's, padded by `pad` of the span (in log10
 * units on a log axis) so that data do not sit on the frame. */
void dfle_gp_axis_range(dfle_gp_axis *a, int log, double dlo, double dhi, double pad,
                        const dfle_plot_axis *user);
/* Choose the ticks of a (range set) for an axis len_pt long, labels in
 * a font_pt font: the most ticks whose labels keep a gap (horizontal
 * labels side by side on an x axis, stacked on a y axis), from 1, 2 and
 * 5 times powers of ten; the caller's ticks, step or format win. */
void dfle_gp_axis_ticks(dfle_gp_axis *a, double len_pt, double font_pt, int vertical,
                        const dfle_plot_axis *user);
/* The axis label for a: `label`, or with a's factor when its ticks are
 * labelled by mantissas ("D (×10^{-6} m^2/s)", "k_e (×10^{-14})"); buf
 * holds the new text. */
const char *dfle_gp_axis_label(const dfle_gp_axis *a, const char *label, char *buf, size_t cap);
/* "set <name>range", log scale, tick list (labels or none) and minor
 * ticks for axis `name` ("x", "y", "cb"). */
void dfle_gp_axis_put(FILE *f, const char *name, const dfle_gp_axis *a, int labels);


/* --- plot_crs.c --- */

/* The EPSG code ("EPSG:32611", or "" when there is none) and name of a
 * map's CRS (NULL or "": none, both ""); DFLE_EINVAL for a CRS GDAL
 * cannot read or one not projected in metres. */
int dfle_gp_crs_names(const char *crs, char *code, size_t ccap, char *name, size_t ncap,
                      dfle_error *err);

/* --- plot_frame.c --- */

/* One thing drawn from n rows (x, y), optionally with error-bar ends
 * lo/hi (y given) or as a band between lo and hi (y NULL), optionally
 * coloured by c.  Unusable rows (non-finite, or <= 0 on a log axis) are
 * left out; in a line they leave a gap rather than a false join. */
typedef struct dfle_gp_layer {
    size_t n;
    const double *x, *y, *lo, *hi, *c;
    dfle_gp_look look;   /* colour and "with" clause */
    const char *title;   /* legend text; NULL: none */
    int line;            /* drawn as a line: the legend avoids its segments */
    int marks;           /* drawn with markers: kept off the frame */
    size_t used;         /* usable rows, counted by the figure */
} dfle_gp_layer;

/* A layer from a series (its look resolved as the k-th series). */
void dfle_gp_layer_of(dfle_gp_layer *l, const dfle_plot_series *s, size_t k,
                      const dfle_gp_frame *fr);

/* Layers sharing one y axis. */
typedef struct dfle_gp_panel {
    dfle_gp_layer *layers;
    size_t nl;
    const dfle_plot_axis *y;  /* the caller's y options (may be NULL) */
    int ylog;                 /* the axis if y->log says nothing */
    const char *ylabel;       /* if y->label is NULL */
    double weight;            /* share of the height; 0 = 1 */
    const char *extra;        /* script lines before its plot (arrows) */
} dfle_gp_panel;

/* A label on the page at (x, y) [pt from the bottom left], rotated by
 * rot degrees, as gnuplot label `tag`; enhanced text unless plain. */
void dfle_gp_page_label(FILE *f, int tag, const char *text, double x, double y, double rot,
                        int plain, const dfle_gp_frame *fr);

/* A figure's part of the page [pt from the bottom left]: figures side
 * by side share one page and one gnuplot run. */
typedef struct dfle_gp_box {
    double x0, y0, x1, y1;
} dfle_gp_box;

/* A figure laid out (ranges, ticks, margins, legends) before gnuplot
 * starts: np panels over one x axis in `box` (NULL: the whole page), as
 * dfle_gp_figure draws them.  P and opts must outlive the plan. */
typedef struct dfle_gp_plan dfle_gp_plan;
int dfle_gp_plan_new(const char *path, const dfle_gp_frame *fr, const dfle_gp_box *box,
                     const dfle_plot_opts *opts, int xlog, const char *xlabel, dfle_gp_panel *P,
                     size_t np, dfle_gp_plan **out, dfle_error *err);
/* Write the plan's script to a run; `cell` names its data blocks (each
 * figure on a page its own), in_multiplot: the caller set multiplot. */
void dfle_gp_plan_put(FILE *f, const dfle_gp_plan *pl, int cell, int in_multiplot);
/* The room below the frame a plan keeps for its legend [pt], and more
 * of it (figures side by side with frames of one height). */
double dfle_gp_plan_key_below(const dfle_gp_plan *pl);
void dfle_gp_plan_set_key_below(dfle_gp_plan *pl, double key_below);
/* Panel p's frame on the page: left, bottom, right, top [pt]. */
void dfle_gp_plan_frame(const dfle_gp_plan *pl, size_t p, double frame[4]);
void dfle_gp_plan_free(dfle_gp_plan *pl);

/* --- plot.c --- */

/* The slope-area panel of dfle_plot_slope_area (data, bins, Eq. 2 and
 * A_df), built in sp, which holds what its layers point at. */
enum { DFLE_GP_FIT_SAMPLES = 200 };
typedef struct dfle_gp_sa_panel {
    dfle_gp_panel panel;
    dfle_gp_layer L[4];
    double fa[DFLE_GP_FIT_SAMPLES], fs[DFLE_GP_FIT_SAMPLES], mark_a, mark_s;
    char ftitle[320], mtitle[96], extra[200];
} dfle_gp_sa_panel;
int dfle_gp_slope_area_panel(dfle_gp_sa_panel *sp, const dfle_gp_frame *fr, const char *path,
                             size_t n, const double *A, const double *S, const dfle_bins *bins,
                             const dfle_eq2_fit *fit, const dfle_plot_axis *y, dfle_error *err);

/* A whole figure: np panels over one x axis (opts->x; xlog and xlabel
 * when it says nothing), a colour box for layers coloured by value,
 * title, legend (opts->legend, in the first panel with legend
 * entries), and the page fr. */
int dfle_gp_figure(const char *path, const dfle_gp_frame *fr, const dfle_plot_opts *opts,
                   int xlog, const char *xlabel, dfle_gp_panel *panels, size_t np,
                   dfle_error *err);

#endif
