/*
 * lua_ensemble_spec.c - the dfle.ensemble table checked into a context
 * table (design, build, measure, outputs, out, ...), and the lines that
 * identify the ensemble's file: the meta line, the comment lines under
 * it (version, run and fit options, units) and the CSV header.
 *
 * The meta line is what resume and dfle.gather check a file against,
 * so it holds everything that makes two ensembles the same (n, seed,
 * the design, inputs and outputs) and nothing that changes from one run
 * to the next.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lua/ensemble/lua_ensemble_internal.h"

#ifndef DFLE_VERSION
#define DFLE_VERSION "unknown"
#endif

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
                dfle_lua_ens_push_value_text(L, -1, 1);
                dfle_lua_text_add(L, &pc);
                lua_pop(L, 1);
            }
            dfle_lua_text_str(L, &pc, "}");
        } else {
            dfle_lua_text_str(L, &pc, ":[");
            lua_geti(L, p, 1);
            dfle_lua_ens_push_number_text(L, lua_tonumber(L, -1));
            dfle_lua_text_add(L, &pc);
            dfle_lua_text_str(L, &pc, ",");
            lua_geti(L, p, 2);
            dfle_lua_ens_push_number_text(L, lua_tonumber(L, -1));
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
