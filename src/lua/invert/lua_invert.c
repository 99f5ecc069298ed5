/*
 * lua_invert.c - dfle.invert{...}: Bayesian inversion of slope-area data
 * for a model's parameters, and its least-squares point estimate.
 *
 *   local res = dfle.invert{
 *       data = dem:network{ ... },            -- or a profile, a CSV file, {A =, S =}
 *       build = function(p, ch) return dfle.model{ channel = ch, U = p.U, ... } end,
 *       params = { U = {1e-4, 1e-3, log = true}, gamma = {0, 1} },
 *       walkers = 32, steps = 2000, burn = 500, seed = 1, out = "chain.csv",
 *   }
 *
 * The call is a parallel call like dfle.ensemble: on the dfle command,
 * worker threads replay the script up to it and evaluate proposals in
 * their own Lua states (lua_invert_pool.c).  The sampler is the C
 * library's (dfle/mcmc.h), fed one half-ensemble at a time; the chain is
 * streamed to `out` row by row and a run resumes from its last complete
 * step (lua_invert_chain.c).  doc/inversion.md has the statistics.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "lua/invert/lua_invert_internal.h"

#include "dfle/lsq.h"
#include "dfle/stream.h"

#define INIT_ROUNDS 100

/* ------------------------------------------------------------------ */
/* The least-squares point estimate (main state, one run at a time).   */

typedef struct lsq_job {
    lua_State *L;
    int ctx;
    inv_run *R;
    double *x;
} lsq_job;

static int lsq_residuals(void *ud, const double *u, double *r, dfle_error *err)
{
    lsq_job *jb = ud;
    inv_run *R = jb->R;
    for (size_t j = 0; j < R->nmodel; j++) {
        jb->x[j] = R->logs[j] ? exp(u[j]) : u[j];
        if (!(dfle_prior_logpdf(&R->prior[j], jb->x[j]) > -INFINITY))
            return DFLE_EFIT;
    }
    if (inv_residuals(jb->L, jb->ctx, R, jb->x, &R->fwd_seconds, err) != DFLE_OK)
        return DFLE_EFIT;
    R->evaluations++;
    memcpy(r, R->r, R->nobs * sizeof *r);
    return DFLE_OK;
}

static void set_named(lua_State *L, int names, size_t j, double v)
{
    lua_geti(L, names, (lua_Integer)j + 1);
    lua_pushnumber(L, v);
    lua_settable(L, -3);
}

/* Push the point estimate's table (never raises on a failed fit: the
 * table says why). */
static void push_lsq(lua_State *L, int ctx, inv_run *R)
{
    const size_t n = R->nmodel;
    double *u0, *step, *lo, *hi, *u, *cov, *x;
    dfle_lsq_opts o;
    dfle_lsq_info info;
    dfle_error err;
    lsq_job jb;
    int st, names, t;

    u0 = lua_newuserdatauv(L, 7 * n * sizeof *u0 + n * n * sizeof *u0, 0);
    step = u0 + n;
    lo = step + n;
    hi = lo + n;
    u = hi + n;
    x = u + n;
    cov = x + 2 * n;
    for (size_t j = 0; j < n; j++) {
        u0[j] = dfle_prior_center(&R->prior[j]);
        step[j] = dfle_prior_width(&R->prior[j]);
        dfle_prior_bounds(&R->prior[j], &lo[j], &hi[j]);
    }
    memset(&o, 0, sizeof o);
    o.n = n;
    o.m = R->nobs;
    o.u0 = u0;
    o.step = step;
    o.lo = lo;
    o.hi = hi;
    o.sigma = R->sigma_free ? 0 : R->sigma;
    jb.L = L;
    jb.ctx = ctx;
    jb.R = R;
    jb.x = x;
    lua_getfield(L, ctx, "names");
    names = lua_gettop(L);
    st = dfle_lsq_fit(&o, lsq_residuals, &jb, u, cov, &info, &err);
    lua_createtable(L, 0, 12);
    t = lua_gettop(L);
    lua_pushboolean(L, st == DFLE_OK && info.converged), lua_setfield(L, t, "converged");
    lua_pushinteger(L, (lua_Integer)info.evaluations), lua_setfield(L, t, "evaluations");
    lua_pushinteger(L, (lua_Integer)info.failed), lua_setfield(L, t, "failed");
    if (st != DFLE_OK) {
        lua_pushstring(L, err.msg), lua_setfield(L, t, "why");
        lua_remove(L, names);
        lua_remove(L, t - 2); /* the scratch */
        return;
    }
    if (info.why[0] != '\0')
        lua_pushstring(L, info.why), lua_setfield(L, t, "why");
    lua_pushnumber(L, info.rss), lua_setfield(L, t, "rss");
    lua_pushnumber(L, sqrt(info.rss / (double)(R->nobs - n))), lua_setfield(L, t, "sigma");
    lua_pushboolean(L, info.cov_ok), lua_setfield(L, t, "cov_ok");
    /* values, sd (delta method for log-scaled ones) and 95 % intervals */
    {
        const char *keys[5] = {"values", "sd", "lo95", "hi95", "log_scale"};
        for (int k = 0; k < 5; k++) {
            lua_createtable(L, 0, (int)n);
            for (size_t j = 0; j < n; j++) {
                double sdu = sqrt(cov[j * n + j]), v = R->logs[j] ? exp(u[j]) : u[j];
                if (k == 4) {
                    lua_geti(L, names, (lua_Integer)j + 1);
                    lua_pushboolean(L, R->logs[j]);
                    lua_settable(L, -3);
                    continue;
                }
                set_named(L, names, j,
                          k == 0   ? v
                          : k == 1 ? (R->logs[j] ? v * sdu : sdu)
                          : k == 2 ? (R->logs[j] ? exp(u[j] - 1.96 * sdu) : u[j] - 1.96 * sdu)
                                   : (R->logs[j] ? exp(u[j] + 1.96 * sdu) : u[j] + 1.96 * sdu));
            }
            lua_setfield(L, t, keys[k]);
        }
    }
    /* covariance and correlation in the sampler's coordinates (ln x for
     * log-scaled parameters), rows in the order of `names` */
    for (int k = 0; k < 2; k++) {
        lua_createtable(L, (int)n, 0);
        for (size_t a = 0; a < n; a++) {
            lua_createtable(L, (int)n, 0);
            for (size_t b = 0; b < n; b++) {
                double c = cov[a * n + b];
                if (k == 1)
                    c /= sqrt(cov[a * n + a] * cov[b * n + b]);
                lua_pushnumber(L, c);
                lua_rawseti(L, -2, (lua_Integer)b + 1);
            }
            lua_rawseti(L, -2, (lua_Integer)a + 1);
        }
        lua_setfield(L, t, k == 0 ? "cov" : "corr");
    }
    lua_remove(L, names);
    lua_remove(L, t - 2); /* the scratch */
}

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

