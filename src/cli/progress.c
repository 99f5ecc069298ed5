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

/* Samples at least this far apart [s], kept over the last
 * DFLE_ETA_SAMPLES * ETA_SPACING seconds: long enough to smooth the
 * steps of a run, short enough to follow its slowing down. */
#define ETA_SPACING 0.5

void dfle_progress_eta_init(dfle_progress_eta *e)
{
    e->count = e->head = 0;
    e->first = -1.0;
}

double dfle_progress_eta_update(dfle_progress_eta *e, double now, double fraction)
{
    int last = (e->head + DFLE_ETA_SAMPLES - 1) % DFLE_ETA_SAMPLES;
    int oldest;
    double df, dt;

    if (e->first < 0)
        e->first = now;
    if (e->count == 0 || now - e->t[last] >= ETA_SPACING) {
        e->t[e->head] = now;
        e->f[e->head] = fraction;
        e->head = (e->head + 1) % DFLE_ETA_SAMPLES;
        if (e->count < DFLE_ETA_SAMPLES)
            e->count++;
    }
    if (now - e->first < 1.0 || e->count < 2)
        return -1.0;
    oldest = (e->head + DFLE_ETA_SAMPLES - e->count) % DFLE_ETA_SAMPLES;
    df = fraction - e->f[oldest];
    dt = now - e->t[oldest];
    if (!(df > 0 && dt > 0))
        return -1.0;
    return (1.0 - fraction) * dt / df;
}

void dfle_progress_bar_init(dfle_progress_bar *bar, FILE *out)
{
    bar->out = out;
    bar->started = -1.0;
    bar->last_draw = -1.0;
    bar->drawn = 0;
    dfle_progress_eta_init(&bar->eta);
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
        fprintf(bar->out, "  %s = %.2e -> %.0e",
                st->ratio_name != NULL ? st->ratio_name : "max|dz/dt|/U", st->rate_ratio, st->tol);
    {
        double left = dfle_progress_eta_update(&bar->eta, t, st->fraction);
        if (left >= 0)
            fprintf(bar->out, left < 100 ? "  ETA %.0f s" : "  ETA %.0f min", left < 100 ? left : left / 60);
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
    dfle_progress_eta_init(&bar->eta);
}
