/*
 * plot_internal.h - what the plot files share (not installed): plot.c
 * (x-y, slope-area, profile figures and the gnuplot run itself) and
 * plot_corner.c (the corner plot of posterior samples).
 *
 * A figure is one gnuplot run: dfle_gp_begin starts gnuplot writing to a
 * temporary file beside the image and sets the terminal and house style;
 * the caller writes the script to r.f; dfle_gp_end checks gnuplot's exit,
 * the image's completeness, and renames it over the target.
 */
#ifndef DFLE_PLOT_INTERNAL_H
#define DFLE_PLOT_INTERNAL_H

#include <signal.h>
#include <stdio.h>

#include "dfle/error.h"
#include "dfle/file.h"

enum { FMT_PNG, FMT_SVG };

/* Okabe-Ito colours: distinguishable with colour-blindness and in print. */
#define DFLE_GP_NPALETTE 7
extern const char *const dfle_gp_palette[DFLE_GP_NPALETTE];

/* One gnuplot run.  SIGPIPE is blocked for this thread while we write, so
 * a gnuplot that is missing or dies early gives EPIPE, not a dead caller. */
typedef struct dfle_gp_run {
    FILE *f;
    const char *prog, *out;
    const char *write_to; /* where gnuplot writes: a temporary file beside out */
    dfle_file file;       /* renamed over out once the image is checked */
    int fmt;
    int errfd;            /* gnuplot's messages: an unlinked file */
    sigset_t pipeset, oldmask;
    int pipe_pending; /* SIGPIPE was pending before us: not ours to eat */
} dfle_gp_run;

/* The image format named by the path's extension (FMT_PNG, FMT_SVG),
 * or a negative status. */
int dfle_gp_format(const char *path, dfle_error *err);
/* s as a gnuplot single-quoted string (no substitution of any kind). */
void dfle_gp_str(FILE *f, const char *s);
int dfle_gp_begin(dfle_gp_run *r, const char *path, int fmt, int w, int h, dfle_error *err);
int dfle_gp_end(dfle_gp_run *r, dfle_error *err);
/* A logarithmic axis c ('x', 'y') over [lo, hi] in log10 units: labels
 * 10^n when it spans two decades or more, and otherwise tics at 1, 2, 5
 * (and 3, 7 below one decade) times 10^n: gnuplot would label only the
 * decades, leaving a narrow axis with one number or none.  labels = 0:
 * the same tics without numbers. */
void dfle_gp_log_axis(FILE *f, char c, double lo, double hi, int labels);
/* v for a legend: 3 significant digits, large or small as "1.2×10^{4}". */
void dfle_gp_number(char *buf, size_t cap, double v);

#endif
