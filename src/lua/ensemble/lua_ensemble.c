/*
 * lua_ensemble.c - dfle.ensemble{...}: run a Latin hypercube ensemble of
 * steady-state models on all cores, streaming rows to a resumable CSV;
 * dfle.gather{...} merges shard files; dfle.pawn(ens, {...}) ranks
 * the inputs of a finished ensemble.
 *
 *   local ens = dfle.ensemble{
 *       params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3} },
 *       n = 64, seed = 1, out = "ens.csv",
 *       build = function(p) return dfle.model{ U = p.U, ... } end,
 *       outputs = { "S_df", "A_df", "r2", "S_max_minus_S_ch" },
 *   }
 *
 * Parallel workers are threads, each with its own Lua state made by the
 * host (lua/drive/lua_drive.h): the worker runs the same script, and the k-th
 * call of dfle.ensemble in it, instead of running, hands its table over
 * and stops the script (earlier calls return their finished results,
 * read from their files).  So `build`, `measure` and Lua-defined laws
 * run in every worker with their upvalues, and the script up to the
 * ensemble call must do the same thing every time it runs (doc/ensembles.md).
 *
 * The run is the C library's (dfle_ensemble_run, dfle/ensemble_run.h:
 * the design, the rows, the worker pool, the file); this binding reads
 * the table (lua_ensemble_spec.c), gives the evaluator that runs one
 * sample in Lua (lua_ensemble_sample.c, on lua/drive/), and reads the
 * finished file back as the result (lua_ensemble_result.c).  This file
 * holds the Lua entry points and the box of C resources they hold while
 * Lua runs.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/sensitivity.h"
#include "lua/ensemble/lua_ensemble_internal.h"

/* ------------------------------------------------------------------ */
/* C resources held while Lua code runs: freed by __gc if it raises.   */

static int box_gc(lua_State *L)
{
    run_box *b = luaL_checkudata(L, 1, RUN_BOX);
    dfle_ens_table_free(b->table);
    free(b->meta);
    free(b->header);
    if (b->ev_set)
        dfle_lua_evaluator_release(&b->ev);
    memset(b, 0, sizeof *b);
    return 0;
}

run_box *dfle_lua_ens_new_box(lua_State *L)
{
    run_box *b = lua_newuserdatauv(L, sizeof *b, 0);
    memset(b, 0, sizeof *b);
    luaL_setmetatable(L, RUN_BOX);
    return b;
}

/* ------------------------------------------------------------------ */
/* The JSON record of a finished run.                                  */

/* The counts of the result table at res into rec's current section, and
 * its rows per status as section "status". */
static void record_counts(lua_State *L, dfle_record *rec, int res)
{
    static const char *const keys[] = {"n", "count", "ok", "failed", "ran"};
    for (int k = 0; k < 5; k++) {
        lua_getfield(L, res, keys[k]);
        dfle_record_number(rec, keys[k], lua_tonumber(L, -1), NULL);
        lua_pop(L, 1);
    }
    lua_getfield(L, res, "complete");
    dfle_record_bool(rec, "complete", lua_toboolean(L, -1));
    lua_getfield(L, res, "status");
    dfle_record_section(rec, "status", NULL);
    dfle_lua_record_table(L, rec, -1, 0);
    lua_pop(L, 2);
}

/* The JSON record of a finished dfle.ensemble (the table at 1, its
 * context at ctx, its result at res): what ran it, the design, the
 * options and the counts.  The CSV file's own comment lines carry only
 * what is the same for every run (the date and command are here). */
static void ensemble_record(lua_State *L, int ctx, int res, const char *path, int workers)
{
    const dfle_lua_host *host = dfle_lua_host_of(L);
    dfle_record *rec = dfle_lua_push_record(L, "dfle.ensemble: one row per sample, in index "
                                               "order");
    const char *jpath;
    int top = lua_gettop(L);

    dfle_record_section(rec, "ensemble", NULL);
    lua_getfield(L, ctx, "meta");
    dfle_record_text(rec, "meta", lua_tostring(L, -1));
    dfle_record_number(rec, "workers", workers, NULL);
    if (host != NULL && host->shard_n > 1) {
        char shard[64];
        snprintf(shard, sizeof shard, "%zu/%zu", host->shard_i, host->shard_n);
        dfle_record_text(rec, "shard", shard);
    }
    record_counts(L, rec, res);
    for (int k = 0; k < 2; k++) {
        const char *key = k == 0 ? "run" : "fit";
        if (lua_getfield(L, 1, key) == LUA_TTABLE) {
            dfle_record_section(rec, key, NULL);
            dfle_lua_record_table(L, rec, -1, 1);
        }
        lua_pop(L, 1);
    }
    jpath = dfle_lua_record_path(L, rec, 1, path, "ensemble");
    dfle_lua_record_done(L, rec, path, jpath);
    lua_settop(L, top - 1);
}

