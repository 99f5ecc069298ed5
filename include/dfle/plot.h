/*
 * plot.h - figures through gnuplot.
 *
 * Each function writes a complete gnuplot script (data inline) to a
 * gnuplot process and checks that the image was written.  The terminal
 * follows the file extension: .png (pngcairo) or .svg.  The program is
 * `gnuplot` on PATH unless the environment variable DFLE_GNUPLOT names
 * another.  Failures (no gnuplot, bad extension, unwritable path) are
 * DFLE_EEXTERNAL / DFLE_EINVAL / DFLE_EIO with a message.
 */
#ifndef DFLE_PLOT_H
#define DFLE_PLOT_H

#include <stddef.h>
#include "dfle/analysis.h"
#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One named curve: n points (x, y), drawn as points or lines. */
typedef struct dfle_plot_series {
    const char *label; /* legend text; NULL = no legend entry */
    size_t n;
    const double *x, *y;
    int lines;         /* 1: lines, 0: points                 */
    const double *c;   /* optional: a value per point, drawn as a colour
                        * on a continuous scale with a colour box   */
    const double *lo, *hi; /* optional: a band filled between lo and hi
                        * (y is then unused), drawn translucent     */
    const char *rgb;   /* optional colour "#rrggbb" instead of the
                        * palette's                                 */
    int dash;          /* lines: 1 dashed                           */
} dfle_plot_series;

typedef struct dfle_plot_opts {
    const char *title;   /* may be NULL */
    const char *xlabel;  /* may be NULL */
    const char *ylabel;  /* may be NULL */
    int logx, logy;      /* logarithmic axes                    */
    int width, height;   /* pixels; 0 = 900 x 600               */
    const char *clabel;  /* label of the colour box (series with c) */
    int logc;            /* logarithmic colour scale               */
} dfle_plot_opts;

/* Generic x-y plot of several series. */
int dfle_plot_xy(const char *path, const dfle_plot_opts *opts,
                 const dfle_plot_series *series, size_t nseries,
                 dfle_error *err);

/* Log-log slope-area plot: raw points (grey), bin means (black), the
 * fitted Eq. (2) (red) with A_df marked.  bins and fit may be NULL. */
int dfle_plot_slope_area(const char *path, const char *title, size_t n,
                         const double *A, const double *S,
                         const dfle_bins *bins, const dfle_eq2_fit *fit,
                         dfle_error *err);

/* Long profile z(x) [m], with a second panel of slope S(x). */
int dfle_plot_profile(const char *path, const char *title, size_t n,
                      const double *x, const double *z, const double *S,
                      dfle_error *err);

/* A map: shaded relief of z (Horn's slope and aspect, light from the
 * north-west at 45 degrees) over a hypsometric tint with its colour
 * box, the channel cells in blue and the cells debris flows reach in
 * vermillion on top, axes in km of map coordinates, equal scales.  Grids
 * of more than 1.5e6 cells are drawn every k-th cell. */
typedef struct dfle_plot_map {
    size_t nx, ny;            /* columns, rows (row 0 at the north)      */
    double x0, y0, dx, dy;    /* north-west corner and cell size [m]     */
    const double *z;          /* elevation [m], NaN = NoData (white)     */
    const double *channel;    /* > 0: a channel cell, or NULL            */
    const double *reach;      /* > 0: debris flows reach it, or NULL     */
    const char *title;        /* may be NULL                             */
    const char *channel_label, *reach_label; /* legend; NULL: defaults   */
} dfle_plot_map;

int dfle_plot_hillshade(const char *path, const dfle_plot_map *map, dfle_error *err);

/* Corner plot of posterior samples: the marginal of each parameter on
 * the diagonal (a histogram with its median and central 68 % interval,
 * given above it as median^{+}_{-}), and below it every pair as a
 * scatter of the samples with the contours enclosing 68 % and 95 % of
 * them.  x holds n samples of d parameters (n x d, sample-major); more
 * than 5000 samples are thinned evenly for the scatter (not for the
 * histograms and contours). */
typedef struct dfle_corner_opts {
    const char *title;          /* may be NULL                          */
    const char *const *labels;  /* d axis labels (enhanced text), or NULL */
    const int *logaxis;         /* d flags: logarithmic axis, or NULL   */
    const double *truth;        /* d values marked in red (NaN: none), or NULL */
    int panel;                  /* pixels per panel; 0 = 250            */
    size_t nbins;               /* histogram bins; 0 = 30               */
} dfle_corner_opts;

int dfle_plot_corner(const char *path, const dfle_corner_opts *opts, size_t d, size_t n,
                     const double *x, dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
