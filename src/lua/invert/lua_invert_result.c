/*
 * lua_invert_result.c - what dfle.invert returns: the posterior samples
 * after burn-in, their summaries, the diagnostics that say how far to
 * trust them (autocorrelation times, acceptance, failures, warnings), the
 * point estimate, and res:predict{}, the posterior-predictive slopes.
 *
 * The result is a plain table with a metatable (methods, tostring); the
 * inversion's context (the problem, the build function, the chain in C)
 * stays reachable from it through a weak-keyed registry table, so that
 * predictions can run the forward model again.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_cdf.h>

#include "lua/invert/lua_invert_internal.h"

#include "dfle/mcmc_diag.h"

static const char ctx_key = 'r'; /* registry: weak table result -> context */

int inv_result_ctx(lua_State *L, int idx)
{
    idx = lua_absindex(L, idx);
    if (!lua_istable(L, idx) || !lua_getmetatable(L, idx))
        luaL_argerror(L, idx, "expected the result of dfle.invert");
    luaL_getmetatable(L, INV_RESULT);
    if (!lua_rawequal(L, -1, -2))
        luaL_argerror(L, idx, "expected the result of dfle.invert");
    lua_pop(L, 2);
    lua_rawgetp(L, LUA_REGISTRYINDEX, &ctx_key);
    lua_pushvalue(L, idx);
    lua_rawget(L, -2);
    lua_remove(L, -2);
    if (!lua_istable(L, -1))
        luaL_argerror(L, idx, "this inversion's context is gone");
    return lua_gettop(L);
}

static void set_num(lua_State *L, const char *k, double v)
{
    lua_pushnumber(L, v);
    lua_setfield(L, -2, k);
}

static void push_summary(lua_State *L, const dfle_summary *s)
{
    lua_createtable(L, 0, 8);
    set_num(L, "median", s->median);
    set_num(L, "mean", s->mean);
    set_num(L, "sd", s->sd);
    set_num(L, "lo68", s->lo68);
    set_num(L, "hi68", s->hi68);
    set_num(L, "lo95", s->lo95);
    set_num(L, "hi95", s->hi95);
}

static void add_warning(lua_State *L, int warn, const char *fmt, ...)
{
    char buf[600];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    lua_pushstring(L, buf);
    lua_rawseti(L, warn, (lua_Integer)lua_rawlen(L, warn) + 1);
}

/* res.stranded (the walkers stranded after burn-in) and res.moved (those
 * moved back in burn-in), arrays of tables. */
static void push_health(lua_State *L, const dfle_invert_result *r, int res, int names)
{
    lua_createtable(L, (int)r->nstranded, 0);
    for (size_t i = 0; i < r->nstranded; i++) {
        const dfle_invert_walker *w = &r->stranded[i];
        lua_createtable(L, 0, 5);
        lua_pushinteger(L, (lua_Integer)w->walker), lua_setfield(L, -2, "walker");
        set_num(L, "acceptance", w->acceptance);
        set_num(L, "ensemble_acceptance", w->ensemble_acceptance);
        set_num(L, "lp_drop", w->lp_drop);
        lua_createtable(L, 0, (int)r->d);
        for (size_t j = 0; j < r->d; j++) {
            lua_geti(L, names, (lua_Integer)j + 1);
            lua_pushnumber(L, w->median[j]);
            lua_settable(L, -3);
        }
        lua_setfield(L, -2, "median");
        lua_rawseti(L, -2, (lua_Integer)i + 1);
    }
    lua_setfield(L, res, "stranded");
    lua_createtable(L, (int)r->nmoved, 0);
    for (size_t i = 0; i < r->nmoved; i++) {
        const dfle_invert_move *mv = &r->moved[i];
        lua_createtable(L, 0, 4);
        lua_pushinteger(L, (lua_Integer)mv->step), lua_setfield(L, -2, "step");
        lua_pushinteger(L, (lua_Integer)mv->walker), lua_setfield(L, -2, "walker");
        lua_pushinteger(L, (lua_Integer)mv->onto), lua_setfield(L, -2, "onto");
        set_num(L, "lp_gain", mv->lp_gain);
        lua_rawseti(L, -2, (lua_Integer)i + 1);
    }
    lua_setfield(L, res, "moved");
    lua_pushnumber(L, r->threshold_lp);
    lua_setfield(L, res, "strand_drop");
}

