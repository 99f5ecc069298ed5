/*
 * lua_ensemble_sample.c - the dfle.ensemble table checked into a
 * context, one sample run protected into a CSV row, and a finished
 * ensemble read back into the result table (lua_ensemble.c).
 */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "lua/ensemble/lua_ensemble_internal.h"

#ifndef DFLE_VERSION
#define DFLE_VERSION "unknown"
#endif

/* ------------------------------------------------------------------ */
/* C resources held while Lua code runs: freed by __gc if it raises.   */

int dfle_lua_ens_box_gc(lua_State *L)
{
    run_box *b = luaL_checkudata(L, 1, RUN_BOX);
    dfle_ens_file_close(b->file, 0, NULL);
    dfle_ens_queue_free(b->queue);
    dfle_ens_table_free(b->table);
    b->file = NULL;
    b->queue = NULL;
    b->table = NULL;
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
/* The ensemble's table, checked, into a context table on the stack.   */

/* Column names go into a CSV header and the meta line unquoted. */
static void check_column_name(lua_State *L, const char *fn, const char *what, const char *name)
{
    static const char *const reserved[] = {"index", "status", "reason"};
    if (name[0] == '\0' || strpbrk(name, ",\"\r\n =") != NULL)
        luaL_error(L, "dfle.%s: %s name '%s' cannot be a CSV column (no commas, quotes, "
                      "spaces, '=' or line breaks)", fn, what, name);
    for (int k = 0; k < 3; k++)
        if (strcmp(name, reserved[k]) == 0)
            luaL_error(L, "dfle.%s: %s name '%s' is reserved for a column of the result", fn,
                       what, name);
}

static void push_number_text(lua_State *L, double v)
{
    char buf[40];
    if (isnan(v))
        lua_pushliteral(L, "nan");
    else if (isinf(v))
        lua_pushstring(L, v > 0 ? "inf" : "-inf");
    else {
        snprintf(buf, sizeof buf, "%.17g", v);
        lua_pushstring(L, buf);
    }
}

/* The text of a field value: integers as integers, floats with 17
 * digits, other values as text, quoted when `quote` (quotes doubled;
 * line breaks become spaces either way). */
static void push_value_text(lua_State *L, int idx, int quote)
{
    idx = lua_absindex(L, idx);
    if (lua_isinteger(L, idx)) {
        char buf[32];
        snprintf(buf, sizeof buf, "%lld", (long long)lua_tointeger(L, idx));
        lua_pushstring(L, buf);
    } else if (lua_type(L, idx) == LUA_TNUMBER) {
        push_number_text(L, lua_tonumber(L, idx));
    } else {
        luaL_Buffer b;
        const char *s = luaL_tolstring(L, idx, NULL); /* stays at the top, below b */
        luaL_buffinit(L, &b);
        if (quote)
            luaL_addchar(&b, '"');
        for (; *s != '\0'; s++) {
            if (*s == '\n' || *s == '\r')
                luaL_addchar(&b, ' ');
            else if (*s == '"' && quote)
                luaL_addstring(&b, "\"\"");
            else
                luaL_addchar(&b, *s);
        }
        if (quote)
            luaL_addchar(&b, '"');
        luaL_pushresult(&b);
        lua_remove(L, -2);
    }
}

/* Push the names of array `arr` joined by commas. */
static void push_joined(lua_State *L, int arr)
{
    dfle_lua_text pc;
    dfle_lua_text_init(L, &pc);
    for (lua_Integer k = 1, n = (lua_Integer)lua_rawlen(L, arr); k <= n; k++) {
        if (k > 1)
            dfle_lua_text_str(L, &pc, ",");
        lua_geti(L, arr, k);
        dfle_lua_text_add(L, &pc);
    }
    dfle_lua_text_finish(L, &pc);
}

/* The meta line: what identifies the ensemble (resume and gather check it). */
static void push_meta(lua_State *L, const spec *s, int params, int names, int outputs,
                      int centered)
{
    dfle_lua_text pc;
    char buf[96];

    dfle_lua_text_init(L, &pc);
    snprintf(buf, sizeof buf, "# dfle.ensemble v1 n=%lld seed=%lld centered=%s inputs=",
             (long long)s->n, (long long)s->seed, centered ? "true" : "false");
    dfle_lua_text_str(L, &pc, buf);
    push_joined(L, names);
    dfle_lua_text_add(L, &pc);
    dfle_lua_text_str(L, &pc, " outputs=");
    push_joined(L, outputs);
    dfle_lua_text_add(L, &pc);
    dfle_lua_text_str(L, &pc, " design=");
    for (size_t k = 1; k <= s->nparams; k++) {
        int p;
        if (k > 1)
            dfle_lua_text_str(L, &pc, ";");
        lua_geti(L, names, (lua_Integer)k);
        lua_pushvalue(L, -1);
        dfle_lua_text_add(L, &pc);
        lua_gettable(L, params);
        p = lua_gettop(L);
        if (lua_getfield(L, p, "values") == LUA_TTABLE) {
            int vals = lua_gettop(L);
            dfle_lua_text_str(L, &pc, ":{");
            for (lua_Integer j = 1, nv = (lua_Integer)lua_rawlen(L, vals); j <= nv; j++) {
                if (j > 1)
                    dfle_lua_text_str(L, &pc, ",");
                lua_geti(L, vals, j);
                push_value_text(L, -1, 1);
                dfle_lua_text_add(L, &pc);
                lua_pop(L, 1);
            }
            dfle_lua_text_str(L, &pc, "}");
        } else {
            dfle_lua_text_str(L, &pc, ":[");
            lua_geti(L, p, 1);
            push_number_text(L, lua_tonumber(L, -1));
            dfle_lua_text_add(L, &pc);
            dfle_lua_text_str(L, &pc, ",");
            lua_geti(L, p, 2);
            push_number_text(L, lua_tonumber(L, -1));
            dfle_lua_text_add(L, &pc);
            lua_getfield(L, p, "log");
            dfle_lua_text_str(L, &pc, lua_toboolean(L, -1) ? ",log]" : "]");
        }
        lua_settop(L, p - 1);
    }
    dfle_lua_text_finish(L, &pc);
}

/* Shard file name: "dir/ens.csv" -> "dir/ens.shard-2-of-4.csv". */
void dfle_lua_ens_push_shard_path(lua_State *L, const char *out, size_t i, size_t n)
{
    const char *slash = strrchr(out, '/');
    const char *dot = strrchr(out, '.');
    if (n <= 1) {
        lua_pushstring(L, out);
        return;
    }
    if (dot == NULL || (slash != NULL && dot < slash) || dot == (slash ? slash + 1 : out))
        dot = out + strlen(out);
    lua_pushlstring(L, out, (size_t)(dot - out));
    lua_pushfstring(L, ".shard-%d-of-%d%s", (int)i, (int)n, dot);
    lua_concat(L, 2);
}

static const char *const spec_keys[] = {"params", "order", "centered", "build", "measure",
                                        "outputs", "out", "resume", "run", "fit", "units",
                                        "record", NULL};

/* Units of the outputs dfle computes (fit, run, derived); a script's
 * `units` names those of its parameters and measured outputs. */
static const struct { const char *name, *unit; } output_units[] = {
    {"S_df", "-"},   {"A_df", "m^2"},   {"a2", "-"},      {"r2", "-"},       {"r2_log", "-"},
    {"rmse", "-"},   {"rmse_log", "-"}, {"S_max", "-"},   {"S_ch", "-"},
    {"S_max_minus_S_ch", "-"},          {"time", "yr"},   {"rate_ratio", "-"},
    {"dt_min", "yr"}, {"dt_max", "yr"}, {"runout_A", "m^2"}, {"runout_x", "m"}};

/* Push the unit of column `name` (nil if none is known): the script's
 * `units` (table at units, may be 0) first, then dfle's own. */
static void push_unit(lua_State *L, int units, const char *name, int output)
{
    if (units != 0 && lua_getfield(L, units, name) == LUA_TSTRING)
        return;
    if (units != 0)
        lua_pop(L, 1);
    for (size_t k = 0; output && k < sizeof output_units / sizeof output_units[0]; k++)
        if (strcmp(name, output_units[k].name) == 0) {
            lua_pushstring(L, output_units[k].unit);
            return;
        }
    lua_pushnil(L);
}

/* The comment lines under the meta line: the version that wrote the
 * file, the run and fit options, the units of the columns.  Nothing
 * that changes from one run to the next (no date, no command): a file
 * must be the same for any number of workers, shards or resumes. */
static void push_comments(lua_State *L, int arg, int names, int outputs, const char *fn)
{
    dfle_record *rec = dfle_lua_push_empty_record(L);
    int box = lua_gettop(L), units = 0;
    lua_Integer np = (lua_Integer)lua_rawlen(L, names), no = (lua_Integer)lua_rawlen(L, outputs);
    const char **nm, **un;
    char *text = NULL, *line;
    size_t len = 0;
    FILE *fp;

    if (lua_getfield(L, arg, "units") != LUA_TNIL) {
        if (!lua_istable(L, -1))
            luaL_error(L, "dfle.%s: parameter 'units' must be a table {name = \"unit\"} of "
                          "parameters and outputs", fn);
        units = lua_gettop(L);
        lua_pushnil(L);
        while (lua_next(L, units) != 0) {
            int known = 0;
            if (lua_type(L, -2) != LUA_TSTRING || lua_type(L, -1) != LUA_TSTRING ||
                strpbrk(lua_tostring(L, -1), ",=\r\n") != NULL)
                luaL_error(L, "dfle.%s: units must map names to unit texts (\"m/yr\", \"-\"), "
                              "without commas or '='", fn);
            for (lua_Integer k = 1; k <= np + no && !known; k++) {
                lua_geti(L, k <= np ? names : outputs, k <= np ? k : k - np);
                known = strcmp(lua_tostring(L, -1), lua_tostring(L, -3)) == 0;
                lua_pop(L, 1);
            }
            if (!known)
                luaL_error(L, "dfle.%s: units names '%s', which is neither a parameter nor an "
                              "output", fn, lua_tostring(L, -2));
            lua_pop(L, 1);
        }
    } else {
        lua_pop(L, 1);
    }
    dfle_record_text(rec, "dfle", DFLE_VERSION);
    for (int k = 0; k < 2; k++) {
        const char *key = k == 0 ? "run" : "fit";
        if (lua_getfield(L, arg, key) == LUA_TTABLE) {
            dfle_record_section(rec, key, NULL);
            dfle_lua_record_table(L, rec, -1, 1);
        }
        lua_pop(L, 1);
    }
    /* Names and units of every column: index, parameters, outputs,
     * status, reason (units only for quantities). */
    nm = lua_newuserdatauv(L, 2 * (size_t)(np + no + 3) * sizeof *nm, 0);
    un = nm + np + no + 3;
    lua_newtable(L); /* anchors the unit texts */
    nm[0] = "index", un[0] = NULL;
    for (lua_Integer k = 1; k <= np + no; k++) {
        lua_geti(L, k <= np ? names : outputs, k <= np ? k : k - np);
        nm[k] = lua_tostring(L, -1); /* anchored in names / outputs */
        lua_pop(L, 1);
        push_unit(L, units, nm[k], k > np);
        un[k] = lua_tostring(L, -1);
        lua_rawseti(L, -2, k);
    }
    nm[np + no + 1] = "status", un[np + no + 1] = NULL;
    nm[np + no + 2] = "reason", un[np + no + 2] = NULL;
    fp = dfle_record_status(rec, NULL) == DFLE_OK ? open_memstream(&text, &len) : NULL;
    if (fp == NULL) {
        luaL_error(L, "dfle.%s: out of memory", fn);
        return;
    }
    dfle_record_write_comments(rec, fp);
    line = dfle_units_line(nm, un, (size_t)(np + no + 3));
    if (line != NULL)
        fprintf(fp, "%s\n", line);
    free(line);
    if (fclose(fp) != 0 || text == NULL) {
        free(text);
        luaL_error(L, "dfle.%s: out of memory", fn);
    }
    if (len > 0 && text[len - 1] == '\n')
        len--; /* the lines, joined by '\n' */
    lua_pushlstring(L, text, len);
    free(text);
    lua_replace(L, box);
    lua_settop(L, box);
}


/* Read and check the table at arg; push the context table. */
void dfle_lua_ens_read_spec(lua_State *L, int arg, const char *fn, spec *s,
                      const dfle_lua_ensemble_host *host)
{
    double n = -1, seed = 1, workers = 0, limit = 0;
    const dfle_lua_param nums[] = {
        {"n", &n}, {"seed", &seed}, {"workers", &workers}, {"limit", &limit}};
    int ctx, outputs, names, design, centered = 0;

    arg = lua_absindex(L, arg);
    luaL_checktype(L, arg, LUA_TTABLE);
    dfle_lua_read_params(L, arg, fn, nums, 4, spec_keys);
    memset(s, 0, sizeof *s);
    if (n < 0)
        luaL_error(L, "dfle.%s: parameter 'n' (number of samples) is required", fn);
    s->n = dfle_lua_check_whole(L, n, fn, "n", 1, 4294967295.0);
    s->seed = dfle_lua_check_whole(L, seed, fn, "seed", 0, 4294967295.0);
    s->workers = (int)dfle_lua_check_whole(L, workers, fn, "workers", 0, 4096);
    s->limit = (size_t)dfle_lua_check_whole(L, limit, fn, "limit", 0, 4294967295.0);
    lua_newtable(L);
    ctx = lua_gettop(L);

    if (lua_getfield(L, arg, "build") != LUA_TFUNCTION)
        luaL_error(L, "dfle.%s: parameter 'build' must be a function(p) returning a dfle.model, "
                      "got %s", fn, luaL_typename(L, -1));
    lua_setfield(L, ctx, "build");
    if (lua_getfield(L, arg, "measure") != LUA_TNIL && !lua_isfunction(L, -1))
        luaL_error(L, "dfle.%s: parameter 'measure' must be a function(m, fit, p, run), got %s",
                   fn, luaL_typename(L, -1));
    lua_setfield(L, ctx, "measure");
    for (int k = 0; k < 2; k++) {
        const char *key = k == 0 ? "run" : "fit";
        if (lua_getfield(L, arg, key) != LUA_TNIL && !lua_istable(L, -1))
            luaL_error(L, "dfle.%s: parameter '%s' must be a table of options, got %s", fn, key,
                       luaL_typename(L, -1));
        lua_setfield(L, ctx, key);
    }
    s->resume = 1;
    if (lua_getfield(L, arg, "resume") != LUA_TNIL) {
        if (!lua_isboolean(L, -1))
            luaL_error(L, "dfle.%s: parameter 'resume' must be a boolean", fn);
        s->resume = lua_toboolean(L, -1);
    }
    lua_pop(L, 1);
    if (lua_getfield(L, arg, "centered") != LUA_TNIL)
        centered = lua_toboolean(L, -1);
    lua_pop(L, 1);
    if (lua_getfield(L, arg, "out") != LUA_TSTRING)
        luaL_error(L, "dfle.%s: parameter 'out' (the CSV file of results) must be a file name, "
                      "got %s", fn, luaL_typename(L, -1));
    dfle_lua_ens_push_shard_path(L, dfle_lua_check_string(L, -1, fn, "out"), host ? host->shard_i : 0,
                                 host ? host->shard_n : 0);
    lua_setfield(L, ctx, "out");
    lua_pop(L, 1);

    /* The design, by dfle.lhs (which checks params and order). */
    dfle_lua_push_module(L);
    lua_getfield(L, -1, "lhs");
    lua_createtable(L, 0, 5);
    lua_pushinteger(L, s->n), lua_setfield(L, -2, "n");
    lua_pushinteger(L, s->seed), lua_setfield(L, -2, "seed");
    lua_getfield(L, arg, "params"), lua_setfield(L, -2, "params");
    lua_getfield(L, arg, "order"), lua_setfield(L, -2, "order");
    lua_getfield(L, arg, "centered"), lua_setfield(L, -2, "centered"); /* lhs checks it */
    if (lua_pcall(L, 1, 2, 0) != LUA_OK) {
        /* dfle.lhs's message, as this function's, at the script's line */
        const char *m = lua_tostring(L, -1);
        if (m == NULL)
            lua_error(L);
        if (strncmp(m, "dfle.lhs: ", 10) == 0)
            m += 10;
        luaL_error(L, "dfle.%s: %s", fn, m);
    }
    names = lua_gettop(L);
    design = names - 1;
    lua_pushvalue(L, design), lua_setfield(L, ctx, "design");
    lua_pushvalue(L, names), lua_setfield(L, ctx, "names");
    s->nparams = (size_t)lua_rawlen(L, names);
    for (size_t k = 1; k <= s->nparams; k++) {
        lua_geti(L, names, (lua_Integer)k);
        check_column_name(L, fn, "parameter", lua_tostring(L, -1));
        lua_pop(L, 1);
    }

    if (lua_getfield(L, arg, "outputs") != LUA_TTABLE || lua_rawlen(L, -1) == 0)
        luaL_error(L, "dfle.%s: parameter 'outputs' must be a non-empty array of names "
                      "(e.g. {\"S_df\", \"A_df\"})", fn);
    outputs = lua_gettop(L);
    s->noutputs = (size_t)lua_rawlen(L, outputs);
    for (size_t k = 1; k <= s->noutputs; k++) {
        const char *o;
        if (lua_geti(L, outputs, (lua_Integer)k) != LUA_TSTRING)
            luaL_error(L, "dfle.%s: outputs[%d] must be a name, got %s", fn, (int)k,
                       luaL_typename(L, -1));
        o = dfle_lua_check_string(L, -1, fn, "an output name");
        check_column_name(L, fn, "output", o);
        for (size_t j = 1; j <= s->nparams; j++) {
            lua_geti(L, names, (lua_Integer)j);
            if (strcmp(lua_tostring(L, -1), o) == 0)
                luaL_error(L, "dfle.%s: '%s' is both a parameter and an output", fn, o);
            lua_pop(L, 1);
        }
        for (size_t j = 1; j < k; j++) {
            lua_geti(L, outputs, (lua_Integer)j);
            if (strcmp(lua_tostring(L, -1), o) == 0)
                luaL_error(L, "dfle.%s: output '%s' is listed twice", fn, o);
            lua_pop(L, 1);
        }
        lua_pop(L, 1);
    }
    lua_pushvalue(L, outputs), lua_setfield(L, ctx, "outputs");

    lua_getfield(L, arg, "params");
    push_meta(L, s, lua_gettop(L), names, outputs, centered);
    lua_setfield(L, ctx, "meta");
    lua_pop(L, 1);
    push_comments(L, arg, names, outputs, fn);
    lua_setfield(L, ctx, "comments");
    {
        dfle_lua_text pc;
        dfle_lua_text_init(L, &pc);
        dfle_lua_text_str(L, &pc, "index,");
        push_joined(L, names);
        dfle_lua_text_add(L, &pc);
        dfle_lua_text_str(L, &pc, ",");
        push_joined(L, outputs);
        dfle_lua_text_add(L, &pc);
        dfle_lua_text_str(L, &pc, ",status,reason");
        dfle_lua_text_finish(L, &pc);
    }
    lua_setfield(L, ctx, "header");
    lua_settop(L, ctx);
}

/* ------------------------------------------------------------------ */
/* One sample.                                                         */

/* Push the output `runout_A` or `runout_x` of the steady model at m:
 * drainage area or distance of the last node one debris flow reaches
 * (router:route on the final profile); NaN if it reaches none. */
static void push_runout(lua_State *L, int m, const char *name)
{
    lua_Integer k;
    int t = lua_gettop(L);
    if (lua_getfield(L, m, "router") == LUA_TNIL)
        luaL_error(L, "output '%s' needs a debris-flow router (the model has router = false)",
                   name);
    lua_getfield(L, t + 1, "route");
    lua_pushvalue(L, t + 1);
    lua_pushvalue(L, m);
    lua_call(L, 2, 1);
    lua_getfield(L, -1, "runout_end");
    k = lua_tointeger(L, -1);
    lua_getfield(L, m, "get");
    lua_pushvalue(L, m);
    lua_pushstring(L, strcmp(name, "runout_A") == 0 ? "A" : "x");
    lua_call(L, 2, 1);
    if (k >= 1)
        lua_geti(L, -1, k);
    else
        lua_pushnumber(L, NAN);
    lua_replace(L, t + 1);
    lua_settop(L, t + 1);
}

/* run_sample(ctx, i) -> status, reason, values; runs under pcall. */
static int run_sample(lua_State *L)
{
    lua_Integer i = lua_tointeger(L, 2);
    int p, m, res, fit, extra, vals;
    lua_Integer nout;

    lua_settop(L, 2);
    lua_getfield(L, 1, "design");
    lua_geti(L, -1, i);
    p = lua_gettop(L);
    lua_getfield(L, 1, "build");
    lua_pushvalue(L, p);
    lua_call(L, 1, 1);
    m = lua_gettop(L);
    if (luaL_testudata(L, m, DFLE_LUA_MODEL) == NULL)
        return luaL_error(L, "build(p) must return a dfle.model, got %s", dfle_lua_typename(L, m));

    /* m:run_to_steady(run options, without a progress bar) */
    lua_getfield(L, m, "run_to_steady");
    lua_pushvalue(L, m);
    lua_newtable(L);
    if (lua_getfield(L, 1, "run") == LUA_TTABLE)
        dfle_lua_copy_table(L, -1, -2);
    lua_pop(L, 1);
    lua_pushboolean(L, 0), lua_setfield(L, -2, "progress");
    lua_call(L, 2, 1);
    res = lua_gettop(L);
    lua_getfield(L, res, "converged");
    if (!lua_toboolean(L, -1)) {
        lua_pushliteral(L, "not_converged");
        if (lua_getfield(L, res, "reason") == LUA_TNIL) {
            lua_pop(L, 1);
            lua_pushliteral(L, "no steady state");
        }
        lua_pushnil(L);
        return 3;
    }
    lua_pop(L, 1);

    dfle_lua_push_module(L);
    lua_getfield(L, -1, "fit_slope_area");
    lua_pushvalue(L, m);
    lua_getfield(L, 1, "fit");
    lua_call(L, 2, 2);
    if (lua_isnil(L, -2)) {
        lua_pushliteral(L, "fit_failed");
        lua_insert(L, -2);
        lua_pushnil(L);
        return 3;
    }
    lua_pop(L, 1);
    fit = lua_gettop(L);

    extra = 0;
    if (lua_getfield(L, 1, "measure") != LUA_TNIL) {
        lua_pushvalue(L, m);
        lua_pushvalue(L, fit);
        lua_pushvalue(L, p);
        lua_pushvalue(L, res);
        lua_call(L, 4, 1);
        if (!lua_isnil(L, -1) && !lua_istable(L, -1))
            return luaL_error(L, "measure(m, fit, p, run) must return a table of outputs, got %s",
                              luaL_typename(L, -1));
        if (lua_istable(L, -1))
            extra = lua_gettop(L);
    }

    lua_getfield(L, 1, "outputs");
    nout = luaL_len(L, -1);
    lua_createtable(L, (int)nout, 0);
    vals = lua_gettop(L);
    for (lua_Integer k = 1; k <= nout; k++) {
        const char *name;
        int t = LUA_TNIL;
        lua_geti(L, vals - 1, k);
        name = lua_tostring(L, -1);
        if (extra)
            t = lua_getfield(L, extra, name);
        if (t == LUA_TNIL) {
            lua_settop(L, vals + 1);
            lua_pushstring(L, name);
            t = lua_rawget(L, fit); /* raw: the fit table raises on unknown keys */
        }
        if (t == LUA_TNIL) {
            lua_settop(L, vals + 1);
            lua_pushstring(L, name);
            t = lua_rawget(L, res);
        }
        if (t == LUA_TNIL && (strcmp(name, "runout_A") == 0 || strcmp(name, "runout_x") == 0)) {
            lua_settop(L, vals + 1);
            push_runout(L, m, name);
            t = LUA_TNUMBER;
        }
        if (t != LUA_TNUMBER)
            return luaL_error(L, "output '%s' is %s (not a fit value%s)", name,
                              t == LUA_TNIL ? "missing" : luaL_typename(L, -1),
                              extra ? " nor returned by measure" : "; compute it in measure");
        if (!isfinite(lua_tonumber(L, -1))) {
            lua_pushliteral(L, "nan");
            lua_pushfstring(L, "output '%s' is %s", name,
                            dfle_lua_number_text(L, lua_tonumber(L, -2)));
            lua_remove(L, -2);
            lua_pushnil(L);
            return 3;
        }
        lua_rawseti(L, vals, k);
        lua_settop(L, vals);
    }
    lua_pushliteral(L, "ok");
    lua_pushliteral(L, "");
    lua_pushvalue(L, vals);
    return 3;
}

/* Run sample i with the context at ctx; push its row text.  Returns 1
 * if the sample failed (its row says why). */
int dfle_lua_ens_sample_row(lua_State *L, int ctx, size_t i)
{
    int failed, top, p, names, outputs;
    lua_Integer np, nout;
    dfle_lua_text pc;
    char buf[32];

    lua_pushcfunction(L, run_sample);
    lua_pushvalue(L, ctx);
    lua_pushinteger(L, (lua_Integer)i);
    if (lua_pcall(L, 2, 3, 0) != LUA_OK) {
        if (lua_type(L, -1) != LUA_TSTRING && lua_type(L, -1) != LUA_TNUMBER) {
            const char *tn = luaL_typename(L, -1);
            lua_pop(L, 1);
            lua_pushfstring(L, "(error object is a %s value)", tn);
        }
        lua_pushliteral(L, "error");
        lua_insert(L, -2);
        lua_pushnil(L);
    }
    /* stack: status, reason, values */
    top = lua_gettop(L);
    failed = strcmp(lua_tostring(L, top - 2), "ok") != 0;
    lua_getfield(L, ctx, "design");
    lua_geti(L, -1, (lua_Integer)i);
    p = lua_gettop(L);
    lua_getfield(L, ctx, "names");
    names = lua_gettop(L);
    lua_getfield(L, ctx, "outputs");
    outputs = lua_gettop(L);
    np = (lua_Integer)lua_rawlen(L, names);
    nout = (lua_Integer)lua_rawlen(L, outputs);
    dfle_lua_text_init(L, &pc);
    snprintf(buf, sizeof buf, "%zu", i);
    dfle_lua_text_str(L, &pc, buf);
    for (lua_Integer k = 1; k <= np; k++) {
        dfle_lua_text_str(L, &pc, ",");
        lua_geti(L, names, k);
        lua_gettable(L, p);
        push_value_text(L, -1, 1);
        dfle_lua_text_add(L, &pc);
        lua_pop(L, 1);
    }
    for (lua_Integer k = 1; k <= nout; k++) {
        dfle_lua_text_str(L, &pc, ",");
        if (lua_istable(L, top)) {
            lua_geti(L, top, k);
            push_number_text(L, lua_tonumber(L, -1));
            dfle_lua_text_add(L, &pc);
            lua_pop(L, 1);
        } else {
            dfle_lua_text_str(L, &pc, "nan");
        }
    }
    dfle_lua_text_str(L, &pc, ",");
    lua_pushvalue(L, top - 2);
    dfle_lua_text_add(L, &pc);
    dfle_lua_text_str(L, &pc, ",");
    push_value_text(L, top - 1, 1);
    dfle_lua_text_add(L, &pc);
    dfle_lua_text_finish(L, &pc);
    lua_replace(L, top - 2);
    lua_settop(L, top - 2);
    return failed;
}

/* ------------------------------------------------------------------ */
/* Reading a result file back into the table dfle.ensemble returns.    */

/* Split one CSV line; push each of its first maxpush fields (strings)
 * and return the count of all.  quoted[k] says whether field k was
 * quoted (up to maxq fields).  Fields past maxpush are only counted: a
 * damaged line of a million commas ran the stack out ("stack overflow
 * (too many columns)") instead of saying it has too many fields. */
static int push_fields(lua_State *L, const char *s, unsigned char *quoted, int maxq,
                       int maxpush)
{
    int n = 0;
    for (;;) {
        luaL_Buffer b;
        int q = 0;
        if (n >= maxpush) {
            int inq = 0;
            for (; *s != '\0'; s++) {
                if (*s == '"')
                    inq = !inq;
                else if (*s == ',' && !inq)
                    n++;
            }
            return n + 1;
        }
        luaL_checkstack(L, 2, "too many columns");
        luaL_buffinit(L, &b);
        if (*s == '"') {
            q = 1;
            s++;
            while (*s != '\0') {
                if (*s == '"' && s[1] == '"') {
                    luaL_addchar(&b, '"');
                    s += 2;
                } else if (*s == '"') {
                    s++;
                    break;
                } else {
                    luaL_addchar(&b, *s++);
                }
            }
            while (*s != '\0' && *s != ',')
                s++;
        } else {
            const char *e = strchr(s, ',');
            size_t len = e ? (size_t)(e - s) : strlen(s);
            luaL_addlstring(&b, s, len);
            s += len;
        }
        luaL_pushresult(&b);
        if (n < maxq)
            quoted[n] = (unsigned char)q;
        n++;
        if (*s != ',')
            return n;
        s++;
    }
}

/* The number in field string f (integers stay integers; "nan", "inf"
 * and an empty field as floats); text stays text. */
static void push_field_number(lua_State *L, int f)
{
    const char *s = lua_tostring(L, f);
    char *end;
    double v;
    if (lua_stringtonumber(L, s) != 0)
        return;
    v = strtod(s, &end);
    if (*s == '\0')
        lua_pushnumber(L, NAN);
    else if (*end == '\0')
        lua_pushnumber(L, v);
    else
        lua_pushvalue(L, f);
}

/* Value of token `key=` in the meta line, pushed (or nil). */
static void push_meta_token(lua_State *L, const char *meta, const char *key)
{
    size_t kl = strlen(key);
    const char *p = meta;
    while ((p = strstr(p, key)) != NULL) {
        if ((p == meta || p[-1] == ' ') && p[kl] == '=') {
            const char *v = p + kl + 1, *e = strchr(v, ' ');
            lua_pushlstring(L, v, e ? (size_t)(e - v) : strlen(v));
            return;
        }
        p += kl;
    }
    lua_pushnil(L);
}

/* Push a Lua array of the comma-separated names in the string at top. */
static void split_names(lua_State *L)
{
    const char *s = lua_tostring(L, -1);
    int k = 0;
    lua_newtable(L);
    while (s != NULL && *s != '\0') {
        const char *e = strchr(s, ',');
        size_t len = e ? (size_t)(e - s) : strlen(s);
        lua_pushlstring(L, s, len);
        lua_rawseti(L, -2, ++k);
        s += len + (e ? 1 : 0);
    }
    lua_remove(L, -2);
}

/* Push the result table of the ensemble file at `path`. */
void dfle_lua_ens_push_result(lua_State *L, const char *fn, const char *path, size_t shard_i,
                        size_t shard_n, lua_Integer ran)
{
    run_box *box = dfle_lua_ens_new_box(L);
    dfle_error err;
    dfle_ens_table *t;
    int res, data, inputs, outputs, header, counts;
    lua_Integer n = 0, nin, nout, ncols, ok = 0;
    unsigned char quoted[4096];

    if (dfle_ens_table_read(path, &box->table, &err) != DFLE_OK)
        luaL_error(L, "dfle.%s: %s", fn, err.msg);
    t = box->table;
    lua_newtable(L);
    res = lua_gettop(L);
    luaL_setmetatable(L, RESULT_MT);
    push_meta_token(L, t->meta, "n");
    n = lua_isnil(L, -1) ? 0 : (lua_Integer)lua_tointeger(L, -1);
    if (strncmp(t->meta, "# dfle.ensemble ", 16) != 0 || n < 1)
        luaL_error(L, "dfle.%s: %s: not a dfle.ensemble file (first line '%s')", fn, path, t->meta);
    lua_pop(L, 1);
    push_meta_token(L, t->meta, "inputs");
    split_names(L);
    inputs = lua_gettop(L);
    push_meta_token(L, t->meta, "outputs");
    split_names(L);
    outputs = lua_gettop(L);
    nin = (lua_Integer)lua_rawlen(L, inputs);
    nout = (lua_Integer)lua_rawlen(L, outputs);
    lua_pushstring(L, t->header);
    split_names(L);
    header = lua_gettop(L);
    ncols = (lua_Integer)lua_rawlen(L, header);
    if (ncols != nin + nout + 3)
        luaL_error(L, "dfle.%s: %s: header and first line disagree", fn, path);
    lua_newtable(L);
    data = lua_gettop(L);
    for (lua_Integer c = 1; c <= ncols; c++) {
        lua_geti(L, header, c);
        lua_createtable(L, (int)t->nrows, 0);
        lua_settable(L, data);
    }
    lua_newtable(L);
    counts = lua_gettop(L);
    luaL_checkstack(L, (int)ncols + 8, "too many columns");
    for (size_t r = 0; r < t->nrows; r++) {
        int base = lua_gettop(L);
        int nf = push_fields(L, t->rows[r], quoted, (int)sizeof quoted, (int)ncols + 1);
        if (nf != ncols)
            luaL_error(L, "dfle.%s: %s: sample %d has %d fields, the header %d", fn, path,
                       (int)t->index[r], nf, (int)ncols);
        for (lua_Integer c = 1; c <= ncols; c++) {
            int f = base + (int)c;
            lua_geti(L, header, c);
            lua_gettable(L, data);
            if (c == 1)
                lua_pushinteger(L, (lua_Integer)t->index[r]);
            else if (c >= ncols - 1 || (c - 1 < (lua_Integer)sizeof quoted && quoted[c - 1]))
                lua_pushvalue(L, f); /* status, reason, text parameters */
            else
                push_field_number(L, f);
            lua_rawseti(L, -2, (lua_Integer)r + 1);
            lua_pop(L, 1);
        }
        /* status count */
        lua_pushvalue(L, base + (int)ncols - 1);
        lua_pushvalue(L, -1);
        lua_gettable(L, counts);
        lua_pushinteger(L, lua_tointeger(L, -1) + 1);
        lua_remove(L, -2);
        lua_settable(L, counts);
        if (strcmp(lua_tostring(L, base + (int)ncols - 1), "ok") == 0)
            ok++;
        lua_settop(L, base);
    }
    lua_pushvalue(L, data), lua_setfield(L, res, "data");
    lua_pushvalue(L, inputs), lua_setfield(L, res, "inputs");
    lua_pushvalue(L, outputs), lua_setfield(L, res, "outputs");
    lua_pushvalue(L, counts), lua_setfield(L, res, "status");
    lua_pushinteger(L, n), lua_setfield(L, res, "n");
    lua_pushinteger(L, (lua_Integer)t->nrows), lua_setfield(L, res, "count");
    lua_pushinteger(L, ok), lua_setfield(L, res, "ok");
    lua_pushinteger(L, (lua_Integer)t->nrows - ok), lua_setfield(L, res, "failed");
    lua_pushinteger(L, ran), lua_setfield(L, res, "ran");
    lua_pushboolean(L, (lua_Integer)t->nrows == n), lua_setfield(L, res, "complete");
    lua_pushstring(L, path), lua_setfield(L, res, "file");
    if (shard_n > 1) {
        lua_createtable(L, 2, 0);
        lua_pushinteger(L, (lua_Integer)shard_i), lua_rawseti(L, -2, 1);
        lua_pushinteger(L, (lua_Integer)shard_n), lua_rawseti(L, -2, 2);
        lua_setfield(L, res, "shard");
    }
    lua_pushvalue(L, res);
    dfle_ens_table_free(box->table);
    box->table = NULL;
}

