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
 * their own Lua states (lua/drive/).  The sampler, the chain file and
 * its resume are the C library's (dfle/invert_run.h).  This file is the
 * entry point: the table (lua_invert_spec.c), the chain opened or
 * resumed, the point estimate (lua_invert_lsq.c), the sampling on the
 * evaluator of lua_invert_eval.c, the result (lua_invert_result.c).
 * doc/inversion.md has the statistics.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lua/invert/lua_invert_internal.h"

/* The driver's progress, to the host. */
static void hook_progress(void *ud, size_t done, size_t total, size_t failed, double elapsed)
{
    const dfle_lua_host *h = ud;
    h->progress(h->ud, done, total, failed, elapsed);
}

/* The chain's arrays, where the result and the figures read them. */
static void note_chain(inv_run *R)
{
    const dfle_invert_result *r = dfle_invert_result_of(R->inv);
    R->walkers = r->walkers;
    R->steps = r->steps;
    R->burn = r->burn;
    R->have = r->have;
    R->X = r->x;
    R->LP = r->log_post;
    R->LL = r->log_like;
    R->ST = r->proposal;
}

/* The point estimate's values (natural units, NaN for sigma and where
 * it failed) to the driver, which checks them against the priors'
 * bounds with the samples. */
static void give_point(lua_State *L, int lsq_idx, inv_run *R)
{
    double *x = lua_newuserdatauv(L, R->d * sizeof *x, 0);
    dfle_error err;
    for (size_t j = 0; j < R->d; j++)
        x[j] = NAN;
    if (lua_getfield(L, lsq_idx, "values") == LUA_TTABLE)
        for (size_t j = 0; j < R->nmodel; j++) {
            if (lua_getfield(L, -1, R->names[j]) == LUA_TNUMBER)
                x[j] = lua_tonumber(L, -1);
            lua_pop(L, 1);
        }
    lua_pop(L, 1);
    if (dfle_invert_set_point(R->inv, x, &err) != DFLE_OK)
        dfle_lua_raise(L, &err);
    lua_pop(L, 1);
}

/* What says a printed number is not the data's (stranded walkers, prior
 * bounds), on stderr as the run ends: a top-level call only (one inside
 * an ensemble's sample has its own caller to tell). */
static void alert(lua_State *L, const inv_run *R)
{
    const dfle_invert_result *r = dfle_invert_result_of(R->inv);
    if (R->nested)
        return;
    for (size_t k = r->first_alert; k < r->nwarnings; k++)
        dfle_lua_warn(L, "invert", r->warnings[k]);
}

/* A Lua prior density, for the driver's prior-bound rule (the prior's
 * own mass near a bound): called protected, NaN if it raises (the rule
 * then counts the prior as flat). */
static double custom_logpdf(void *ud, size_t j, double x)
{
    inv_run *R = ud;
    lua_State *L = R->L;
    double v = NAN;
    if (!lua_checkstack(L, 4))
        return v;
    lua_getfield(L, R->ctx, "density");
    lua_getfield(L, -1, R->names[j]);
    lua_pushnumber(L, x);
    if (lua_pcall(L, 1, 1, 0) == LUA_OK && lua_type(L, -1) == LUA_TNUMBER)
        v = lua_tonumber(L, -1);
    lua_pop(L, 2);
    return v;
}

