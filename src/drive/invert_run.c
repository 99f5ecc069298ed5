/*
 * invert_run.c - dfle_invert_run (invert_run.h): the options, the
 * starting ensemble drawn from the priors, then step after step of the
 * ensemble sampler (dfle/mcmc.h), each half-step's proposals evaluated
 * on the worker pool, every walker's row streamed to the chain file.
 *
 * The priors' own densities are evaluated here; a proposal outside their
 * support never reaches the evaluator.  Results go to their proposal's
 * slot, whichever worker evaluated it, and every random number comes
 * from a stream keyed by (seed, step, walker): the chain is the same for
 * any number of workers.
 */
#include "drive/invert_internal.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/mcmc.h"
#include "dfle/pool.h"
#include "dfle/stream.h"

#define DEFAULT_WALKERS 32
#define INIT_ROUNDS 100

void dfle_invert_opts_default(dfle_invert_opts *o)
{
    memset(o, 0, sizeof *o);
    o->burn = DFLE_INVERT_BURN_DEFAULT;
    o->seed = 1;
    o->a = 2;
    o->resume = 1;
    o->workers = 1;
    o->move_stranded = 1;
}

int inv_resolve(const dfle_invert_opts *o, dfle_invert_opts *r, dfle_error *err)
{
    int st;
    *r = *o;
    if (o->d < 1 || o->names == NULL || o->priors == NULL)
        return dfle_error_set(err, DFLE_EINVAL,
                              "invert: no free parameters: name at least one to infer");
    for (size_t j = 0; j < o->d; j++)
        if ((st = dfle_prior_check(&o->priors[j], o->names[j], err)) != DFLE_OK) {
            char msg[DFLE_ERROR_MSG_MAX];
            snprintf(msg, sizeof msg, "%s", err != NULL ? err->msg : "");
            return dfle_error_set(err, st, "invert: parameter %s", msg);
        }
    if (r->burn == DFLE_INVERT_BURN_DEFAULT)
        r->burn = o->steps / 4;
    if (o->steps > 0 && r->burn >= o->steps)
        return dfle_error_set(err, DFLE_EINVAL,
                              "invert: burn (%zu) must be less than steps (%zu): the samples after "
                              "burn-in are the posterior", r->burn, o->steps);
    if (r->walkers == 0) {
        r->walkers = DEFAULT_WALKERS;
        while (r->walkers < 2 * o->d)
            r->walkers += 2;
    }
    if (r->walkers % 2 != 0 || r->walkers < 2 * o->d || r->walkers < 4)
        return dfle_error_set(err, DFLE_EINVAL,
                              "invert: walkers must be even and at least twice the %zu free "
                              "parameters (got %zu)", o->d, r->walkers);
    if ((double)(o->steps + 1) * (double)r->walkers * (double)(o->d + 3) > 4e8)
        return dfle_error_set(err, DFLE_EINVAL,
                              "invert: %zu walkers x %zu steps would hold %.1f GB of chain in "
                              "memory; use fewer steps or walkers", r->walkers, o->steps,
                              (double)(o->steps + 1) * (double)r->walkers *
                                  (double)(o->d + 3) * 8e-9);
    if (o->seed > 4294967295UL)
        return dfle_error_set(err, DFLE_EINVAL, "invert: seed must be 0 .. 4294967295");
    if (!(o->a > 1))
        return dfle_error_set(err, DFLE_EINVAL, "invert: a (the stretch scale) must be > 1 (got %g)",
                              o->a);
    if (o->workers < 0)
        return dfle_error_set(err, DFLE_EINVAL, "invert: workers must be >= 1 (got %d)",
                              o->workers);
    if (r->workers == 0)
        r->workers = 1;
    if (o->read_only && o->out == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "invert: reading a chain needs its file ('out')");
    return DFLE_OK;
}

int dfle_invert_check(const dfle_invert_opts *o, dfle_error *err)
{
    dfle_invert_opts r;
    return inv_resolve(o, &r, err);
}

/* ------------------------------------------------------------------ */
/* A batch of proposals: the pool's task.                              */