void inv_push_result(lua_State *L, int ctx, inv_run *R, int lsq_idx, double elapsed)
{
    const dfle_invert_result *r = dfle_invert_result_of(R->inv);
    const size_t K = r->walkers, d = r->d, N = r->steps;
    int res, names, warn;

    lua_newtable(L);
    res = lua_gettop(L);
    luaL_setmetatable(L, INV_RESULT);
    lua_getfield(L, ctx, "names");
    names = lua_gettop(L);
    lua_pushvalue(L, names), lua_setfield(L, res, "names");
    lua_newtable(L);
    warn = lua_gettop(L);
    lua_pushinteger(L, (lua_Integer)K), lua_setfield(L, res, "walkers");
    lua_pushinteger(L, (lua_Integer)N), lua_setfield(L, res, "steps");
    lua_pushinteger(L, (lua_Integer)r->burn), lua_setfield(L, res, "burn");
    lua_pushinteger(L, (lua_Integer)R->o.seed), lua_setfield(L, res, "seed");
    lua_pushinteger(L, (lua_Integer)r->ran), lua_setfield(L, res, "ran");
    /* "complete", or "interrupted" (then no posterior: the whole steps
     * are in the file, and running again resumes them) */
    lua_pushstring(L, r->interrupted ? "interrupted" : r->complete || N == 0 ? "complete"
                                                                             : "incomplete");
    lua_setfield(L, res, "reason");
    lua_pushinteger(L, (lua_Integer)(r->have > 0 ? r->have - 1 : 0));
    lua_setfield(L, res, "have");
    lua_pushinteger(L, (lua_Integer)(r->evaluations + R->lsq_evaluations));
    lua_setfield(L, res, "evaluations");
    lua_pushnumber(L, r->forward_seconds + R->lsq_seconds);
    lua_setfield(L, res, "forward_seconds");
    lua_pushnumber(L, elapsed), lua_setfield(L, res, "elapsed");
    lua_pushinteger(L, (lua_Integer)r->init_failed), lua_setfield(L, res, "init_failed");
    lua_getfield(L, ctx, "out"), lua_setfield(L, res, "file");
    lua_getfield(L, ctx, "data"), lua_setfield(L, res, "data");
    /* the first message of each kind of failure (of this call) */
    lua_newtable(L);
    for (int k = DFLE_PROPOSAL_OUTSIDE; k <= DFLE_PROPOSAL_ERROR; k++)
        if (r->failure[k][0] != '\0') {
            lua_pushstring(L, r->failure[k]);
            lua_setfield(L, -2, dfle_proposal_name(k));
        }
    lua_setfield(L, res, "failure_messages");
    if (!R->sigma_free)
        lua_pushnumber(L, R->sigma), lua_setfield(L, res, "sigma");

    if (r->complete) {
        const size_t m = r->nsamples;
        const double *post = r->x + (r->burn + 1) * K * d;
        /* samples after burn-in, step by step, walker by walker */
        lua_createtable(L, 0, (int)d + 2);
        for (size_t j = 0; j < d; j++) {
            lua_createtable(L, (int)m, 0);
            for (size_t i = 0; i < m; i++) {
                lua_pushnumber(L, post[i * d + j]);
                lua_rawseti(L, -2, (lua_Integer)i + 1);
            }
            lua_geti(L, names, (lua_Integer)j + 1);
            lua_insert(L, -2);
            lua_settable(L, -3);
        }
        for (int k = 0; k < 2; k++) {
            const double *v = (k == 0 ? r->log_post : r->log_like) + (r->burn + 1) * K;
            lua_createtable(L, (int)m, 0);
            for (size_t i = 0; i < m; i++) {
                lua_pushnumber(L, v[i]);
                lua_rawseti(L, -2, (lua_Integer)i + 1);
            }
            lua_setfield(L, -2, k == 0 ? "log_post" : "log_like");
        }
        lua_setfield(L, res, "samples");
        lua_pushinteger(L, (lua_Integer)m), lua_setfield(L, res, "nsamples");
        lua_createtable(L, 0, (int)d);
        for (size_t j = 0; j < d; j++) {
            lua_geti(L, names, (lua_Integer)j + 1);
            push_summary(L, &r->summary[j]);
            if (r->bounded != NULL && r->bounded[j] != DFLE_BOUND_NONE) {
                lua_pushstring(L, dfle_bound_name(r->bounded[j]));
                lua_setfield(L, -2, "bounded");
            }
            lua_settable(L, -3);
        }
        lua_setfield(L, res, "summary");
        push_health(L, r, res, names);
        lua_createtable(L, 0, (int)d);
        for (size_t j = 0; j < d; j++) {
            lua_geti(L, names, (lua_Integer)j + 1);
            lua_pushnumber(L, r->tau[j]);
            lua_settable(L, -3);
        }
        lua_setfield(L, res, "tau");
        lua_pushnumber(L, r->tau_max), lua_setfield(L, res, "tau_max");
        lua_pushinteger(L, (lua_Integer)r->ess), lua_setfield(L, res, "ess");
        lua_createtable(L, (int)K, 0);
        for (size_t k = 0; k < K; k++) {
            lua_pushnumber(L, r->acceptance_walkers[k]);
            lua_rawseti(L, -2, (lua_Integer)k + 1);
        }
        lua_setfield(L, res, "acceptance_walkers");
        lua_pushnumber(L, r->acceptance), lua_setfield(L, res, "acceptance");
        lua_createtable(L, 0, (int)d + 1);
        for (size_t j = 0; j < d; j++) {
            lua_geti(L, names, (lua_Integer)j + 1);
            lua_pushnumber(L, r->x[r->best * d + j]);
            lua_settable(L, -3);
        }
        set_num(L, "log_post", r->log_post[r->best]);
        set_num(L, "log_like", r->log_like[r->best]);
        lua_setfield(L, res, "best");
        lua_pushboolean(L, r->converged);
        lua_setfield(L, res, "converged");
    }
    /* the driver's warnings, then the problem's */
    for (size_t k = 0; k < r->nwarnings; k++)
        add_warning(L, warn, "%s", r->warnings[k]);
    lua_createtable(L, 0, 5);
    for (int k = DFLE_PROPOSAL_OUTSIDE; k <= DFLE_PROPOSAL_ERROR; k++) {
        lua_pushinteger(L, (lua_Integer)r->tally[k]);
        lua_setfield(L, -2, dfle_proposal_name(k));
    }
    lua_setfield(L, res, "failures");
    lua_getfield(L, ctx, "data");
    if (lua_getfield(L, -1, "outside") == LUA_TNUMBER && lua_tointeger(L, -1) > 0)
        add_warning(L, warn, "%d data bins lie outside the model channel's drainage areas and "
                             "were left out", (int)lua_tointeger(L, -1));
    lua_pop(L, 2);
    if (lsq_idx != 0) {
        lua_pushvalue(L, lsq_idx);
        lua_setfield(L, res, "lsq");
        if (lua_getfield(L, lsq_idx, "converged") == LUA_TBOOLEAN && !lua_toboolean(L, -1)) {
            lua_getfield(L, lsq_idx, "why");
            add_warning(L, warn, "the least-squares point estimate did not converge: %s",
                        lua_tostring(L, -1) ? lua_tostring(L, -1) : "?");
            lua_pop(L, 1);
        }
        lua_pop(L, 1);
    }
    lua_pushvalue(L, warn), lua_setfield(L, res, "warnings");
    /* the context, for predictions */
    lua_rawgetp(L, LUA_REGISTRYINDEX, &ctx_key);
    lua_pushvalue(L, res);
    lua_pushvalue(L, ctx);
    lua_rawset(L, -3);
    lua_pop(L, 1);
    lua_settop(L, res);
}

