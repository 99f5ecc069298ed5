/*
 * plot.h - figures through gnuplot.
 *
 * Each function writes a complete gnuplot script (data inline) to a
 * gnuplot process and checks that the image was written whole.  The
 * format follows the file extension: .png (pngcairo), .pdf (pdfcairo) or
 * .svg.  The program is `gnuplot` on PATH unless the environment variable
 * DFLE_GNUPLOT names another.  Failures (no gnuplot, a gnuplot without
 * the terminal, bad options, an unwritable path) are DFLE_EEXTERNAL /
 * DFLE_EINVAL / DFLE_EIO with a message; a message about an option
 * names it as dfle.plot's options table does (xrange, size, legend, ...).
 *
 * Every figure takes the same dfle_plot_opts: size, font, title, the
 * axes (label, range, log, ticks), the colour scale and the legend.  A
 * zeroed struct ({0} or memset) means "the figure's own default" in every
 * field, so a caller sets only what differs.
 */
#ifndef DFLE_PLOT_H
#define DFLE_PLOT_H

#include <stddef.h>
#include "dfle/analysis.h"
#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Units of a figure's width and height.  Pixels mean pixels of a PNG;
 * for PDF and SVG they are converted at the figure's dpi. */
enum dfle_plot_unit { DFLE_PLOT_CM = 0, DFLE_PLOT_IN = 1, DFLE_PLOT_PX = 2 };

/* Where the legend goes: inside the frame at a corner or the middle of
 * a side, outside it (right of the frame, or below it in columns), or
 * nowhere.  AUTO takes the inside corner or side the legend would cover
 * least data in, and goes below the frame when every one would cover
 * some. */
enum dfle_plot_legend {
    DFLE_LEGEND_AUTO = 0,
    DFLE_LEGEND_NONE,
    DFLE_LEGEND_TOP_LEFT,
    DFLE_LEGEND_TOP_RIGHT,
    DFLE_LEGEND_BOTTOM_LEFT,
    DFLE_LEGEND_BOTTOM_RIGHT,
    DFLE_LEGEND_TOP,          /* inside, top centre    */
    DFLE_LEGEND_BOTTOM,       /* inside, bottom centre */
    DFLE_LEGEND_LEFT,         /* inside, left middle   */
    DFLE_LEGEND_RIGHT,        /* inside, right middle  */
    DFLE_LEGEND_OUTSIDE_RIGHT,
    DFLE_LEGEND_BELOW         /* outside, under the x axis */
};

/* How a series is drawn. */
enum dfle_plot_style { DFLE_PLOT_POINTS = 0, DFLE_PLOT_LINES = 1, DFLE_PLOT_LINESPOINTS = 2 };

enum dfle_plot_dash {
    DFLE_DASH_SOLID = 0,
    DFLE_DASH_DASH,
    DFLE_DASH_DOT,
    DFLE_DASH_DASHDOT,
    DFLE_DASH_DASHDOTDOT
};

enum dfle_plot_marker {
    DFLE_MARKER_AUTO = 0, /* a filled circle; linespoints: a shape per series */
    DFLE_MARKER_CIRCLE,
    DFLE_MARKER_SQUARE,
    DFLE_MARKER_TRIANGLE,
    DFLE_MARKER_DOWN_TRIANGLE,
    DFLE_MARKER_DIAMOND,
    DFLE_MARKER_OPEN_CIRCLE,
    DFLE_MARKER_OPEN_SQUARE,
    DFLE_MARKER_OPEN_TRIANGLE,
    DFLE_MARKER_OPEN_DOWN_TRIANGLE,
    DFLE_MARKER_OPEN_DIAMOND,
    DFLE_MARKER_PLUS,
    DFLE_MARKER_CROSS,
    DFLE_MARKER_STAR
};

/* Most ticks an axis takes from its caller. */
#define DFLE_PLOT_MAXTICKS 128