typedef struct batch {
    const dfle_invert_opts *o;
    size_t n;
    const double *y;     /* n x d                                  */
    double *lp, *ll;     /* n                                      */
    unsigned char *st;   /* n: enum dfle_proposal (ACCEPTED: evaluated) */
    char *msgs;          /* n x DFLE_INVERT_MSG                    */
    double *lprior;      /* n: the priors' own log density         */
    pthread_mutex_t lock;
    size_t next;
    double fwd;          /* the evaluators' CPU time               */
} batch;

static void set_msg(batch *b, size_t i, const char *m)
{
    dfle_drive_copy(b->msgs + i * DFLE_INVERT_MSG, DFLE_INVERT_MSG, m);
}

static int batch_next(void *ud, size_t *item, double *x)
{
    batch *b = ud;
    const size_t d = b->o->d;
    for (;;) {
        size_t i;
        double lprior = 0;
        pthread_mutex_lock(&b->lock);
        i = b->next < b->n ? b->next++ : b->n;
        pthread_mutex_unlock(&b->lock);
        if (i == b->n)
            return 0;
        for (size_t j = 0; j < d; j++)
            lprior += dfle_prior_logpdf(&b->o->priors[j], b->y[i * d + j]);
        b->lprior[i] = lprior;
        if (!(lprior > -INFINITY)) { /* not run: outside the priors' support */
            b->st[i] = DFLE_PROPOSAL_OUTSIDE;
            b->lp[i] = b->ll[i] = -INFINITY;
            set_msg(b, i, "outside the prior");
            continue;
        }
        memcpy(x, b->y + i * d, d * sizeof *x);
        *item = i;
        return 1;
    }
}

static int batch_done(void *ud, size_t i, const dfle_eval_out *out, dfle_error *err)
{
    batch *b = ud;
    const dfle_invert_opts *o = b->o;
    (void)err;
    b->lp[i] = b->ll[i] = -INFINITY;
    switch (out->status) {
    case DFLE_EVAL_OK: {
        double lprior = b->lprior[i], ll = out->y[0];
        if (!(ll > -INFINITY)) {
            b->st[i] = DFLE_PROPOSAL_INVALID;
            set_msg(b, i, "the likelihood is zero or NaN");
            break;
        }
        for (size_t j = 0; j < o->d; j++)
            if (o->priors[j].kind == DFLE_PRIOR_CUSTOM)
                lprior += out->y[1 + j];
        if (!(lprior > -INFINITY)) {
            b->st[i] = DFLE_PROPOSAL_OUTSIDE;
            set_msg(b, i, "zero prior density");
            break;
        }
        b->st[i] = DFLE_PROPOSAL_ACCEPTED;
        b->ll[i] = ll;
        b->lp[i] = lprior + ll;
        b->msgs[i * DFLE_INVERT_MSG] = '\0';
        break;
    }
    case DFLE_EVAL_OUTSIDE:
        b->st[i] = DFLE_PROPOSAL_OUTSIDE;
        set_msg(b, i, out->reason[0] ? out->reason : "zero prior density");
        break;
    case DFLE_EVAL_NOT_CONVERGED:
        b->st[i] = DFLE_PROPOSAL_NOT_CONVERGED;
        set_msg(b, i, out->reason);
        break;
    case DFLE_EVAL_INVALID:
        b->st[i] = DFLE_PROPOSAL_INVALID;
        set_msg(b, i, out->reason);
        break;
    default:
        b->st[i] = DFLE_PROPOSAL_ERROR;
        set_msg(b, i, out->reason);
        break;
    }
    pthread_mutex_lock(&b->lock);
    b->fwd += out->seconds;
    pthread_mutex_unlock(&b->lock);
    return DFLE_OK;
}

/* ------------------------------------------------------------------ */
/* The sampling loop.                                                  */

typedef struct loop {
    inv_run *R;
    dfle_pool *pool;
    batch b;
    double *y;        /* K x d proposals                       */
    unsigned char *acc;
    double *cur_lp;   /* K: the walkers' log posteriors, exact (the
                       * chain's are rounded as the file has them)   */
    double *cur_ll;   /* K: their log-likelihoods, exact             */
    size_t failed;    /* failed forward runs this call           */
    double t0;
    size_t total;     /* evaluations expected this call          */
} loop;

