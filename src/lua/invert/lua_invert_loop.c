/*
 * lua_invert_loop.c - dfle.invert's sampling loop: the starting ensemble
 * drawn from the priors, then step after step of the library's ensemble
 * sampler (dfle/mcmc.h), each half-step's proposals evaluated by the
 * worker pool, every walker's row streamed to the chain file.
 *
 * Nothing in here raises: the pool's threads are running, so a failure
 * comes back as -1 with a message, for the entry point to raise once the
 * threads are stopped.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lua/invert/lua_invert_internal.h"

#include "dfle/stream.h"

#define INIT_ROUNDS 100

/* ------------------------------------------------------------------ */
/* The sampling loop: raises nothing; -1 with msg on failure.          */

typedef struct loop {
    double *y, *lp, *ll;   /* K x d, K, K */
    unsigned char *st, *acc;
    char *msgs;            /* K x INV_MSG */
    double *cur_ll;        /* K: the walkers' current log-likelihoods */
    char first[INV_NSTATUS][INV_MSG]; /* first message of each failure */
    size_t failed;         /* failed forward runs this call */
    double t0;
    size_t total;          /* evaluations expected this call */
} loop;

static void note(loop *lp, int status, const char *msg)
{
    if (status >= INV_OUTSIDE && lp->first[status][0] == '\0')
        snprintf(lp->first[status], INV_MSG, "%s", msg);
    if (status >= INV_NOT_CONVERGED)
        lp->failed++;
}

static void progress(lua_State *L, inv_run *R, loop *lp)
{
    const dfle_lua_ensemble_host *h = dfle_lua_ens_host(L);
    if (h != NULL && h->progress != NULL && !R->nested)
        h->progress(h->ud, R->evaluations, lp->total, lp->failed, dfle_lua_ens_now() - lp->t0);
}

/* Write the K rows of step s that the file does not have yet. */
static int write_step(inv_run *R, size_t s, char *msg, size_t msglen)
{
    dfle_error err;
    if (R->file == NULL)
        return 0;
    for (size_t k = 0; k < R->walkers; k++) {
        size_t index = s * R->walkers + k + 1;
        if (dfle_ens_file_done(R->file, index))
            continue; /* a resumed step: the same row is there */
        if (inv_format_row(R, s, k) != 0) {
            snprintf(msg, msglen, "out of memory");
            return -1;
        }
        if (dfle_ens_file_append(R->file, index, R->row, &err) != DFLE_OK) {
            snprintf(msg, msglen, "%s", err.msg);
            return -1;
        }
    }
    return 0;
}

/* The starting ensemble: draws from the prior, drawn again (at most
 * INIT_ROUNDS times) where the posterior is zero. */
static int start(lua_State *L, int ctx, inv_run *R, loop *lp, char *msg, size_t msglen)
{
    const size_t K = R->walkers, d = R->d;
    size_t *idx = malloc(K * sizeof *idx), npend = K, *attempt = calloc(K, sizeof *attempt);
    int rc = -1;
    if (idx == NULL || attempt == NULL) {
        snprintf(msg, msglen, "out of memory");
        goto done;
    }
    for (size_t k = 0; k < K; k++)
        idx[k] = k;
    for (int round = 0; round < INIT_ROUNDS && npend > 0; round++) {
        size_t keep = 0;
        for (size_t i = 0; i < npend; i++) {
            dfle_stream s;
            dfle_stream_init(&s, R->seed, 0, idx[i], attempt[idx[i]] + 1);
            for (size_t j = 0; j < d; j++)
                lp->y[i * d + j] = dfle_prior_draw(&R->prior[j], &s);
        }
        if (inv_pool_eval(L, ctx, R, npend, lp->y, lp->lp, lp->ll, lp->st, lp->msgs, msg,
                          msglen) != 0)
            goto done;
        for (size_t i = 0; i < npend; i++) {
            size_t k = idx[i];
            if (lp->st[i] == INV_ACCEPTED) {
                memcpy(R->X + k * d, lp->y + i * d, d * sizeof *R->X);
                R->LP[k] = lp->lp[i];
                R->LL[k] = lp->ll[i];
                R->ST[k] = INV_INITIAL;
            } else {
                note(lp, lp->st[i], lp->msgs + i * INV_MSG);
                R->init_failed++;
                attempt[k]++;
                if (round == INIT_ROUNDS - 1 && keep == 0) /* name the first */
                    snprintf(msg, msglen, "no starting point with a non-zero posterior for walker "
                             "%zu in %d draws from the prior; the last: %.*s", k + 1,
                             INIT_ROUNDS, INV_MSG, lp->msgs + i * INV_MSG);
                idx[keep++] = k;
            }
        }
        npend = keep;
        progress(L, R, lp);
    }
    if (npend > 0)
        goto done;
    if (write_step(R, 0, msg, msglen) != 0)
        goto done;
    R->have = 1;
    rc = 0;
done:
    free(idx);
    free(attempt);
    return rc;
}