/* One axis (x, y, or the colour scale c).  Zero: the figure's default. */
typedef struct dfle_plot_axis {
    const char *label;       /* enhanced text; NULL: the figure's own       */
    int log;                 /* 1 logarithmic, -1 linear, 0 the figure's own */
    int has_lo, has_hi;      /* lo / hi given: fixes that end of the range */
    double lo, hi;           /* range in data units (> 0 on a log axis)     */
    double step;             /* linear axis: tick spacing (> 0); 0: chosen
                              * so that the labels do not touch            */
    const double *ticks;     /* explicit ticks (nticks of them, 0 = none at
                              * all), or NULL                              */
    const char *const *tick_labels; /* their labels (NULL entries: the
                              * number), or NULL                          */
    size_t nticks;
    const char *format;      /* tick labels as a gnuplot format, e.g. "%.1f";
                              * NULL: chosen from the tick spacing         */
} dfle_plot_axis;

typedef struct dfle_plot_opts {
    const char *title;        /* may be NULL (journal figures carry none) */
    dfle_plot_axis x, y, c;   /* c: the colour scale of coloured series    */
    double width, height;     /* in `unit`; 0: the figure's default        */
    int unit;                 /* enum dfle_plot_unit                       */
    double dpi;               /* PNG resolution [1/in]; 0: 150             */
    const char *font;         /* "Family,size" (size in pt), "Family" or
                               * ",size"; NULL: "sans,9"                   */
    int legend;               /* enum dfle_plot_legend                     */
} dfle_plot_opts;

/* One named curve: n points (x, y), drawn as points, lines or both. */
typedef struct dfle_plot_series {
    const char *label;  /* legend text; NULL = no legend entry          */
    size_t n;
    const double *x, *y;
    int style;          /* enum dfle_plot_style                         */
    const double *c;    /* optional: a value per point, drawn as a colour
                         * on a continuous scale with a colour box      */
    const double *lo, *hi; /* optional: a band filled between lo and hi
                         * (y is then unused), drawn translucent        */
    const char *rgb;    /* optional colour: "#rrggbb" or a name of
                         * dfle_plot_colour; NULL: the palette's next   */
    int dash;           /* enum dfle_plot_dash                          */
    double width;       /* line width [pt]; 0: 1.25                     */
    int marker;         /* enum dfle_plot_marker                        */
    double marker_size; /* marker width [pt]; 0: 4 (2.5 beyond 2000 points) */
} dfle_plot_series;

/* Names the options use, parsed here so every binding shares them.
 * Each returns the enum value, or DFLE_EINVAL with a message naming
 * `what` (the option) and listing the accepted names. */
int dfle_plot_parse_legend(const char *s, const char *what, dfle_error *err);
int dfle_plot_parse_unit(const char *s, const char *what, dfle_error *err);
int dfle_plot_parse_style(const char *s, const char *what, dfle_error *err);
int dfle_plot_parse_dash(const char *s, const char *what, dfle_error *err);
int dfle_plot_parse_marker(const char *s, const char *what, dfle_error *err);
/* A colour: "#rrggbb" or a name of the colour-blind-safe (Okabe-Ito)
 * palette: black, orange, sky blue, green, yellow, blue, vermillion,
 * purple, and grey.  Writes "#rrggbb" to out[8]. */
int dfle_plot_colour(const char *s, const char *what, char out[8], dfle_error *err);

/* The house label of a quantity by its dfle name ("A" -> "Drainage area,
 * {/:Italic A} (m^2)", "U" -> "Uplift rate, {/:Italic U} (mm/yr)"), and
 * the factor that takes dfle's unit to the label's (1e3 for U: m/yr to
 * mm/yr; 1 for most).  NULL for a name it does not know. */
const char *dfle_plot_label(const char *name, double *factor);
/* The i-th name dfle_plot_label knows (from 0), NULL past the last. */
const char *dfle_plot_label_name(size_t i);

/* v as a label shows it: 3 significant digits, and large or small
 * values as enhanced text "1.42×10^{5}" rather than "1.42e+05";
 * "inf", "-inf" or "NaN" for a value that is not finite. */