/* ------------------------------------------------------------------ */
/* res:predict{ n = 100, A = {...} }: the model's slopes at areas A for
 * n draws spread evenly over the samples after burn-in, and their
 * quantiles; obs_* add the noise of each draw's sigma (the band a new
 * set of binned slopes would fall in). */

enum { NOISE = 20 }; /* noise values per draw in the observation band */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static int l_predict(lua_State *L)
{
    double nd = 100;
    const dfle_lua_param nums[] = {{"n", &nd}};
    static const char *const other[] = {"A", NULL};
    int ctx, out;
    inv_run *R;
    size_t n, nA = 120, ok = 0, npost, K, d;
    double *A, *S, *row, *col, *noisy;

    lua_settop(L, 2);
    ctx = inv_result_ctx(L, 1);
    dfle_lua_read_params(L, 2, "inversion:predict", nums, 1, other);
    n = (size_t)dfle_lua_check_whole(L, nd, "inversion:predict", "n", 1, 100000);
    lua_getfield(L, ctx, "box");
    R = luaL_checkudata(L, -1, INV_BOX);
    lua_pop(L, 1);
    K = R->walkers;
    d = R->d;
    if (R->steps < 1 || R->have < R->steps + 1)
        return luaL_error(L, "dfle.inversion:predict: there are no posterior samples (steps = 0 "
                             "or an unfinished chain)");
    npost = (R->steps - R->burn) * K;
    if (lua_istable(L, 2) && lua_getfield(L, 2, "A") != LUA_TNIL) {
        A = dfle_lua_check_array(L, -1, "inversion:predict: A", &nA);
        if (nA < 1)
            return luaL_error(L, "dfle.inversion:predict: A is empty");
    } else {
        double lo = HUGE_VAL, hi = -HUGE_VAL;
        for (size_t i = 0; i < R->nobs; i++) {
            lo = fmin(lo, R->A_obs[i]);
            hi = fmax(hi, R->A_obs[i]);
        }
        A = lua_newuserdatauv(L, nA * sizeof *A, 0);
        for (size_t i = 0; i < nA; i++)
            A[i] = lo * pow(hi / lo, (double)i / (double)(nA - 1));
        A[nA - 1] = hi;
    }
    if (n > npost)
        n = npost;
    S = lua_newuserdatauv(L, (n * (NOISE + 1) + 1) * nA * sizeof *S, 0);
    noisy = S + n * nA;
    row = noisy + NOISE * n * nA;
    col = lua_newuserdatauv(L, NOISE * n * sizeof *col, 0);
    for (size_t i = 0; i < n; i++) {
        /* draws spread evenly over the samples after burn-in */
        size_t at = (R->burn + 1) * K + (size_t)(((double)i + 0.5) * (double)npost / (double)n);
        const double *x = R->X + at * d;
        double sigma = R->sigma_free ? x[d - 1] : R->sigma;
        if (inv_predict_at(L, ctx, R, x, nA, A, row) != DFLE_EVAL_OK)
            continue;
        /* The noise at the NOISE quantiles of N(0, 1), the same at every
         * area: a smooth band, and no random numbers. */
        for (size_t q = 0; q < nA; q++) {
            S[ok * nA + q] = row[q];
            for (int c = 0; c < NOISE; c++)
                noisy[(NOISE * ok + (size_t)c) * nA + q] =
                    row[q] * exp(sigma * gsl_cdf_ugaussian_Pinv((c + 0.5) / NOISE));
        }
        ok++;
    }
    lua_newtable(L);
    out = lua_gettop(L);
    dfle_lua_push_array(L, A, nA), lua_setfield(L, out, "A");
    lua_pushinteger(L, (lua_Integer)ok), lua_setfield(L, out, "n");
    lua_pushinteger(L, (lua_Integer)(n - ok)), lua_setfield(L, out, "failed");
    if (ok == 0)
        return luaL_error(L, "dfle.inversion:predict: every forward run failed");
    {
        static const char *const keys[] = {"median", "lo68", "hi68", "lo95", "hi95",
                                           "obs_lo68", "obs_hi68", "obs_lo95", "obs_hi95"};
        static const double ps[] = {0.5, 0.15865525393145707, 0.8413447460685429, 0.025, 0.975,
                                    0.15865525393145707, 0.8413447460685429, 0.025, 0.975};
        for (int k = 0; k < 9; k++) {
            size_t m = k < 5 ? ok : NOISE * ok;
            const double *src = k < 5 ? S : noisy;
            lua_createtable(L, (int)nA, 0);
            for (size_t q = 0; q < nA; q++) {
                for (size_t i = 0; i < m; i++)
                    col[i] = src[i * nA + q];
                qsort(col, m, sizeof *col, cmp_double);
                lua_pushnumber(L, dfle_quantile_sorted(col, m, ps[k]));
                lua_rawseti(L, -2, (lua_Integer)q + 1);
            }
            lua_setfield(L, out, keys[k]);
        }
    }
    return 1;
}