/* Evaluate the n proposals in lp->y: DFLE_OK, DFLE_ECANCELED or an error. */
static int evaluate(loop *lp, size_t n, dfle_error *err)
{
    dfle_pool_task t;
    int st;
    memset(&t, 0, sizeof t);
    lp->b.n = n;
    lp->b.next = 0;
    lp->b.y = lp->y;
    t.next = batch_next;
    t.done = batch_done;
    t.ud = &lp->b;
    t.total = n;
    st = dfle_pool_run(lp->pool, &t, err);
    lp->R->r->evaluations += n;
    lp->R->r->forward_seconds += lp->b.fwd;
    lp->b.fwd = 0;
    return st;
}

static void note(loop *lp, int status, const char *msg)
{
    dfle_invert_result *r = lp->R->r;
    if (status >= DFLE_PROPOSAL_OUTSIDE && r->failure[status][0] == '\0')
        dfle_drive_copy(r->failure[status], DFLE_INVERT_MSG, msg);
    if (status >= DFLE_PROPOSAL_NOT_CONVERGED)
        lp->failed++;
}

static void progress(loop *lp)
{
    const dfle_invert_opts *o = &lp->R->o;
    if (o->progress != NULL)
        o->progress(o->ud, lp->R->r->evaluations, lp->total, lp->failed,
                    dfle_drive_now() - lp->t0);
}

/* The starting ensemble: draws from the prior, drawn again (at most
 * INIT_ROUNDS times) where the posterior is zero. */
static int start(loop *lp, dfle_error *err)
{
    inv_run *R = lp->R;
    dfle_invert_result *r = R->r;
    const size_t K = r->walkers, d = r->d;
    size_t *idx = malloc(K * sizeof *idx), npend = K, *attempt = calloc(K, sizeof *attempt);
    char why[DFLE_ERROR_MSG_MAX] = "";
    int st = DFLE_ENOMEM;

    if (idx == NULL || attempt == NULL) {
        dfle_error_set(err, st, "invert: out of memory");
        goto done;
    }
    for (size_t k = 0; k < K; k++)
        idx[k] = k;
    for (int round = 0; round < INIT_ROUNDS && npend > 0; round++) {
        size_t keep = 0;
        for (size_t i = 0; i < npend; i++) {
            dfle_stream s;
            dfle_stream_init(&s, R->o.seed, 0, idx[i], attempt[idx[i]] + 1);
            for (size_t j = 0; j < d; j++)
                lp->y[i * d + j] = inv_round(dfle_prior_draw(&R->o.priors[j], &s), INV_X_DIGITS);
        }
        if ((st = evaluate(lp, npend, err)) != DFLE_OK)
            goto done;
        for (size_t i = 0; i < npend; i++) {
            size_t k = idx[i];
            const char *m = lp->b.msgs + i * DFLE_INVERT_MSG;
            if (lp->b.st[i] == DFLE_PROPOSAL_ACCEPTED) {
                memcpy(r->x + k * d, lp->y + i * d, d * sizeof *r->x);
                lp->cur_lp[k] = lp->b.lp[i];
                lp->cur_ll[k] = lp->b.ll[i];
                r->log_post[k] = inv_round(lp->b.lp[i], INV_LP_DIGITS);
                r->log_like[k] = inv_round(lp->b.ll[i], INV_LP_DIGITS);
                r->proposal[k] = DFLE_PROPOSAL_INITIAL;
            } else {
                note(lp, lp->b.st[i], m);
                r->init_failed++;
                attempt[k]++;
                if (round == INIT_ROUNDS - 1 && keep == 0) /* name the first */
                    snprintf(why, sizeof why, "no starting point with a non-zero posterior for "
                             "walker %zu in %d draws from the prior; the last: %.*s", k + 1,
                             INIT_ROUNDS, DFLE_INVERT_MSG, m);
                idx[keep++] = k;
            }
        }
        npend = keep;
        progress(lp);
    }
    if (npend > 0) {
        st = dfle_error_set(err, DFLE_EFIT, "invert: %s", why);
        goto done;
    }
    if ((st = inv_write_step(R, 0, err)) != DFLE_OK)
        goto done;
    r->have = 1;
done:
    free(idx);
    free(attempt);
    return st;
}