void dfle_plot_number(char *buf, size_t cap, double v);

/* Check options and series before anything is drawn: ranges finite and
 * increasing (positive on log axes), size, dpi and font size within
 * bounds, known enums, colours.  The figures call these themselves. */
int dfle_plot_opts_check(const dfle_plot_opts *opts, dfle_error *err);
int dfle_plot_series_check(const dfle_plot_series *series, size_t nseries, dfle_error *err);

/* Generic x-y plot of several series: 16 x 10 cm. */
int dfle_plot_xy(const char *path, const dfle_plot_opts *opts,
                 const dfle_plot_series *series, size_t nseries,
                 dfle_error *err);

/* Panels stacked over one shared x axis (opts->x), each with its own y
 * axis; opts->y is not used.  weight: the panel's share of the height
 * (0 = 1).  16 x (5 + 4.5 per panel) cm. */
typedef struct dfle_plot_panel {
    const dfle_plot_series *series;
    size_t nseries;
    dfle_plot_axis y;
    double weight;
} dfle_plot_panel;

int dfle_plot_panels(const char *path, const dfle_plot_opts *opts,
                     const dfle_plot_panel *panels, size_t npanels, dfle_error *err);

/* Log-log slope-area plot: raw points (grey), bin means (black), the
 * fitted Eq. (2) (vermillion) with A_df marked.  bins and fit may be
 * NULL.  16 x 11 cm. */
int dfle_plot_slope_area(const char *path, const dfle_plot_opts *opts, size_t n,
                         const double *A, const double *S,
                         const dfle_bins *bins, const dfle_eq2_fit *fit,
                         dfle_error *err);

/* A chi plot (Perron and Royden 2013): each cell's elevation against
 * its chi, coloured by k_sn (or black), cells below A_min in light grey
 * (left out of the line), and the line z = z_b + M_chi chi in vermillion
 * with its k_sn = M_chi A0^theta_ref and R^2 in the legend.  The colour
 * range defaults to the 2nd to 98th percentile of k_sn (opts->c sets
 * it).  16 x 11 cm. */
typedef struct dfle_plot_chi_data {
    size_t n;
    const double *chi;      /* [m]                                             */
    const double *z;        /* elevation [m] (or height above base level)      */
    const double *k_sn;     /* colour, or NULL                                  */
    const double *A;        /* drainage area [m^2], or NULL (all fitted)        */
    double A_min;           /* [m^2]                                            */
    double theta_ref, A0;   /* [-], [m^2]: named in the axis label              */
    double M_chi, z_b, r2;  /* the line; M_chi NaN: none                        */
} dfle_plot_chi_data;

int dfle_plot_chi(const char *path, const dfle_plot_opts *opts, const dfle_plot_chi_data *chi,
                  dfle_error *err);

/* The slope-area figure (as dfle_plot_slope_area) and the chi plot side
 * by side, (a) and (b), on one page: 25 x 10.5 cm. */
int dfle_plot_slope_area_chi(const char *path, const dfle_plot_opts *opts, size_t n,
                             const double *A, const double *S, const dfle_bins *bins,
                             const dfle_eq2_fit *fit, const dfle_plot_chi_data *chi,
                             dfle_error *err);

/* Long profile z(x) [m], with a second panel of slope S(x) (S may be
 * NULL).  opts->y applies to the elevation panel.  16 x 13 cm. */
int dfle_plot_profile(const char *path, const dfle_plot_opts *opts, size_t n,
                      const double *x, const double *z, const double *S,
                      dfle_error *err);

/* Several PNG images (paths[k], titled titles[k] or by their file name)
 * tiled in `columns` columns (0: 3) on one page: a contact sheet to look
 * at every figure at once.  Each tile is 9 cm wide unless opts sets the
 * page's size. */
int dfle_plot_sheet(const char *path, const dfle_plot_opts *opts, const char *const *paths,
                    const char *const *titles, size_t n, size_t columns, dfle_error *err);