/* tostring(res): the summary a user reads first. */
static int l_tostring(lua_State *L)
{
    char line[800];
    lua_Integer nn;
    dfle_lua_text parts;
    luaL_checktype(L, 1, LUA_TTABLE);
    lua_settop(L, 1);
    lua_getfield(L, 1, "names");    /* 2 */
    lua_getfield(L, 1, "summary");  /* 3 */
    lua_getfield(L, 1, "tau");      /* 4 */
    lua_getfield(L, 1, "lsq");      /* 5 */
    dfle_lua_text_init(L, &parts);  /* 6 */
    nn = lua_istable(L, 2) ? (lua_Integer)lua_rawlen(L, 2) : 0;
    lua_getfield(L, 1, "walkers");
    lua_getfield(L, 1, "steps");
    lua_getfield(L, 1, "burn");
    lua_getfield(L, 1, "acceptance");
    lua_getfield(L, 1, "reason");
    lua_getfield(L, 1, "have");
    lua_getfield(L, 1, "file");
    if (lua_isstring(L, -3) && strcmp(lua_tostring(L, -3), "interrupted") == 0) {
        /* a cut chain has no posterior: say so first, and what was kept */
        const char *file = lua_tostring(L, -1);
        snprintf(line, sizeof line, "dfle.invert: %d walkers x %d steps, interrupted after step "
                 "%d: no posterior; %s%s%s\n", (int)lua_tointeger(L, -7),
                 (int)lua_tointeger(L, -6), (int)lua_tointeger(L, -2),
                 file != NULL ? "the whole steps are in " : "no 'out' file: the chain is lost",
                 file != NULL ? file : "", file != NULL ? ", and running again resumes it" : "");
    } else {
        snprintf(line, sizeof line, "dfle.invert: %d walkers x %d steps (burn-in %d), "
                 "acceptance %.3f\n", (int)lua_tointeger(L, -7), (int)lua_tointeger(L, -6),
                 (int)lua_tointeger(L, -5), lua_tonumber(L, -4));
    }
    lua_pop(L, 7);
    dfle_lua_text_str(L, &parts, line);
    if (lua_istable(L, 3) && lua_istable(L, 4)) {
        snprintf(line, sizeof line, "  %-10s %12s %27s %27s %8s\n", "parameter", "median",
                 "68 % interval", "95 % interval", "tau");
        dfle_lua_text_str(L, &parts, line);
        for (lua_Integer j = 1; j <= nn; j++) {
            static const char *const keys[5] = {"median", "lo68", "hi68", "lo95", "hi95"};
            double v[5], t;
            const char *name, *bound;
            lua_geti(L, 2, j);
            name = lua_tostring(L, -1);
            lua_getfield(L, 4, name);
            t = lua_tonumber(L, -1);
            lua_pop(L, 1);
            lua_getfield(L, 3, name);
            for (int k = 0; k < 5; k++) {
                lua_getfield(L, -1, keys[k]);
                v[k] = lua_tonumber(L, -1);
                lua_pop(L, 1);
            }
            /* an interval a prior's bound holds is marked where it is read */
            lua_getfield(L, -1, "bounded");
            bound = lua_tostring(L, -1);
            snprintf(line, sizeof line, "  %-10s %12.4g   [%11.4g, %11.4g]   [%11.4g, %11.4g] "
                     "%8.1f%s%s\n", name ? name : "?", v[0], v[1], v[2], v[3], v[4], t,
                     bound != NULL ? "  bounded: " : "", bound != NULL ? bound : "");
            lua_pop(L, 3);
            dfle_lua_text_str(L, &parts, line);
        }
    }
    if (lua_istable(L, 5)) {
        lua_getfield(L, 5, "values");
        if (lua_istable(L, -1)) {
            dfle_lua_text_str(L, &parts, "  least squares:");
            for (lua_Integer j = 1; j <= nn; j++) {
                lua_geti(L, 2, j);
                lua_getfield(L, -2, lua_tostring(L, -1));
                if (lua_isnumber(L, -1)) {
                    snprintf(line, sizeof line, " %s = %.4g", lua_tostring(L, -2),
                             lua_tonumber(L, -1));
                    lua_pop(L, 2);
                    dfle_lua_text_str(L, &parts, line);
                } else {
                    lua_pop(L, 2);
                }
            }
            dfle_lua_text_str(L, &parts, "\n");
        }
        lua_pop(L, 1);
    }
    /* the tally is the whole chain's, which a cut one is not */
    lua_getfield(L, 1, lua_istable(L, 3) ? "failures" : "(none)");
    if (lua_istable(L, -1)) {
        dfle_lua_text_str(L, &parts, "  proposals:");
        for (int k = DFLE_PROPOSAL_OUTSIDE; k <= DFLE_PROPOSAL_ERROR; k++) {
            lua_getfield(L, -1, dfle_proposal_name(k));
            snprintf(line, sizeof line, " %s %d", dfle_proposal_name(k), (int)lua_tointeger(L, -1));
            lua_pop(L, 1);
            dfle_lua_text_str(L, &parts, line);
        }
        dfle_lua_text_str(L, &parts, "\n");
    }
    lua_pop(L, 1);
    lua_getfield(L, 1, "warnings");
    for (lua_Integer k = 1, nw = lua_istable(L, -1) ? (lua_Integer)lua_rawlen(L, -1) : 0; k <= nw;
         k++) {
        lua_geti(L, -1, k);
        snprintf(line, sizeof line, "  warning: %s\n", lua_tostring(L, -1) ? lua_tostring(L, -1) : "?");
        lua_pop(L, 1);
        dfle_lua_text_str(L, &parts, line);
    }
    lua_pop(L, 1);
    dfle_lua_text_finish(L, &parts);
    {
        /* no final line break: print() adds one */
        size_t len;
        const char *text = lua_tolstring(L, -1, &len);
        if (len > 0 && text[len - 1] == '\n')
            lua_pushlstring(L, text, len - 1);
    }
    return 1;
}

void inv_open_result(lua_State *L)
{
    static const luaL_Reg methods[] = {{"predict", l_predict}, {NULL, NULL}};
    if (luaL_newmetatable(L, INV_RESULT)) {
        lua_newtable(L);
        luaL_setfuncs(L, methods, 0);
        lua_setfield(L, -2, "__index");
        lua_pushcfunction(L, l_tostring);
        lua_setfield(L, -2, "__tostring");
        lua_pushliteral(L, INV_RESULT);
        lua_setfield(L, -2, "__name");
    }
    lua_pop(L, 1);
    lua_newtable(L);
    lua_newtable(L);
    lua_pushliteral(L, "k");
    lua_setfield(L, -2, "__mode");
    lua_setmetatable(L, -2);
    lua_rawsetp(L, LUA_REGISTRYINDEX, &ctx_key);
}