/* What a resume says when a row read back does not give, at its
 * position, the log densities the file has for it. */
static int refuse_row(loop *lp, size_t s, size_t k, size_t i, dfle_error *err)
{
    inv_run *R = lp->R;
    const dfle_invert_result *r = R->r;
    const size_t at = s * r->walkers + k;
    char place[300];
    inv_row_place(R, s, k, place, sizeof place);
    if (lp->b.st[i] != DFLE_PROPOSAL_ACCEPTED)
        return dfle_error_set(err, DFLE_EINVAL,
                              "invert: %s: step %zu, walker %zu: the file gives this row a "
                              "non-zero posterior, but its position now has zero posterior "
                              "(%.*s): the file was edited, or the model or data changed; "
                              "remove it, pass resume = false, or choose another 'out'",
                              place, s, k + 1, DFLE_INVERT_MSG, lp->b.msgs + i * DFLE_INVERT_MSG);
    if (fabs(lp->b.lp[i] - r->log_post[at]) > 1e-9 * (1 + fabs(lp->b.lp[i])) ||
        fabs(lp->b.ll[i] - r->log_like[at]) > 1e-9 * (1 + fabs(lp->b.ll[i])))
        return dfle_error_set(err, DFLE_EINVAL,
                              "invert: %s: step %zu, walker %zu: log_post %.10g and log_like "
                              "%.10g in the file, but its position gives %.10g and %.10g "
                              "now: the file was edited, or the model or data changed; "
                              "remove it, pass resume = false, or choose another 'out'",
                              place, s, k + 1, r->log_post[at], r->log_like[at], lp->b.lp[i],
                              lp->b.ll[i]);
    return DFLE_OK;
}

/* A chain read back continues from its last step: its walkers' log
 * densities are evaluated again (the sampler needs them exact, and they
 * must be what the file says: a file edited, or a model changed since,
 * would continue a chain of another posterior).  So is the row with the
 * largest log_post (it becomes the result's best sample): an edit that
 * raised one row's log densities together would else freeze its walker
 * and be reported as the best fit.  A complete chain is checked the
 * same way before it is summarised. */
static int recompute_last(loop *lp, dfle_error *err)
{
    inv_run *R = lp->R;
    dfle_invert_result *r = R->r;
    const size_t K = r->walkers, d = r->d, s = r->have - 1;
    size_t best = 0;
    int st;

    for (size_t i = 1; i < r->have * K; i++)
        if (r->log_post[i] > r->log_post[best])
            best = i;
    if (best < s * K) {
        memcpy(lp->y, r->x + best * d, d * sizeof *lp->y);
        if ((st = evaluate(lp, 1, err)) != DFLE_OK ||
            (st = refuse_row(lp, best / K, best % K, 0, err)) != DFLE_OK)
            return st;
    }
    memcpy(lp->y, r->x + s * K * d, K * d * sizeof *lp->y);
    if ((st = evaluate(lp, K, err)) != DFLE_OK)
        return st;
    for (size_t k = 0; k < K; k++) {
        if ((st = refuse_row(lp, s, k, k, err)) != DFLE_OK)
            return st;
        lp->cur_lp[k] = lp->b.lp[k];
        lp->cur_ll[k] = lp->b.ll[k];
    }
    return DFLE_OK;
}