/* ------------------------------------------------------------------ */
/* dfle.ensemble                                                       */

/* The driver's progress and notes, to the host and the state's notes. */
typedef struct hooks {
    lua_State *L;
    const dfle_lua_host *host;
} hooks;

static void hook_note(void *ud, const char *line)
{
    const hooks *h = ud;
    dfle_lua_note(h->L, DFLE_LUA_NOTE, "%s", line);
}

static void hook_progress(void *ud, size_t done, size_t total, size_t failed, double elapsed)
{
    const hooks *h = ud;
    h->host->progress(h->host->ud, done, total, failed, elapsed);
}

static int l_ensemble(lua_State *L)
{
    const dfle_lua_host *host = dfle_lua_host_of(L);
    lua_Integer call;
    spec *s;
    int ctx, nw, role, workers, st;
    run_box *box;
    dfle_error err;
    dfle_ensemble_result res;
    hooks hk = {L, host};
    double started;
    const char *path;

    lua_settop(L, 1);
    /* A worker replaying the script stops in here at its own call. */
    role = dfle_lua_par_enter(L, DFLE_LUA_PAR_ENSEMBLE, 1, &call);
    dfle_lua_ens_read_spec(L, 1, "ensemble", &s, host);
    ctx = lua_gettop(L);
    lua_getfield(L, ctx, "out");
    path = lua_tostring(L, -1);
    if (role == DFLE_LUA_PAR_EARLIER) {
        /* An earlier ensemble of the script, finished by the main state. */
        dfle_lua_ens_push_result(L, "ensemble", path, host ? host->shard_i : 0,
                                 host ? host->shard_n : 0, 0);
        return 1;
    }

    dfle_lua_check_interrupt(L, "ensemble");
    started = dfle_lua_now();
    nw = dfle_lua_par_workers(host, s->workers, host != NULL ? host->cores : 0);
    if (host == NULL || host->open_state == NULL || role == DFLE_LUA_PAR_NESTED)
        nw = 1;
    workers = nw;
    box = dfle_lua_ens_new_box(L);
    lua_getfield(L, ctx, "identity");
    if (dfle_lua_evaluator_init(&box->ev, &dfle_lua_ens_kind, host, L, ctx,
                                role == DFLE_LUA_PAR_RUN ? call : 0, lua_tostring(L, -1),
                                &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    lua_pop(L, 1);
    box->ev_set = 1;
    s->o.workers = nw;
    /* Other processes (MPI ranks) share the samples; this one then runs
     * its share on worker threads, never in the calling state, so that
     * its main thread stays free to watch them. */
    s->o.remote = role == DFLE_LUA_PAR_RUN && host != NULL && host->open_state != NULL
                      ? host->remote
                      : NULL;
    s->o.remote_workers = s->workers;
    s->o.interrupt = dfle_lua_get_interrupt(L);
    s->o.progress = host != NULL && host->progress != NULL ? hook_progress : NULL;
    s->o.note = hook_note;
    s->o.ud = &hk;
    st = dfle_ensemble_run(&s->o, &box->ev.ev, &res, &err);
    if (host != NULL && host->progress_end != NULL && res.total > 0)
        host->progress_end(host->ud);
    if (st == DFLE_ECANCELED) {
        dfle_lua_set_interrupt_note(L, "dfle.ensemble stopped taking samples; %d finished rows "
                                       "are in %s, and running the script again resumes it",
                                    (int)(res.kept + res.ran), res.path);
        dfle_lua_check_interrupt(L, "ensemble");
    }
    if (st != DFLE_OK)
        return dfle_lua_raise(L, &err);
    if ((size_t)nw > res.total)
        nw = res.total > 0 ? (int)res.total : 1;
    dfle_lua_note(L, DFLE_LUA_DETAIL, "ensemble %s: %zu sample%s run in %.1f s", path, res.ran,
                  res.ran == 1 ? "" : "s", dfle_lua_now() - started);
    dfle_lua_ens_push_result(L, "ensemble", path, host ? host->shard_i : 0,
                             host ? host->shard_n : 0, (lua_Integer)res.ran);
    lua_pushinteger(L, workers); /* dfle.pawn(ens) runs its bootstrap on as many */
    lua_setfield(L, -2, "workers");
    ensemble_record(L, ctx, lua_gettop(L), path, nw);
    return 1;
}

/* dfle.gather{ files = {...} | shards = k, out = "ens.csv" } */
static int l_gather(lua_State *L)
{
    double shards = 0;
    const dfle_lua_param nums[] = {{"shards", &shards}};
    static const char *const other[] = {"files", "out", "record", NULL};
    const char **files;
    size_t nf;
    dfle_error err;
    const char *out;

    luaL_checktype(L, 1, LUA_TTABLE);
    dfle_lua_read_params(L, 1, "gather", nums, 1, other);
    lua_settop(L, 1);
    if (lua_getfield(L, 1, "out") != LUA_TSTRING)
        return luaL_error(L, "dfle.gather: parameter 'out' must be a file name, got %s",
                          luaL_typename(L, -1));
    out = dfle_lua_check_string(L, 2, "gather", "out");
    lua_getfield(L, 1, "files");
    if ((lua_isnil(L, 3)) == (shards == 0))
        return luaL_error(L, "dfle.gather: give either 'files' (an array of file names) or "
                             "'shards' (the n of --shard i/n)");
    if (shards != 0) {
        lua_Integer k = dfle_lua_check_whole(L, shards, "gather", "shards", 1, 1e6);
        lua_createtable(L, (int)k, 0);
        for (lua_Integer i = 1; i <= k; i++) {
            char p[4096];
            if (dfle_ensemble_shard_path(out, (size_t)i, (size_t)k, p, sizeof p, &err) != DFLE_OK)
                return dfle_lua_raise(L, &err);
            lua_pushstring(L, p);
            lua_rawseti(L, -2, i);
        }
        lua_replace(L, 3);
    }
    if (!lua_istable(L, 3) || lua_rawlen(L, 3) == 0)
        return luaL_error(L, "dfle.gather: parameter 'files' must be a non-empty array of file "
                             "names");
    nf = (size_t)lua_rawlen(L, 3);
    files = lua_newuserdatauv(L, nf * sizeof *files, 0);
    for (size_t i = 0; i < nf; i++) {
        if (lua_geti(L, 3, (lua_Integer)i + 1) != LUA_TSTRING)
            return luaL_error(L, "dfle.gather: files[%d] must be a file name", (int)i + 1);
        files[i] = dfle_lua_check_string(L, -1, "gather", "a file name");
        lua_pop(L, 1); /* still referenced by the files table */
    }
    if (dfle_ens_gather(files, nf, out, NULL, &err) != DFLE_OK)
        return luaL_error(L, "dfle.gather: %s", err.msg);
    dfle_lua_ens_push_result(L, "gather", out, 0, 0, 0);
    {
        int res = lua_gettop(L);
        dfle_record *rec = dfle_lua_push_record(L, "dfle.gather: the rows of the shards, in "
                                                   "index order");
        const char *jpath;
        dfle_record_section(rec, "gather", NULL);
        dfle_record_list(rec, "from", files, nf);
        record_counts(L, rec, res);
        jpath = dfle_lua_record_path(L, rec, 1, out, "gather");
        dfle_lua_record_done(L, rec, out, jpath);
        lua_settop(L, res);
    }
    return 1;
}

/* The bootstrap threads of a dfle.pawn call that gives none: 1 inside
 * an ensemble's sample or an inversion (their workers have the cores
 * already), else the command's -j, else (for an ensemble) the workers it
 * ran with (at idx, or 0); 0: dfle.pawn's own default, every core. */
static lua_Integer default_threads(lua_State *L, int ens)
{
    const dfle_lua_host *host = dfle_lua_host_of(L);
    lua_Integer n = 0;
    if (dfle_lua_par_inside(L))
        return 1;
    if (host != NULL && host->workers > 0)
        return host->workers;
    if (ens != 0 && lua_getfield(L, ens, "workers") == LUA_TNUMBER)
        n = lua_tointeger(L, -1);
    if (ens != 0)
        lua_pop(L, 1);
    /* a result the script has changed may hold anything there */
    return n >= 1 && n <= DFLE_PAWN_MAX_THREADS ? n : 0;
}

/* The plain dfle.pawn (upvalue 1 of l_pawn_ensemble) on the nargs values
 * on top of the stack, leaving nres results; its errors get the
 * script's position here (called from C, they carry none). */
static void plain_pawn(lua_State *L, int nargs, int nres)
{
    lua_pushvalue(L, lua_upvalueindex(1));
    lua_insert(L, -nargs - 1);
    if (lua_pcall(L, nargs, nres, 0) != LUA_OK) {
        if (lua_type(L, -1) == LUA_TSTRING) {
            luaL_where(L, 1);
            lua_insert(L, -2);
            lua_concat(L, 2);
        }
        lua_error(L);
    }
}

/* The array of names at idx: a table of strings (the script's options,
 * or the result table, which a script may have changed). */
static void check_names(lua_State *L, int idx, const char *what)
{
    lua_Integer n;
    if (!lua_istable(L, idx))
        luaL_error(L, "dfle.pawn: %s must be an array of names, got %s", what,
                   dfle_lua_typename(L, idx));
    n = (lua_Integer)lua_rawlen(L, idx);
    for (lua_Integer i = 1; i <= n; i++) {
        if (lua_rawgeti(L, idx, i) != LUA_TSTRING)
            luaL_error(L, "dfle.pawn: %s[%d] must be a name, got %s", what, (int)i,
                       dfle_lua_typename(L, -1));
        lua_pop(L, 1);
    }
}

/* dfle.pawn(ens, {outputs =, inputs =, S =, ..., threads =}): PAWN of each
 * output on the rows with status "ok"; anything else goes to the plain
 * dfle.pawn.  Both get the -j of the command as their default threads. */
static int l_pawn_ensemble(lua_State *L)
{
    static const char *const keys[] = {"outputs", "inputs", NULL};
    double S = 10, boot = 0, conf = 0.95, seed = 1, threads = -1; /* -1: not given */
    const dfle_lua_param nums[] = {{"S", &S},       {"bootstrap", &boot}, {"conf", &conf},
                                   {"seed", &seed}, {"threads", &threads}};
    int data, outs, ins, si, info, okrows, is_ens = 0;
    lua_Integer count, k = 0;

    if (lua_getmetatable(L, 1)) {
        luaL_getmetatable(L, RESULT_MT);
        is_ens = lua_rawequal(L, -1, -2);
        lua_pop(L, 2);
    }
    if (!is_ens) {
        lua_Integer n = default_threads(L, 0);
        if (n > 0 && lua_type(L, 1) == LUA_TTABLE &&
            lua_getfield(L, 1, "threads") == LUA_TNIL) {
            /* a copy with threads = -j: the script's table stays as it was */
            lua_newtable(L);
            lua_pushnil(L);
            while (lua_next(L, 1) != 0) {
                lua_pushvalue(L, -2);
                lua_insert(L, -2);
                lua_rawset(L, -4);
            }
            lua_pushinteger(L, n);
            lua_setfield(L, -2, "threads");
            lua_replace(L, 1);
            lua_pop(L, 1);
        } else if (n > 0 && lua_type(L, 1) == LUA_TTABLE) {
            lua_pop(L, 1);
        }
        plain_pawn(L, lua_gettop(L), LUA_MULTRET);
        return lua_gettop(L);
    }
    lua_settop(L, 2);
    dfle_lua_read_params(L, 2, "pawn", nums, 5, keys);
    if (threads == -1 && default_threads(L, 1) > 0)
        threads = (double)default_threads(L, 1);
    /* The result is a plain table the script may have changed: every
     * part used is checked before it is used. */
    lua_getfield(L, 1, "data");
    data = lua_gettop(L);
    if (!lua_istable(L, data))
        return luaL_error(L, "dfle.pawn: the ensemble's 'data' is not a table (got %s)",
                          dfle_lua_typename(L, data));
    if (!lua_istable(L, 2) || lua_getfield(L, 2, "outputs") == LUA_TNIL) {
        lua_settop(L, data);
        lua_getfield(L, 1, "outputs");
    }
    outs = lua_gettop(L);
    check_names(L, outs, "outputs");
    if (!lua_istable(L, 2) || lua_getfield(L, 2, "inputs") == LUA_TNIL) {
        /* default: the numeric parameters */
        lua_Integer nin, j = 0;
        lua_settop(L, outs);
        lua_getfield(L, 1, "inputs");
        check_names(L, -1, "the ensemble's inputs");
        nin = (lua_Integer)lua_rawlen(L, -1);
        lua_newtable(L);
        for (lua_Integer c = 1; c <= nin; c++) {
            int numeric = 1;
            lua_Integer nr;
            lua_rawgeti(L, -2, c);
            lua_pushvalue(L, -1);
            numeric = lua_gettable(L, data) == LUA_TTABLE;
            nr = numeric ? (lua_Integer)lua_rawlen(L, -1) : 0;
            for (lua_Integer r = 1; r <= nr && numeric; r++) {
                numeric = lua_geti(L, -1, r) == LUA_TNUMBER;
                lua_pop(L, 1);
            }
            lua_pop(L, 1);
            if (numeric)
                lua_rawseti(L, -2, ++j);
            else
                lua_pop(L, 1);
        }
        lua_remove(L, -2);
    }
    ins = lua_gettop(L);
    check_names(L, ins, "inputs");
    /* Row numbers with status ok. */
    lua_newtable(L);
    okrows = lua_gettop(L);
    if (lua_getfield(L, data, "status") != LUA_TTABLE)
        return luaL_error(L, "dfle.pawn: the ensemble's data.status is not a table (got %s)",
                          dfle_lua_typename(L, -1));
    count = (lua_Integer)lua_rawlen(L, -1);
    for (lua_Integer r = 1; r <= count; r++) {
        lua_rawgeti(L, -1, r);
        if (lua_type(L, -1) == LUA_TSTRING && strcmp(lua_tostring(L, -1), "ok") == 0) {
            lua_pushinteger(L, r);
            lua_rawseti(L, okrows, ++k);
        }
        lua_pop(L, 1);
    }
    lua_pop(L, 1);
    lua_newtable(L);
    si = lua_gettop(L);
    lua_newtable(L);
    info = lua_gettop(L);
    for (lua_Integer o = 1, no = (lua_Integer)lua_rawlen(L, outs); o <= no; o++) {
        int cols, base = lua_gettop(L);
        lua_createtable(L, 0, 8);
        lua_newtable(L);
        cols = lua_gettop(L);
        for (lua_Integer c = 0, nin = (lua_Integer)lua_rawlen(L, ins); c <= nin; c++) {
            if (c == 0)
                lua_rawgeti(L, outs, o);
            else
                lua_rawgeti(L, ins, c);
            lua_pushvalue(L, -1);
            if (lua_gettable(L, data) != LUA_TTABLE)
                return luaL_error(L, "dfle.pawn: the ensemble has no column '%s'",
                                  lua_tostring(L, -2));
            lua_createtable(L, (int)k, 0);
            for (lua_Integer r = 1; r <= k; r++) {
                lua_geti(L, okrows, r);
                lua_gettable(L, -3);
                lua_rawseti(L, -2, r);
            }
            lua_remove(L, -2);
            lua_settable(L, cols);
        }
        lua_setfield(L, base + 1, "data");
        lua_pushvalue(L, ins), lua_setfield(L, base + 1, "inputs");
        lua_rawgeti(L, outs, o), lua_setfield(L, base + 1, "output");
        lua_pushnumber(L, S), lua_setfield(L, base + 1, "S");
        lua_pushnumber(L, boot), lua_setfield(L, base + 1, "bootstrap");
        lua_pushnumber(L, conf), lua_setfield(L, base + 1, "conf");
        lua_pushnumber(L, seed), lua_setfield(L, base + 1, "seed");
        if (threads != -1)
            lua_pushnumber(L, threads), lua_setfield(L, base + 1, "threads");
        plain_pawn(L, 1, 2);
        lua_rawgeti(L, outs, o);
        lua_insert(L, -2);
        lua_settable(L, info);
        lua_rawgeti(L, outs, o);
        lua_insert(L, -2);
        lua_settable(L, si);
        lua_settop(L, base);
    }
    lua_pushvalue(L, si);
    lua_pushvalue(L, info);
    return 2;
}

/* dfle.worker(): true while a worker replays the script up to its
 * dfle.ensemble call (scripts may skip output there). */
static int l_worker(lua_State *L)
{
    lua_pushboolean(L, dfle_lua_is_worker(L));
    return 1;
}

void dfle_lua_open_ensemble(lua_State *L)
{
    if (luaL_newmetatable(L, RUN_BOX)) {
        lua_pushcfunction(L, box_gc);
        lua_setfield(L, -2, "__gc");
    }
    lua_pop(L, 1);
    if (luaL_newmetatable(L, RESULT_MT)) {
        lua_pushliteral(L, RESULT_MT);
        lua_setfield(L, -2, "__name");
        dfle_lua_ens_result_methods(L); /* ens:write_netcdf */
    }
    lua_pop(L, 1);
    lua_pushcfunction(L, l_ensemble);
    lua_setfield(L, -2, "ensemble");
    lua_pushcfunction(L, l_gather);
    lua_setfield(L, -2, "gather");
    lua_pushcfunction(L, l_worker);
    lua_setfield(L, -2, "worker");
    /* dfle.pawn also accepts an ensemble result (after lua_sampling.c). */
    lua_getfield(L, -1, "pawn");
    lua_pushcclosure(L, l_pawn_ensemble, 1);
    lua_setfield(L, -2, "pawn");
}
