/*
 * invert_summary.c - what a finished chain says and how far to trust
 * it: the samples after burn-in summarised (medians, intervals), their
 * autocorrelation times and effective size, acceptance, the tally of
 * failed proposals, the best sample, the stranded walkers
 * (invert_health.c) and the marginals held by a prior bound
 * (invert_bounds.c), and warnings in sentences a user reads beside the
 * numbers (doc/inversion.md, "Diagnostics").
 */
#include "drive/invert_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int inv_warn(dfle_invert_result *r, const char *fmt, ...)
{
    char buf[600], **w, *s;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    w = realloc(r->warnings, (r->nwarnings + 1) * sizeof *w);
    if (w == NULL)
        return -1;
    r->warnings = w;
    if ((s = malloc(strlen(buf) + 1)) == NULL)
        return -1;
    strcpy(s, buf);
    r->warnings[r->nwarnings++] = s;
    return 0;
}

/* The diagnostics' warnings, in the order a user should read them. */
static int warnings(dfle_invert_result *r, int windowed, double tau_use)
{
    const size_t N = r->steps, K = r->walkers, npost = N - r->burn;
    const double tau_max = r->tau_max;
    size_t acc = 0, fails;
    int bad = 0;

    for (size_t i = K; i < (N + 1) * K; i++)
        acc += r->proposal[i] == DFLE_PROPOSAL_ACCEPTED;
    if (!windowed || !isfinite(tau_max))
        bad |= inv_warn(r, "the chain is too short to estimate the autocorrelation time (%zu steps "
                       "after burn-in); the intervals are unreliable: run many more steps",
                    npost);
    else if ((double)npost < 50 * tau_use && npost < 100)
        bad |= inv_warn(r, "the chain is too short: %zu steps after burn-in are fewer than 50 "
                       "autocorrelation times (tau = %.1f steps, itself underestimated on so "
                       "short a chain); the intervals are rough: run many more steps",
                    npost, tau_max);
    else if ((double)npost < 50 * tau_use)
        bad |= inv_warn(r, "the chain is too short: %zu steps after burn-in are fewer than 50 "
                       "autocorrelation times (tau = %.1f steps); the intervals are rough, run "
                       "at least %.0f steps",
                    npost, tau_max, ceil(50 * tau_use + (double)r->burn));
    if (isfinite(tau_max) && (double)r->burn < 2 * tau_max)
        bad |= inv_warn(r, "burn-in (%zu steps) is shorter than 2 autocorrelation times (tau = %.1f): "
                       "the start may still show in the samples",
                    r->burn, tau_max);
    if ((double)acc < 0.1 * (double)(N * K))
        bad |= inv_warn(r, "low acceptance (%.3f): the walkers rarely move; see the failures and the "
                       "priors",
                    (double)acc / (double)(N * K));
    fails = r->tally[DFLE_PROPOSAL_NOT_CONVERGED] + r->tally[DFLE_PROPOSAL_INVALID] +
            r->tally[DFLE_PROPOSAL_ERROR];
    if ((double)fails > 0.05 * (double)(N * K))
        bad |= inv_warn(r, "%.1f %% of the proposals failed in the forward model (%zu not converged, "
                       "%zu invalid profiles, %zu errors); they count as zero likelihood",
                    100.0 * (double)fails / (double)(N * K), r->tally[DFLE_PROPOSAL_NOT_CONVERGED],
                    r->tally[DFLE_PROPOSAL_INVALID], r->tally[DFLE_PROPOSAL_ERROR]);
    return bad;
}

int inv_summarize(inv_run *R)
{
    dfle_invert_result *r = R->r;
    const size_t K = r->walkers, d = r->d, N = r->steps, burn = r->burn;
    size_t npost, m, acc = 0;
    const double *post;
    double tau_use;
    int windowed = 1;

    /* (a complete chain read back and interrupted while its last step
     * was evaluated again is not yet checked: no posterior either) */
    r->complete = N >= 1 && r->have == N + 1 && !r->interrupted;
    if (!r->complete) {
        int bad = N < 1            ? 0
                  : r->interrupted ? inv_warn(r, "interrupted after step %zu of %zu: a cut "
                                                 "chain has no posterior; running again "
                                                 "resumes it", r->have > 0 ? r->have - 1 : 0, N)
                                   : inv_warn(r, "the chain is not complete");
        r->first_alert = r->nwarnings;
        return bad;
    }
    npost = N - burn;
    m = npost * K;
    post = r->x + (burn + 1) * K * d;
    r->nsamples = m;
    r->summary = calloc(d, sizeof *r->summary);
    r->tau = calloc(d, sizeof *r->tau);
    r->acceptance_walkers = calloc(K, sizeof *r->acceptance_walkers);
    if (r->summary == NULL || r->tau == NULL || r->acceptance_walkers == NULL)
        return -1;
    for (size_t j = 0; j < d; j++)
        dfle_summarize(post + j, m, d, &r->summary[j], NULL);
    /* autocorrelation times of the samples after burn-in */
    for (size_t j = 0; j < d; j++)
        r->tau[j] = NAN;
    if (npost >= 2)
        dfle_mcmc_autocorr(post, npost, K, d, 5.0, r->tau, &windowed, NULL);
    r->tau_max = 0;
    for (size_t j = 0; j < d; j++)
        if (isnan(r->tau[j]) || r->tau[j] > r->tau_max)
            r->tau_max = isnan(r->tau[j]) ? INFINITY : r->tau[j];
    /* An estimate below 1 step (a few steps after burn-in give tau = 0 by
     * chance: the lag-1 correlation of two values is -1/2) counts as 1,
     * so that a short chain is never "converged" with more effective
     * samples than samples. */
    tau_use = fmax(r->tau_max, 1.0);
    r->ess = isfinite(tau_use) ? (size_t)((double)m / tau_use) : 0;
    /* acceptance and failures over steps 1 .. N */
    for (size_t k = 0; k < K; k++) {
        size_t a = 0;
        for (size_t s = 1; s <= N; s++)
            a += r->proposal[s * K + k] == DFLE_PROPOSAL_ACCEPTED;
        acc += a;
        r->acceptance_walkers[k] = (double)a / (double)N;
    }
    r->acceptance = (double)acc / (double)(N * K);
    memset(r->tally, 0, sizeof r->tally);
    for (size_t i = K; i < (N + 1) * K; i++)
        r->tally[r->proposal[i]]++;
    r->best = 0;
    for (size_t i = 0; i < (N + 1) * K; i++)
        if (r->log_post[i] > r->log_post[r->best])
            r->best = i;
    /* what to trust: emcee's rule of thumb, N > 50 tau */
    r->converged = windowed && isfinite(tau_use) && (double)npost >= 50 * tau_use;
    if (warnings(r, windowed, tau_use) != 0)
        return -1;
    /* what the numbers rest on: the walkers' health, then the priors' bounds */
    if (inv_health_report(R) != 0 || inv_bounds(R) != 0)
        return -1;
    return 0;
}