static int run_chain(loop *lp, dfle_error *err)
{
    inv_run *R = lp->R;
    dfle_invert_result *r = R->r;
    const size_t K = r->walkers, d = r->d, H = K / 2;
    dfle_mcmc_opts mo;
    dfle_mcmc *mc = NULL;
    int *logs = malloc(d * sizeof *logs);
    inv_health health;
    int st, health_ok = inv_health_init(&health, K, d, r->steps) == 0;

    if (logs == NULL || !health_ok) {
        free(logs);
        if (health_ok)
            inv_health_free(&health);
        return dfle_error_set(err, DFLE_ENOMEM, "invert: out of memory");
    }
    if ((st = r->have == 0 ? start(lp, err) : recompute_last(lp, err)) != DFLE_OK)
        goto done;
    for (size_t j = 0; j < d; j++)
        logs[j] = dfle_prior_log_scale(&R->o.priors[j]);
    dfle_mcmc_opts_default(&mo);
    mo.ndim = d;
    mo.nwalkers = K;
    mo.seed = R->o.seed;
    mo.a = R->o.a;
    mo.log_scale = logs;
    if ((st = dfle_mcmc_new(&mo, &mc, err)) != DFLE_OK ||
        (st = dfle_mcmc_set_state(mc, r->have - 1, r->x + (r->have - 1) * K * d, lp->cur_lp,
                                  err)) != DFLE_OK) {
        dfle_drive_prefix(err, "invert");
        goto done;
    }
    for (size_t s = r->have; s <= r->steps; s++) {
        for (int h = 0; h < 2; h++) {
            if ((st = dfle_mcmc_propose(mc, h, lp->y, err)) != DFLE_OK)
                goto done;
            /* the chain's positions are its file's numbers */
            for (size_t i = 0; i < H * d; i++)
                lp->y[i] = inv_round(lp->y[i], INV_X_DIGITS);
            if ((st = evaluate(lp, H, err)) != DFLE_OK)
                goto done; /* interrupted or failed: this step is not written */
            if ((st = dfle_mcmc_accept(mc, h, lp->y, lp->b.lp, lp->acc, err)) != DFLE_OK)
                goto done;
            for (size_t i = 0; i < H; i++) {
                size_t k = (size_t)h * H + i;
                int p = lp->b.st[i];
                if (p == DFLE_PROPOSAL_ACCEPTED) {
                    p = lp->acc[i] ? DFLE_PROPOSAL_ACCEPTED : DFLE_PROPOSAL_REJECTED;
                    if (lp->acc[i])
                        lp->cur_ll[k] = lp->b.ll[i];
                } else {
                    note(lp, p, lp->b.msgs + i * DFLE_INVERT_MSG);
                }
                r->proposal[s * K + k] = (unsigned char)p;
            }
        }
        memcpy(r->x + s * K * d, dfle_mcmc_x(mc), K * d * sizeof *r->x);
        memcpy(lp->cur_lp, dfle_mcmc_lp(mc), K * sizeof *lp->cur_lp);
        for (size_t k = 0; k < K; k++) {
            r->log_post[s * K + k] = inv_round(lp->cur_lp[k], INV_LP_DIGITS);
            r->log_like[s * K + k] = inv_round(lp->cur_ll[k], INV_LP_DIGITS);
        }
        /* in burn-in, stranded walkers back into the ensemble */
        if (R->o.move_stranded && inv_check_step(s, r->burn) &&
            inv_move_stranded(R, s, lp->cur_lp, lp->cur_ll, &health) > 0 &&
            (st = dfle_mcmc_set_state(mc, s, r->x + s * K * d, lp->cur_lp, err)) != DFLE_OK) {
            dfle_drive_prefix(err, "invert");
            goto done;
        }
        if ((st = inv_write_step(R, s, err)) != DFLE_OK)
            goto done;
        r->have = s + 1;
        progress(lp);
    }
    st = DFLE_OK;
done:
    dfle_mcmc_free(mc);
    free(logs);
    inv_health_free(&health);
    inv_forget_partial(R);
    return st;
}

static void *zalloc(size_t n, size_t size, int *ok)
{
    void *p = calloc(n ? n : 1, size);
    *ok = *ok && p != NULL;
    return p;
}