static int run_chain(lua_State *L, int ctx, inv_run *R, loop *lp, char *msg, size_t msglen)
{
    const size_t K = R->walkers, d = R->d, H = K / 2;
    dfle_mcmc_opts o;
    dfle_error err;

    if (R->have == 0 && start(L, ctx, R, lp, msg, msglen) != 0)
        return -1;
    dfle_mcmc_opts_default(&o);
    o.ndim = d;
    o.nwalkers = K;
    o.seed = R->seed;
    o.a = R->a;
    o.log_scale = R->logs;
    if (dfle_mcmc_new(&o, &R->mc, &err) != DFLE_OK ||
        dfle_mcmc_set_state(R->mc, R->have - 1, R->X + (R->have - 1) * K * d,
                            R->LP + (R->have - 1) * K, &err) != DFLE_OK) {
        snprintf(msg, msglen, "%s", err.msg);
        return -1;
    }
    memcpy(lp->cur_ll, R->LL + (R->have - 1) * K, K * sizeof *lp->cur_ll);
    for (size_t s = R->have; s <= R->steps; s++) {
        for (int h = 0; h < 2; h++) {
            if (dfle_mcmc_propose(R->mc, h, lp->y, &err) != DFLE_OK) {
                snprintf(msg, msglen, "%s", err.msg);
                return -1;
            }
            if (inv_pool_eval(L, ctx, R, H, lp->y, lp->lp, lp->ll, lp->st, lp->msgs, msg,
                              msglen) != 0)
                return -1;
            if (dfle_mcmc_accept(R->mc, h, lp->y, lp->lp, lp->acc, &err) != DFLE_OK) {
                snprintf(msg, msglen, "%s", err.msg);
                return -1;
            }
            for (size_t i = 0; i < H; i++) {
                size_t k = (size_t)h * H + i;
                int st = lp->st[i];
                if (st == INV_ACCEPTED) {
                    st = lp->acc[i] ? INV_ACCEPTED : INV_REJECTED;
                    if (lp->acc[i])
                        lp->cur_ll[k] = lp->ll[i];
                } else {
                    note(lp, st, lp->msgs + i * INV_MSG);
                }
                R->ST[s * K + k] = (unsigned char)st;
            }
        }
        memcpy(R->X + s * K * d, dfle_mcmc_x(R->mc), K * d * sizeof *R->X);
        memcpy(R->LP + s * K, dfle_mcmc_lp(R->mc), K * sizeof *R->LP);
        memcpy(R->LL + s * K, lp->cur_ll, K * sizeof *R->LL);
        if (write_step(R, s, msg, msglen) != 0)
            return -1;
        R->have = s + 1;
        progress(L, R, lp);
    }
    return 0;
}

static void *loop_alloc(size_t n, size_t size, int *ok)
{
    void *p = calloc(n ? n : 1, size);
    *ok = *ok && p != NULL;
    return p;
}

int inv_sample(lua_State *L, int ctx, inv_run *R, int nw, lua_Integer call, char *msg,
               size_t msglen)
{
    const size_t K = R->walkers;
    const dfle_lua_ensemble_host *host = dfle_lua_ens_host(L);
    loop lp;
    int ok = 1, rc = 0;

    memset(&lp, 0, sizeof lp);
    lp.y = loop_alloc(K * R->d, sizeof *lp.y, &ok);
    lp.lp = loop_alloc(K, sizeof *lp.lp, &ok);
    lp.ll = loop_alloc(K, sizeof *lp.ll, &ok);
    lp.st = loop_alloc(K, 1, &ok);
    lp.acc = loop_alloc(K, 1, &ok);
    lp.msgs = loop_alloc(K, INV_MSG, &ok);
    lp.cur_ll = loop_alloc(K, sizeof *lp.cur_ll, &ok);
    lp.t0 = dfle_lua_ens_now();
    lp.total = (R->steps + 1 - R->have) * K;
    msg[0] = '\0';
    if (!ok) {
        rc = -1;
        snprintf(msg, msglen, "out of memory");
    }
    if (rc == 0) {
        lua_getfield(L, ctx, "meta");
        rc = inv_pool_start(L, R, nw - 1, call, lua_tostring(L, -1), msg, msglen);
        lua_pop(L, 1);
    }
    /* Parallel calls made by build run in the evaluating state. */
    dfle_lua_par_depth(L, +1);
    if (rc == 0)
        rc = run_chain(L, ctx, R, &lp, msg, msglen);
    dfle_lua_par_depth(L, -1);
    if (inv_pool_stop(R, rc == 0 ? msg : NULL, msglen) != 0)
        rc = -1;
    if (host != NULL && host->progress_end != NULL && !R->nested)
        host->progress_end(host->ud);
    free(lp.y);
    free(lp.lp);
    free(lp.ll);
    free(lp.st);
    free(lp.acc);
    free(lp.msgs);
    free(lp.cur_ll);
    if (rc == 0) {
        /* The first message of each kind of failure, for the result. */
        lua_newtable(L);
        for (int k = INV_OUTSIDE; k < INV_NSTATUS; k++)
            if (lp.first[k][0] != '\0') {
                lua_pushstring(L, lp.first[k]);
                lua_setfield(L, -2, inv_status_name[k]);
            }
        lua_setfield(L, ctx, "failure_messages");
    }
    return rc;
}
