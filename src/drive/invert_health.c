/*
 * invert_health.c - walkers the ensemble left behind.  A walker that
 * starts where the posterior is negligible and every proposal along the
 * lines through it is worse (a sharp posterior seen from a prior bound,
 * with a noise scale fitted to its own misfit) can sit there for the
 * whole chain: its samples then set the tails of the intervals, out to
 * the prior's edge.  The ensemble shows it: its log posterior lies far
 * below the others' and it rarely moves.
 *
 * The test (invert_run.h, doc/inversion.md "Walker health"), over a
 * window of steps: walker k is stranded when its median log posterior
 * lies more than `drop` below the median of the walkers' medians, drop
 * = half the 1 - 1e-6 quantile of chi-square with d degrees of freedom
 * (a d-dimensional Gaussian posterior has all but 1e-6 of its mass
 * within that drop of its peak, so a healthy walker's median is far
 * inside), or when its acceptance is below a quarter of the walkers'
 * median and a binomial count that low has probability < 1e-6.
 *
 * In burn-in (steps 25, 50, 100, ... up to burn, each on the steps
 * since half of it) a stranded walker takes the position of a healthy
 * one, picked by the walker's own stream: an intervention the burn-in
 * forgets, which copies a draw of the current ensemble.  At most a
 * quarter of the walkers (and so many that d + 1 others remain) move at
 * once: more far below the median means the ensemble is still walking
 * in from the prior.
 */
#include "drive/invert_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_cdf.h>

#include "dfle/stream.h"

/* The stream of a move (seed, step, walker, this). */
#define MOVE_STREAM 0x6d6f7665u

int inv_health_init(inv_health *h, size_t K, size_t d, size_t steps)
{
    memset(h, 0, sizeof *h);
    h->K = K;
    h->flag = calloc(K, 1);
    h->acc = calloc(K, sizeof *h->acc);
    h->lp_med = calloc(K, sizeof *h->lp_med);
    h->scratch = calloc(K > steps + 1 ? K : steps + 1, sizeof *h->scratch);
    h->drop = 0.5 * gsl_cdf_chisq_Qinv(1e-6, (double)d);
    if (h->flag == NULL || h->acc == NULL || h->lp_med == NULL || h->scratch == NULL) {
        inv_health_free(h);
        return -1;
    }
    return 0;
}