/* Sample from r->have to the last step on a pool of o->workers. */
static int sample(inv_run *R, const dfle_evaluator *ev, dfle_error *err)
{
    const size_t K = R->r->walkers, d = R->r->d;
    dfle_pool_opts po;
    dfle_error e2 = {0};
    loop lp;
    int ok = 1, st, st2;

    memset(&lp, 0, sizeof lp);
    lp.R = R;
    lp.b.o = &R->o;
    lp.y = zalloc(K * d, sizeof *lp.y, &ok);
    lp.b.lp = zalloc(K, sizeof *lp.b.lp, &ok);
    lp.b.ll = zalloc(K, sizeof *lp.b.ll, &ok);
    lp.b.st = zalloc(K, 1, &ok);
    lp.b.msgs = zalloc(K, DFLE_INVERT_MSG, &ok);
    lp.b.lprior = zalloc(K, sizeof *lp.b.lprior, &ok);
    lp.acc = zalloc(K, 1, &ok);
    lp.cur_lp = zalloc(K, sizeof *lp.cur_lp, &ok);
    lp.cur_ll = zalloc(K, sizeof *lp.cur_ll, &ok);
    lp.t0 = dfle_drive_now();
    lp.total = (R->r->steps + 1 - R->r->have) * K;
    pthread_mutex_init(&lp.b.lock, NULL);
    st = ok ? DFLE_OK : dfle_error_set(err, DFLE_ENOMEM, "invert: out of memory");
    if (st == DFLE_OK) {
        dfle_pool_opts_default(&po);
        po.caller = 1; /* the calling thread evaluates too */
        po.threads = R->o.workers - 1;
        po.ninputs = d;
        po.noutputs = 1 + d;
        po.interrupt = R->o.interrupt;
        st = dfle_pool_new(ev, &po, &lp.pool, err);
    }
    if (st == DFLE_OK) {
        st = run_chain(&lp, err);
        st2 = dfle_pool_free(lp.pool, &e2);
        if (st == DFLE_OK && st2 != DFLE_OK) {
            st = st2;
            if (err != NULL)
                *err = e2;
        }
    }
    pthread_mutex_destroy(&lp.b.lock);
    free(lp.y);
    free(lp.b.lp);
    free(lp.b.ll);
    free(lp.b.st);
    free(lp.b.msgs);
    free(lp.b.lprior);
    free(lp.acc);
    free(lp.cur_lp);
    free(lp.cur_ll);
    return st;
}

/* Drop the summaries of an earlier call (a chain run further). */
static void unsummarize(dfle_invert_result *r)
{
    free(r->summary);
    free(r->tau);
    free(r->acceptance_walkers);
    for (size_t k = 0; k < r->nwarnings; k++)
        free(r->warnings[k]);
    free(r->warnings);
    for (size_t k = 0; k < r->nstranded; k++)
        free(r->stranded[k].median);
    free(r->stranded);
    free(r->moved);
    free(r->bounded);
    r->summary = NULL;
    r->tau = r->acceptance_walkers = NULL;
    r->warnings = NULL;
    r->nwarnings = 0;
    r->stranded = NULL;
    r->nstranded = 0;
    r->moved = NULL;
    r->nmoved = 0;
    r->bounded = NULL;
    r->first_alert = 0;
    r->complete = 0;
}

static void result_free(dfle_invert_result *r)
{
    if (r == NULL)
        return;
    unsummarize(r);
    free(r->x);
    free(r->log_post);
    free(r->log_like);
    free(r->proposal);
    free(r);
}

static int new_result(const dfle_invert_opts *o, dfle_invert_result **out, dfle_error *err)
{
    const size_t rows = (o->steps + 1) * o->walkers;
    dfle_invert_result *r = calloc(1, sizeof *r);
    int ok = r != NULL;
    if (ok) {
        r->d = o->d;
        r->walkers = o->walkers;
        r->steps = o->steps;
        r->burn = o->burn;
        r->x = zalloc(rows * o->d, sizeof *r->x, &ok);
        r->log_post = zalloc(rows, sizeof *r->log_post, &ok);
        r->log_like = zalloc(rows, sizeof *r->log_like, &ok);
        r->proposal = zalloc(rows, 1, &ok);
    }
    if (!ok) {
        result_free(r);
        return dfle_error_set(err, DFLE_ENOMEM, "invert: out of memory for the chain");
    }
    *out = r;
    return DFLE_OK;
}

void dfle_invert_free(dfle_invert *inv)
{
    if (inv == NULL)
        return;
    dfle_ens_file_close(inv->R.file, 0, NULL);
    dfle_text_free(&inv->R.row);
    inv_forget_partial(&inv->R);
    free(inv->R.line);
    free(inv->R.point);
    result_free(inv->R.r);
    free(inv);
}

const dfle_invert_result *dfle_invert_result_of(const dfle_invert *inv) { return inv->R.r; }