/* Points drawn on a map, coloured by a value on the figure's colour
 * scale (opts->c: label, range, log; the default range spans the 2nd to
 * 98th percentile of the values, so that a few extreme cells do not wash
 * out the rest), e.g. the k_sn of a channel network's cells.  Each is a
 * filled circle, larger where `size` (e.g. drainage area) is larger on a
 * log scale; those of non-finite value are not drawn. */
typedef struct dfle_plot_map_points {
    size_t n;
    const double *x, *y;      /* map coordinates [m]                     */
    const double *value;      /* the colour                              */
    const double *size;       /* > 0, or NULL: all one size              */
} dfle_plot_map_points;

/* A map: shaded relief of z (Horn's slope and aspect, light from the
 * north-west at 45 degrees) over a hypsometric tint with its colour
 * box, the channel cells in blue and the cells debris flows reach in
 * vermillion on top (the legend names a colour only where the map shows
 * it: no channel entry when every channel cell is reached).  With
 * points, the relief is grey and the colour box is the points' scale.
 * Axes in km of the map's coordinates at equal scales, labelled with the
 * CRS's EPSG code ("Easting (km, EPSG:32611)"; "x (km)" without a CRS),
 * the frame fitted to the cells with data, the page to the frame (no
 * empty bands); a scale bar with the CRS's name, a north arrow (grid
 * north: the top of the grid) and the legend inside the frame where they
 * cover least data (the legend below the frame when every corner would
 * hide data).  Grids of more than 1.5e6 cells are drawn every k-th cell. */
typedef struct dfle_plot_map {
    size_t nx, ny;            /* columns, rows (row 0 at the north)      */
    double x0, y0, dx, dy;    /* north-west corner and cell size [m]     */
    const double *z;          /* elevation [m], NaN = NoData (white)     */
    const double *channel;    /* > 0: a channel cell, or NULL            */
    const double *reach;      /* > 0: debris flows reach it, or NULL     */
    const char *title;        /* may be NULL (opts->title wins)          */
    const char *channel_label, *reach_label; /* legend; NULL: defaults   */
    const char *crs;          /* the CRS: WKT, "EPSG:32611" or any string
                               * GDAL reads; NULL: none.  Must be
                               * projected, in metres                    */
    const dfle_plot_map_points *points; /* or NULL                       */
} dfle_plot_map;

/* The map on a page of the options' width (16 cm), its height set by
 * the map's proportions unless the options give it too. */
int dfle_plot_map_draw(const char *path, const dfle_plot_opts *opts, const dfle_plot_map *map,
                       dfle_error *err);
/* The same with the default options. */
int dfle_plot_hillshade(const char *path, const dfle_plot_map *map, dfle_error *err);

/* Corner plot of posterior samples: the marginal of each parameter on
 * the diagonal (a histogram with its median and central 68 % interval,
 * given above it as median^{+}_{-}), and below it every pair as a
 * scatter of the samples with the contours enclosing 68 % and 95 % of
 * them.  x holds n samples of d parameters (n x d, sample-major); more
 * than 5000 samples are thinned evenly for the scatter (not for the
 * histograms and contours).  From dfle_plot_opts it takes the title,
 * size (default: 4 cm per panel), dpi and font. */
typedef struct dfle_corner_opts {
    const char *const *labels;  /* d axis labels (enhanced text), or NULL */
    const int *logaxis;         /* d flags: logarithmic axis, or NULL   */
    const double *truth;        /* d values marked in vermillion (NaN: none), or NULL */
    size_t nbins;               /* histogram bins; 0 = 30               */
    /* d prior bounds that hold the posterior (NaN: none), or NULL: each
     * drawn as a line, the side outside the prior shaded, and noted
     * "prior bound" on the diagonal */
    const double *bound_lo, *bound_hi;
} dfle_corner_opts;

int dfle_plot_corner(const char *path, const dfle_plot_opts *opts,
                     const dfle_corner_opts *corner, size_t d, size_t n,
                     const double *x, dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