static int l_invert(lua_State *L)
{
    const dfle_lua_host *host = dfle_lua_host_of(L);
    lua_Integer call;
    int role, ctx, lsq_idx = 0, st;
    inv_run *R;
    const char *out;
    dfle_error err;
    double t0 = dfle_lua_now();

    lua_settop(L, 1);
    role = dfle_lua_par_enter(L, DFLE_LUA_PAR_INVERT, 1, &call);
    inv_read_spec(L, 1, &R);
    ctx = lua_gettop(L);
    R->nested = role == DFLE_LUA_PAR_NESTED;
    R->L = L;
    R->ctx = ctx;
    R->o.custom_logpdf = custom_logpdf;
    R->o.custom_ud = R;
    lua_getfield(L, ctx, "out");
    out = lua_tostring(L, -1); /* held by ctx */
    lua_pop(L, 1);

    if (role == DFLE_LUA_PAR_EARLIER) {
        /* A worker replaying the script: this inversion is finished. */
        if (out == NULL)
            return luaL_error(L, "dfle.invert: a worker replaying the script for a later parallel "
                                 "call met this inversion, which has no 'out' file to read its "
                                 "result from; give it out = \"...\" (doc/inversion.md)");
        R->o.read_only = 1;
        if (dfle_invert_new(&R->o, &R->inv, &err) != DFLE_OK)
            return dfle_lua_raise(L, &err);
        note_chain(R);
        R->lsq = 0;
        inv_push_result(L, ctx, R, 0, 0);
        return 1;
    }
    /* Nothing new starts once interrupted. */
    dfle_lua_check_interrupt(L, "invert");
    {
        int nw = dfle_lua_par_workers(host, R->o.workers, 0);
        if (host == NULL || host->open_state == NULL || R->nested)
            nw = 1;
        R->o.workers = nw;
    }
    R->o.interrupt = dfle_lua_get_interrupt(L);
    R->o.progress = host != NULL && host->progress != NULL && !R->nested ? hook_progress : NULL;
    R->o.ud = (void *)host;
    /* What made the file, for its comment lines (kept on the stack). */
    if (out != NULL)
        R->o.describe = dfle_lua_push_record(L, "dfle.invert chain: every walker at every step");
    /* The chain file first: another inversion's is refused before the
     * point estimate takes its time. */
    if (dfle_invert_new(&R->o, &R->inv, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    R->o.describe = NULL; /* read while the file was made */
    if (R->lsq && R->nmodel >= 1) {
        dfle_lua_par_depth(L, +1);
        inv_push_lsq(L, ctx, R);
        dfle_lua_par_depth(L, -1);
        lsq_idx = lua_gettop(L);
        /* runs an interrupt cut short are failures to the fit, not the
         * fit: it is left out (the chain, below, does not start) */
        if (dfle_lua_interrupted(L)) {
            lua_pop(L, 1);
            lsq_idx = 0;
        } else {
            give_point(L, lsq_idx, R);
        }
    }
    lua_getfield(L, ctx, "identity");
    st = dfle_lua_evaluator_init(&R->ev, &inv_kind, host, L, ctx, call, lua_tostring(L, -1), &err);
    lua_pop(L, 1);
    if (st != DFLE_OK)
        return dfle_lua_raise(L, &err);
    R->ev_set = 1;
    /* Parallel calls made by build run in the evaluating state. */
    dfle_lua_par_depth(L, +1);
    st = dfle_invert_run(R->inv, &R->ev.ev, &err);
    dfle_lua_par_depth(L, -1);
    if (host != NULL && host->progress_end != NULL && !R->nested)
        host->progress_end(host->ud);
    note_chain(R);
    if (st == DFLE_ECANCELED) {
        /* The whole steps are kept; the result says "interrupted" and has
         * no posterior (nothing of a cut chain is a result). */
        const dfle_invert_result *r = dfle_invert_result_of(R->inv);
        int last = (int)(r->have > 0 ? r->have - 1 : 0);
        if (out != NULL)
            dfle_lua_set_interrupt_note(L, "dfle.invert stopped after step %d of %d; the whole "
                                           "steps are in %s, and running the script again "
                                           "resumes it", last, (int)r->steps, out);
        else
            dfle_lua_set_interrupt_note(L, "dfle.invert stopped after step %d of %d (no 'out' "
                                           "file: the chain is lost)", last, (int)r->steps);
    } else if (st != DFLE_OK) {
        return dfle_lua_raise(L, &err);
    }
    inv_push_result(L, ctx, R, lsq_idx, dfle_lua_now() - t0);
    if (st == DFLE_OK)
        alert(L, R);
    return 1;
}

void dfle_lua_open_invert(lua_State *L)
{
    lua_pushcfunction(L, l_invert);
    lua_setfield(L, -2, "invert");
    inv_open_result(L);
    inv_open_plot(L);
}