void inv_health_free(inv_health *h)
{
    free(h->flag);
    free(h->acc);
    free(h->lp_med);
    free(h->scratch);
    memset(h, 0, sizeof *h);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, size_t n)
{
    qsort(v, n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

size_t inv_stranded(const dfle_invert_result *r, size_t s0, size_t s1, inv_health *h)
{
    const size_t K = r->walkers, n = s1 - s0 + 1;
    size_t count = 0;

    for (size_t k = 0; k < K; k++) {
        size_t a = 0;
        for (size_t s = s0; s <= s1; s++) {
            h->scratch[s - s0] = r->log_post[s * K + k];
            a += r->proposal[s * K + k] == DFLE_PROPOSAL_ACCEPTED;
        }
        h->lp_med[k] = median(h->scratch, n);
        h->acc[k] = (double)a / (double)n;
    }
    memcpy(h->scratch, h->lp_med, K * sizeof *h->scratch);
    h->lp_ref = median(h->scratch, K);
    memcpy(h->scratch, h->acc, K * sizeof *h->scratch);
    h->acc_ref = median(h->scratch, K);
    for (size_t k = 0; k < K; k++) {
        double a = h->acc[k] * (double)n;
        int low_lp = h->lp_med[k] < h->lp_ref - h->drop;
        int low_acc = h->acc[k] < 0.25 * h->acc_ref && h->acc_ref > 0 &&
                      gsl_cdf_binomial_P((unsigned)floor(a + 0.5), h->acc_ref, (unsigned)n) < 1e-6;
        h->flag[k] = (unsigned char)(low_lp || low_acc);
        count += h->flag[k];
    }
    return count;
}

int inv_check_step(size_t s, size_t burn)
{
    if (s < 25 || s > burn || s % 25 != 0)
        return 0;
    s /= 25;
    return (s & (s - 1)) == 0; /* 25 times a power of two */
}

size_t inv_move_stranded(inv_run *R, size_t s, double *lp, double *ll, inv_health *h)
{
    dfle_invert_result *r = R->r;
    const size_t K = r->walkers, d = r->d;
    size_t n = inv_stranded(r, s / 2 + 1, s, h), cap = K / 4, healthy = K - n;
    double *x = r->x + s * K * d;

    if ((K - d - 1) / 2 < cap)
        cap = (K - d - 1) / 2;
    if (n == 0 || n > cap)
        return 0;
    for (size_t k = 0; k < K; k++) {
        dfle_stream st;
        size_t pick, j;
        if (!h->flag[k])
            continue;
        dfle_stream_init(&st, R->o.seed, s, k, MOVE_STREAM);
        pick = (size_t)dfle_stream_below(&st, healthy);
        for (j = 0; j < K; j++)
            if (!h->flag[j] && pick-- == 0)
                break;
        memcpy(x + k * d, x + j * d, d * sizeof *x);
        lp[k] = lp[j];
        ll[k] = ll[j];
        r->log_post[s * K + k] = r->log_post[s * K + j];
        r->log_like[s * K + k] = r->log_like[s * K + j];
        r->proposal[s * K + k] = DFLE_PROPOSAL_MOVED;
    }
    return n;
}

/* The moves of the chain, from its rows: a "moved" row took the
 * position of the first other walker of its step with the same one. */
static int collect_moves(dfle_invert_result *r)
{
    const size_t K = r->walkers, d = r->d;
    size_t n = 0;
    for (size_t i = K; i < (r->steps + 1) * K; i++)
        n += r->proposal[i] == DFLE_PROPOSAL_MOVED;
    free(r->moved);
    r->moved = NULL;
    r->nmoved = 0;
    if (n == 0)
        return 0;
    if ((r->moved = calloc(n, sizeof *r->moved)) == NULL)
        return -1;
    for (size_t s = 1; s <= r->steps; s++)
        for (size_t k = 0; k < K; k++) {
            size_t at = s * K + k, j;
            dfle_invert_move *mv;
            if (r->proposal[at] != DFLE_PROPOSAL_MOVED)
                continue;
            for (j = 0; j < K; j++)
                if (j != k && memcmp(r->x + at * d, r->x + (s * K + j) * d,
                                     d * sizeof *r->x) == 0)
                    break;
            mv = &r->moved[r->nmoved++];
            mv->step = s;
            mv->walker = k + 1;
            mv->onto = j < K ? j + 1 : 0;
            mv->lp_gain = r->log_post[at] - r->log_post[at - K];
        }
    return 0;
}

int inv_health_report(inv_run *R)
{
    dfle_invert_result *r = R->r;
    const size_t K = r->walkers, d = r->d, N = r->steps, burn = r->burn;
    const double *post = r->x + (burn + 1) * K * d;
    inv_health h;
    int bad = 0;
    size_t n;

    if (collect_moves(r) != 0 || inv_health_init(&h, K, d, N) != 0)
        return -1;
    r->threshold_lp = h.drop;
    if (r->nmoved > 0) {
        size_t last = r->moved[r->nmoved - 1].step;
        bad |= inv_warn(r, "%zu stranded walker%s moved back into the ensemble during burn-in "
                           "(the last at step %zu of the %zu of burn-in): %s log posterior lay "
                           "far below the others'", r->nmoved, r->nmoved == 1 ? " was" : "s were",
                        last, burn, r->nmoved == 1 ? "its" : "their");
    }
    /* what follows says a number is not what it seems: shown at run time */
    r->first_alert = r->nwarnings;
    /* On fewer steps than INV_HEALTH_MIN_STEPS the ensemble may still be
     * walking in, and a walker that never moved is not yet improbable. */
    n = N >= burn + INV_HEALTH_MIN_STEPS ? inv_stranded(r, burn + 1, N, &h) : 0;
    if (n > 0 && (r->stranded = calloc(n, sizeof *r->stranded)) == NULL)
        n = 0, bad = -1;
    for (size_t k = 0; k < K && n > 0; k++) {
        dfle_invert_walker *w;
        double *med;
        if (!h.flag[k])
            continue;
        w = &r->stranded[r->nstranded];
        if ((med = calloc(d, sizeof *med)) == NULL) {
            bad = -1;
            break;
        }
        r->nstranded++;
        w->walker = k + 1;
        w->acceptance = h.acc[k];
        w->ensemble_acceptance = h.acc_ref;
        w->lp_drop = h.lp_ref - h.lp_med[k];
        w->median = med;
        for (size_t j = 0; j < d; j++) {
            for (size_t s = 0; s < N - burn; s++)
                h.scratch[s] = post[(s * K + k) * d + j];
            med[j] = median(h.scratch, N - burn);
        }
        {
            dfle_text at;
            dfle_text_init(&at);
            for (size_t j = 0; j < d; j++)
                dfle_text_printf(&at, "%s%s = %.4g", j > 0 ? ", " : "", R->o.names[j], med[j]);
            bad |= inv_warn(r, "walker %zu is stranded: after burn-in it accepted %.1f %% of its "
                               "proposals (the walkers' median %.1f %%) and its median log "
                               "posterior lies %.3g below the others' (%.3g strands); its samples "
                               "(median %s) widen the intervals toward them: run with more "
                               "burn-in%s, or another seed",
                            k + 1, 100 * h.acc[k], 100 * h.acc_ref, h.lp_ref - h.lp_med[k],
                            h.drop, at.s != NULL ? at.s : "?",
                            R->o.move_stranded ? "" : " and move_stranded on");
            dfle_text_free(&at);
        }
    }
    inv_health_free(&h);
    return bad;
}