/* Open the chain file: a longer chain in it is fine (its first steps
 * serve), so the file's own length sets how many rows it may hold. */
/* The first setting in which two identity lines differ, as
 * "seed=3 in the file, seed=4 here". */
static void push_difference(lua_State *L, const char *file, const char *mine)
{
    const char *a = file, *b = mine;
    while (*a != '\0' && *b != '\0') {
        size_t la = strcspn(a, " "), lb = strcspn(b, " ");
        if (la != lb || strncmp(a, b, la) != 0) {
            lua_pushfstring(L, "%s in the file, %s here", lua_pushlstring(L, a, la),
                            lua_pushlstring(L, b, lb));
            lua_replace(L, -3);
            lua_pop(L, 1);
            return;
        }
        a += la + (a[la] == ' ');
        b += lb + (b[lb] == ' ');
    }
    lua_pushliteral(L, "the file's first lines differ");
}

/* Open the chain file: a longer chain in it is fine (its first steps
 * serve), so the file's own length sets how many rows it may hold. */
static void open_chain(lua_State *L, int ctx, inv_run *R, const char *path)
{
    size_t n = (R->steps + 1) * R->walkers;
    dfle_error err;
    char msg[DFLE_ERROR_MSG_MAX];
    lua_getfield(L, ctx, "meta");
    lua_getfield(L, ctx, "header");
    if (R->resume) {
        dfle_ens_table *t = NULL;
        struct stat sb;
        if (stat(path, &sb) == 0 && S_ISREG(sb.st_mode) && sb.st_size > 0) {
            int same;
            if (dfle_ens_table_read(path, &t, &err) != DFLE_OK)
                luaL_error(L, "dfle.invert: %s is not a chain of dfle.invert (%s); remove it, pass "
                              "resume = false, or choose another 'out'", path, err.msg);
            same = strcmp(t->meta, lua_tostring(L, -2)) == 0 &&
                   strcmp(t->header, lua_tostring(L, -1)) == 0;
            if (t->nrows > 0 && t->index[t->nrows - 1] > n)
                n = t->index[t->nrows - 1];
            if (!same)
                lua_pushstring(L, t->meta);
            dfle_ens_table_free(t);
            if (!same) {
                push_difference(L, lua_tostring(L, -1), lua_tostring(L, -3));
                luaL_error(L, "dfle.invert: %s holds another inversion's chain (%s); remove it, "
                              "pass resume = false, or choose another 'out'", path,
                           lua_tostring(L, -1));
            }
        }
    }
    if (dfle_ens_file_open(path, lua_tostring(L, -2), lua_tostring(L, -1), n, R->resume,
                           &R->file, &err) != DFLE_OK)
        luaL_error(L, "dfle.invert: %s", err.msg);
    lua_pop(L, 2);
    if (dfle_ens_file_ndone(R->file) > 0 && inv_read_chain(R, path, msg, sizeof msg) != 0)
        luaL_error(L, "dfle.invert: %s", msg);
}

