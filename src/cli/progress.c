/*
 * progress.c - a one-line progress bar on stderr for long runs.
 *
 * The library only reports status through a callback; drawing is the
 * CLI's business, and only when stderr is a terminal, so pipes, logs and
 * CI output never see carriage returns.
 */
#include "cli/progress.h"

#include <time.h>

#define BAR_WIDTH 24

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void dfle_progress_bar_init(dfle_progress_bar *bar, FILE *out)
{
    bar->out = out;
    bar->started = -1.0;
    bar->last_draw = -1.0;
    bar->drawn = 0;
}

int dfle_progress_bar_update(void *ud, const dfle_run_status *st)
{
    dfle_progress_bar *bar = ud;
    double t = now();
    int filled;

    if (bar->started < 0)
        bar->started = t;
    if (bar->last_draw >= 0 && t - bar->last_draw < 0.1)
        return 0;
    bar->last_draw = t;
    filled = (int)(st->fraction * BAR_WIDTH + 0.5);
    fputs("\r[", bar->out);
    for (int i = 0; i < BAR_WIDTH; i++)
        fputc(i < filled ? '#' : '.', bar->out);
    fprintf(bar->out, "] %3d%%  t = %.3g yr", (int)(100 * st->fraction), st->time);
    if (st->tol > 0)
        fprintf(bar->out, "  max|dz/dt|/U = %.2e -> %.0e", st->rate_ratio, st->tol);
    if (st->fraction > 0.02) {
        double elapsed = t - bar->started;
        fprintf(bar->out, "  ETA %.0f s", elapsed * (1.0 - st->fraction) / st->fraction);
    }
    fputs("\033[K", bar->out); /* clear what a longer previous line left */
    fflush(bar->out);
    bar->drawn = 1;
    return 0;
}

void dfle_progress_bar_finish(void *ud)
{
    dfle_progress_bar *bar = ud;
    if (bar->drawn) {
        fputs("\r\033[K", bar->out);
        fflush(bar->out);
    }
    bar->started = bar->last_draw = -1.0;
    bar->drawn = 0;
}
