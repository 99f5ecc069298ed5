/*
 * progress.h - the CLI's terminal progress bar (not part of the library).
 */
#ifndef DFLE_PROGRESS_H
#define DFLE_PROGRESS_H

#include <stdio.h>

#include "dfle/solver.h"

typedef struct dfle_progress_bar {
    FILE *out;
    double started;    /* monotonic seconds at the first update */
    double last_draw;  /* monotonic seconds of the last redraw  */
    int drawn;         /* something is on the line              */
} dfle_progress_bar;

void dfle_progress_bar_init(dfle_progress_bar *bar, FILE *out);
/* dfle_progress_fn: redraws at most ten times a second; never cancels. */
int dfle_progress_bar_update(void *bar, const dfle_run_status *st);
/* Clear the line and reset for the next run. */
void dfle_progress_bar_finish(void *bar);

#endif