static int l_invert(lua_State *L)
{
    const dfle_lua_ensemble_host *host = dfle_lua_ens_host(L);
    lua_Integer call;
    int role, ctx, lsq_idx = 0, ok = 1, rc = 0;
    inv_run *R;
    const char *out;
    size_t K, ran = 0, have0;
    loop lp;
    char msg[DFLE_ERROR_MSG_MAX];
    double t0 = dfle_lua_ens_now();

    lua_settop(L, 1);
    role = dfle_lua_par_enter(L, DFLE_LUA_PAR_INVERT, 1, &call);
    inv_read_spec(L, 1, &R);
    ctx = lua_gettop(L);
    R->nested = role == DFLE_LUA_PAR_NESTED;
    K = R->walkers;
    lua_getfield(L, ctx, "out");
    out = lua_tostring(L, -1); /* held by ctx */
    lua_pop(L, 1);
    R->X = calloc((R->steps + 1) * K * R->d, sizeof *R->X);
    R->LP = calloc((R->steps + 1) * K, sizeof *R->LP);
    R->LL = calloc((R->steps + 1) * K, sizeof *R->LL);
    R->ST = calloc((R->steps + 1) * K, 1);
    if (R->X == NULL || R->LP == NULL || R->LL == NULL || R->ST == NULL)
        return luaL_error(L, "dfle.invert: out of memory for the chain");

    if (role == DFLE_LUA_PAR_EARLIER) {
        /* A worker replaying the script: this inversion is finished. */
        if (out == NULL)
            return luaL_error(L, "dfle.invert: a worker replaying the script for a later parallel "
                                 "call met this inversion, which has no 'out' file to read its "
                                 "result from; give it out = \"...\" (doc/inversion.md)");
        if (inv_read_chain(R, out, msg, sizeof msg) != 0)
            return luaL_error(L, "dfle.invert: %s", msg);
        if (R->have < R->steps + 1)
            return luaL_error(L, "dfle.invert: %s is not a finished chain", out);
        R->lsq = 0;
        inv_push_result(L, ctx, R, 0, 0, 0);
        return 1;
    }
    if (out != NULL)
        open_chain(L, ctx, R, out);
    have0 = R->have;
    if (R->lsq && R->nmodel >= 1) {
        dfle_lua_par_depth(L, +1);
        push_lsq(L, ctx, R);
        dfle_lua_par_depth(L, -1);
        lsq_idx = lua_gettop(L);
    }
    if (R->steps > 0 && R->have < R->steps + 1) {
        int nw = host != NULL && host->workers > 0 ? host->workers
                 : R->workers > 0                  ? R->workers
                                                   : dfle_lua_ens_cores();
        if (host == NULL || host->open_state == NULL || R->nested)
            nw = 1;
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
            snprintf(msg, sizeof msg, "out of memory");
        }
        if (rc == 0) {
            lua_getfield(L, ctx, "meta");
            rc = inv_pool_start(L, R, nw - 1, call, lua_tostring(L, -1), msg, sizeof msg);
            lua_pop(L, 1);
        }
        /* Parallel calls made by build run in the evaluating state. */
        dfle_lua_par_depth(L, +1);
        if (rc == 0)
            rc = run_chain(L, ctx, R, &lp, msg, sizeof msg);
        dfle_lua_par_depth(L, -1);
        if (inv_pool_stop(R, rc == 0 ? msg : NULL, sizeof msg) != 0)
            rc = -1;
        {
            const dfle_lua_ensemble_host *h = host;
            if (h != NULL && h->progress_end != NULL && !R->nested)
                h->progress_end(h->ud);
        }
        ran = (R->have > 0 ? R->have - 1 : 0) - (have0 > 0 ? have0 - 1 : 0);
        free(lp.y);
        free(lp.lp);
        free(lp.ll);
        free(lp.st);
        free(lp.acc);
        free(lp.msgs);
        free(lp.cur_ll);
        if (rc != 0) {
            dfle_ens_file *f = R->file;
            R->file = NULL;
            dfle_ens_file_close(f, 0, NULL);
            return luaL_error(L, "dfle.invert: %s%s", msg,
                              out != NULL ? " (the rows written are kept; run again to resume)"
                                          : "");
        }
        /* The first message of each kind of failure, for the result. */
        lua_newtable(L);
        for (int k = INV_OUTSIDE; k < INV_NSTATUS; k++)
            if (lp.first[k][0] != '\0') {
                lua_pushstring(L, lp.first[k]);
                lua_setfield(L, -2, inv_status_name[k]);
            }
        lua_setfield(L, ctx, "failure_messages");
    }
    if (R->file != NULL) {
        dfle_ens_file *f = R->file;
        dfle_error err;
        R->file = NULL;
        if (dfle_ens_file_close(f, 1, &err) != DFLE_OK)
            return luaL_error(L, "dfle.invert: %s", err.msg);
    }
    inv_push_result(L, ctx, R, lsq_idx, dfle_lua_ens_now() - t0, ran);
    return 1;
}

void dfle_lua_open_invert(lua_State *L)
{
    lua_pushcfunction(L, l_invert);
    lua_setfield(L, -2, "invert");
    inv_open_result(L);
    inv_open_plot(L);
}