int dfle_invert_set_point(dfle_invert *inv, const double *x, dfle_error *err)
{
    inv_run *R = &inv->R;
    if (x == NULL) {
        free(R->point);
        R->point = NULL;
        return DFLE_OK;
    }
    if (R->point == NULL && (R->point = malloc(R->o.d * sizeof *R->point)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "invert: out of memory");
    memcpy(R->point, x, R->o.d * sizeof *R->point);
    return DFLE_OK;
}

int dfle_invert_new(const dfle_invert_opts *opts, dfle_invert **out, dfle_error *err)
{
    dfle_invert *inv;
    inv_run *R;
    int st;

    *out = NULL;
    inv = calloc(1, sizeof *inv);
    if (inv == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "invert: out of memory");
    R = &inv->R;
    if ((st = inv_resolve(opts, &R->o, err)) != DFLE_OK ||
        (st = new_result(&R->o, &R->r, err)) != DFLE_OK)
        goto fail;
    if (R->o.read_only) {
        /* A chain finished before (a worker replaying a script passes it). */
        if ((st = inv_read_chain(R, R->o.out, err)) != DFLE_OK)
            goto fail;
        if (R->r->have < R->r->steps + 1) {
            st = dfle_error_set(err, DFLE_EINVAL, "invert: %s is not a finished chain", R->o.out);
            goto fail;
        }
        if (inv_summarize(R) != 0) {
            st = dfle_error_set(err, DFLE_ENOMEM, "invert: out of memory for the summaries");
            goto fail;
        }
    } else if (R->o.out != NULL && (st = inv_open_chain(R, err)) != DFLE_OK) {
        goto fail;
    }
    *out = inv;
    return DFLE_OK;
fail:
    dfle_invert_free(inv);
    return st;
}

int dfle_invert_run(dfle_invert *inv, const dfle_evaluator *ev, dfle_error *err)
{
    inv_run *R = &inv->R;
    size_t have0 = R->r->have;
    int st = DFLE_OK;

    if (R->o.read_only)
        return DFLE_OK;
    unsummarize(R->r);
    R->r->ran = 0;
    R->r->interrupted = 0;
    /* A chain read back whole is checked as a resumed one is (its last
     * step and best row evaluated again) before it is summarised. */
    if (R->o.steps > 0 && (R->r->have < R->o.steps + 1 || R->line != NULL)) {
        if ((st = dfle_evaluator_check(ev, err)) != DFLE_OK)
            return st;
        st = sample(R, ev, err);
        R->r->ran = (R->r->have > 0 ? R->r->have - 1 : 0) - (have0 > 0 ? have0 - 1 : 0);
        if (st == DFLE_ECANCELED) {
            R->r->interrupted = 1;
            st = dfle_error_set(err, st, "invert: interrupted after step %zu of %zu%s%s%s",
                                R->r->have > 0 ? R->r->have - 1 : 0, R->o.steps,
                                R->o.out != NULL ? "; the whole steps are in " : "",
                                R->o.out != NULL ? R->o.out : "",
                                R->o.out != NULL ? ", and running again resumes it" : "");
        } else if (st != DFLE_OK && st != DFLE_EINVAL && R->o.out != NULL) {
            /* (a file refused, DFLE_EINVAL, says what to do itself) */
            char msg[DFLE_ERROR_MSG_MAX];
            dfle_drive_prefix(err, "invert");
            dfle_drive_copy(msg, sizeof msg, err != NULL ? err->msg : "failed");
            dfle_error_set(err, st, "%s (the rows written are kept; run again to resume)", msg);
        } else if (st != DFLE_OK) {
            dfle_drive_prefix(err, "invert");
        }
    }
    if (R->file != NULL) {
        /* Sorted only when whole: the rows are in order already, and an
         * interrupt's message must not wait for the rewrite. */
        dfle_error e2;
        int st2 = dfle_ens_file_close(R->file, st == DFLE_OK, &e2);
        R->file = NULL;
        if (st == DFLE_OK && st2 != DFLE_OK) {
            st = st2;
            if (err != NULL)
                *err = e2;
            dfle_drive_prefix(err, "invert");
        }
    }
    if ((st == DFLE_OK || st == DFLE_ECANCELED) && inv_summarize(R) != 0 && st == DFLE_OK)
        st = dfle_error_set(err, DFLE_ENOMEM, "invert: out of memory for the summaries");
    return st;
}
