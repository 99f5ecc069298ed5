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
 * their own Lua states (lua_invert_pool.c).  This file is the entry
 * point: the table (lua_invert_spec.c), the chain file opened or resumed
 * (lua_invert_chain.c), the point estimate (lua_invert_lsq.c), the
 * sampling loop (lua_invert_loop.c), the result (lua_invert_result.c).
 * doc/inversion.md has the statistics.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "lua/invert/lua_invert_internal.h"

/* The first setting in which two identity lines differ, as
 * "seed=3 in the file, seed=4 here". */
static void push_difference(lua_State *L, const char *file, const char *mine)
{
    const char *a = file, *b = mine;
    while (*a != '\0' && *b != '\0') {
        size_t la = strcspn(a, " "), lb = strcspn(b, " ");
        if (la != lb || strncmp(a, b, la) != 0) {
            lua_pushlstring(L, a, la);
            lua_pushlstring(L, b, lb);
            lua_pushfstring(L, "%s in the file, %s here", lua_tostring(L, -2),
                            lua_tostring(L, -1));
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
        struct stat sb;
        if (stat(path, &sb) == 0 && S_ISREG(sb.st_mode) && sb.st_size > 0) {
            /* the table is held by the box, whose __gc frees it if we raise */
            dfle_ens_table *t;
            if (dfle_ens_table_read(path, &R->table, &err) != DFLE_OK)
                luaL_error(L, "dfle.invert: %s is not a chain of dfle.invert (%s); remove it, pass "
                              "resume = false, or choose another 'out'", path, err.msg);
            t = R->table;
            if (t->nrows > 0 && t->index[t->nrows - 1] > n)
                n = t->index[t->nrows - 1];
            if (strcmp(t->meta, lua_tostring(L, -2)) != 0 ||
                strcmp(t->header, lua_tostring(L, -1)) != 0) {
                push_difference(L, t->meta, lua_tostring(L, -2));
                luaL_error(L, "dfle.invert: %s holds another inversion's chain (%s); remove it, "
                              "pass resume = false, or choose another 'out'", path,
                           lua_tostring(L, -1));
            }
            dfle_ens_table_free(R->table);
            R->table = NULL;
        }
    }
    if (dfle_ens_file_open(path, lua_tostring(L, -2), NULL, lua_tostring(L, -1), n, R->resume,
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
    int role, ctx, lsq_idx = 0;
    inv_run *R;
    const char *out;
    size_t K, ran = 0, have0;
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
        inv_push_lsq(L, ctx, R);
        dfle_lua_par_depth(L, -1);
        lsq_idx = lua_gettop(L);
    }
    if (R->steps > 0 && R->have < R->steps + 1) {
        int nw = dfle_lua_par_workers(host, R->workers, 0);
        if (host == NULL || host->open_state == NULL || R->nested)
            nw = 1;
        if (inv_sample(L, ctx, R, nw, call, msg, sizeof msg) != 0) {
            dfle_ens_file *f = R->file;
            R->file = NULL;
            dfle_ens_file_close(f, 0, NULL);
            return luaL_error(L, "dfle.invert: %s%s", msg,
                              out != NULL ? " (the rows written are kept; run again to resume)"
                                          : "");
        }
        ran = (R->have > 0 ? R->have - 1 : 0) - (have0 > 0 ? have0 - 1 : 0);
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
