/*
 * progress.h - the CLI's terminal progress bar (not part of the library).
 */
#ifndef DFLE_PROGRESS_H
#define DFLE_PROGRESS_H

#include <stdio.h>

#include "dfle/solver.h"

/* The time left, from how fast the completion estimate moved lately.
 * A steady-state run's estimate (how far max|dz/dt|/U has fallen on a
 * log scale) races through the first orders of magnitude and crawls
 * through the last, so an ETA from the average since the start says
 * "3 s" for a run that takes 13; the recent pace is the honest guess. */
#define DFLE_ETA_SAMPLES 16
typedef struct dfle_progress_eta {
    double t[DFLE_ETA_SAMPLES], f[DFLE_ETA_SAMPLES]; /* ring of (seconds, fraction) */
    int count, head;
    double first;  /* seconds of the first sample */
} dfle_progress_eta;

void dfle_progress_eta_init(dfle_progress_eta *e);
/* Record the fraction done at time `now` [s] and return the estimated
 * seconds left, or a negative number while there is no honest estimate
 * (the first second, or no progress lately). */
double dfle_progress_eta_update(dfle_progress_eta *e, double now, double fraction);

typedef struct dfle_progress_bar {
    FILE *out;
    double started;    /* monotonic seconds at the first update */
    double last_draw;  /* monotonic seconds of the last redraw  */
    int drawn;         /* something is on the line              */
    dfle_progress_eta eta;
} dfle_progress_bar;

void dfle_progress_bar_init(dfle_progress_bar *bar, FILE *out);
/* dfle_progress_fn: redraws at most ten times a second; never cancels. */
int dfle_progress_bar_update(void *bar, const dfle_run_status *st);
/* Clear the line and reset for the next run. */
void dfle_progress_bar_finish(void *bar);

#endif
