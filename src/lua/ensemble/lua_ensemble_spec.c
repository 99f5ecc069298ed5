/*
 * lua_ensemble_spec.c - the dfle.ensemble table read into the driver's
 * options (dfle/ensemble_run.h) and a context table that the samples
 * use (build, measure, the run and fit options, the parameters' Lua
 * values), in every state that runs samples.
 *
 * The design's parameters are checked by dfle.lhs, whose messages become
 * this function's; names, outputs and the file's lines are checked once,
 * by the driver (dfle_ensemble_identity).  The C options point into
 * userdata and strings that the context table holds, so nothing here
 * needs freeing if anything raises.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lua/ensemble/lua_ensemble_internal.h"

static const char *const spec_keys[] = {"params", "order", "centered", "build", "measure",
                                        "outputs", "out", "resume", "run", "fit", "units",
                                        "record", NULL};

/* Scratch held by the context table at ctx under `key`. */
static void *held(lua_State *L, int ctx, const char *key, size_t size)
{
    void *p = lua_newuserdatauv(L, size ? size : 1, 0);
    memset(p, 0, size ? size : 1);
    lua_setfield(L, ctx, key);
    return p;
}

/* The design's parameters (names at `names`, specs in the table `params`)
 * into the options: ranges, or a discrete parameter's values, whose texts
 * the file shows (ctx.values[j]: the Lua values, false for a range). */
static void read_design(lua_State *L, int ctx, int params, int names, spec *s)
{
    const size_t np = (size_t)lua_rawlen(L, names);
    dfle_ensemble_param *p = held(L, ctx, "c_params", np * sizeof *p);
    int values, texts;

    lua_createtable(L, (int)np, 0);
    values = lua_gettop(L);
    lua_createtable(L, (int)np, 0);
    texts = lua_gettop(L);
    for (size_t k = 0; k < np; k++) {
        int sp;
        lua_geti(L, names, (lua_Integer)k + 1);
        p[k].name = lua_tostring(L, -1); /* held by names */
        lua_gettable(L, params);
        sp = lua_gettop(L);
        if (lua_getfield(L, sp, "values") == LUA_TTABLE) {
            int vals = lua_gettop(L);
            size_t nv = (size_t)lua_rawlen(L, vals);
            const char **vt = lua_newuserdatauv(L, nv * sizeof *vt, 0);
            lua_rawseti(L, texts, (lua_Integer)(2 * k + 1)); /* anchors vt */
            lua_createtable(L, (int)nv, 0);
            for (size_t j = 0; j < nv; j++) {
                lua_geti(L, vals, (lua_Integer)j + 1);
                dfle_lua_push_field_text(L, -1, 1);
                vt[j] = lua_tostring(L, -1);
                lua_rawseti(L, -3, (lua_Integer)j + 1); /* anchors the text */
                lua_pop(L, 1);
            }
            lua_rawseti(L, texts, (lua_Integer)(2 * k + 2));
            p[k].kind = DFLE_LHS_DISCRETE;
            p[k].nvalues = nv;
            p[k].value_text = vt;
            lua_pushvalue(L, vals);
        } else {
            lua_pop(L, 1);
            lua_geti(L, sp, 1);
            lua_geti(L, sp, 2);
            p[k].lo = lua_tonumber(L, -2);
            p[k].hi = lua_tonumber(L, -1);
            lua_getfield(L, sp, "log");
            p[k].kind = lua_toboolean(L, -1) ? DFLE_LHS_LOG_UNIFORM : DFLE_LHS_UNIFORM;
            lua_pop(L, 3);
            lua_pushboolean(L, 0);
        }
        lua_rawseti(L, values, (lua_Integer)k + 1);
        lua_settop(L, texts);
    }
    lua_setfield(L, ctx, "c_texts");
    lua_setfield(L, ctx, "values");
    s->o.nparams = np;
    s->o.params = p;
}

/* The units of parameters and outputs: the script's `units` table first,
 * then (for outputs) those dfle knows. */
static void read_units(lua_State *L, int arg, int ctx, const char *fn, spec *s)
{
    const char **ou = held(L, ctx, "c_units", s->o.noutputs * sizeof *ou);
    dfle_ensemble_param *p = (dfle_ensemble_param *)s->o.params;
    int units = 0, top = lua_gettop(L);

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
            for (size_t k = 0; k < s->o.nparams + s->o.noutputs && !known; k++)
                known = strcmp(k < s->o.nparams ? p[k].name : s->o.outputs[k - s->o.nparams],
                               lua_tostring(L, -2)) == 0;
            if (!known)
                luaL_error(L, "dfle.%s: units names '%s', which is neither a parameter nor an "
                              "output", fn, lua_tostring(L, -2));
            lua_pop(L, 1);
        }
        lua_pushvalue(L, units);
        lua_setfield(L, ctx, "c_units_table"); /* anchors the unit texts */
    }
    for (size_t k = 0; k < s->o.nparams + s->o.noutputs; k++) {
        const char *name = k < s->o.nparams ? p[k].name : s->o.outputs[k - s->o.nparams];
        const char *u = NULL;
        if (units != 0 && lua_getfield(L, units, name) == LUA_TSTRING)
            u = lua_tostring(L, -1);
        if (units != 0)
            lua_pop(L, 1);
        if (k < s->o.nparams)
            p[k].unit = u;
        else
            ou[k - s->o.nparams] = u != NULL ? u : dfle_ensemble_known_unit(name);
    }
    lua_settop(L, top);
    s->o.output_units = ou;
}

/* The record of the run and fit options: the file's comment lines. */
static void read_describe(lua_State *L, int arg, int ctx, spec *s)
{
    dfle_record *rec = dfle_lua_push_empty_record(L);
    lua_setfield(L, ctx, "c_describe");
    for (int k = 0; k < 2; k++) {
        const char *key = k == 0 ? "run" : "fit";
        if (lua_getfield(L, arg, key) == LUA_TTABLE) {
            dfle_record_section(rec, key, NULL);
            dfle_lua_record_table(L, rec, -1, 1);
        }
        lua_pop(L, 1);
    }
    s->o.describe = rec;
}

void dfle_lua_ens_read_spec(lua_State *L, int arg, const char *fn, spec **sp,
                            const dfle_lua_host *host)
{
    double n = -1, seed = 1, workers = 0, limit = 0;
    const dfle_lua_param nums[] = {
        {"n", &n}, {"seed", &seed}, {"workers", &workers}, {"limit", &limit}};
    int ctx, outputs, names;
    run_box *box;
    dfle_error err;
    spec *s;

    arg = lua_absindex(L, arg);
    luaL_checktype(L, arg, LUA_TTABLE);
    dfle_lua_read_params(L, arg, fn, nums, 4, spec_keys);
    if (n < 0)
        luaL_error(L, "dfle.%s: parameter 'n' (number of samples) is required", fn);
    lua_newtable(L);
    ctx = lua_gettop(L);
    s = held(L, ctx, "c_spec", sizeof *s);
    dfle_ensemble_opts_default(&s->o);
    s->o.n = (size_t)dfle_lua_check_whole(L, n, fn, "n", 1, 4294967295.0);
    s->o.seed = (unsigned long)dfle_lua_check_whole(L, seed, fn, "seed", 0, 4294967295.0);
    s->workers = (int)dfle_lua_check_whole(L, workers, fn, "workers", 0, 4096);
    s->o.limit = (size_t)dfle_lua_check_whole(L, limit, fn, "limit", 0, 4294967295.0);
    s->o.shard_i = host != NULL ? host->shard_i : 0;
    s->o.shard_n = host != NULL ? host->shard_n : 0;

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
    if (lua_getfield(L, arg, "resume") != LUA_TNIL) {
        if (!lua_isboolean(L, -1))
            luaL_error(L, "dfle.%s: parameter 'resume' must be a boolean", fn);
        s->o.resume = lua_toboolean(L, -1);
    }
    lua_pop(L, 1);
    if (lua_getfield(L, arg, "centered") != LUA_TNIL)
        s->o.centered = lua_toboolean(L, -1);
    lua_pop(L, 1);
    if (lua_getfield(L, arg, "out") != LUA_TSTRING)
        luaL_error(L, "dfle.%s: parameter 'out' (the CSV file of results) must be a file name, "
                      "got %s", fn, luaL_typename(L, -1));
    s->o.out = dfle_lua_check_string(L, -1, fn, "out");
    lua_setfield(L, ctx, "out_base"); /* holds s->o.out */
    {
        char path[4096];
        if (dfle_ensemble_shard_path(s->o.out, s->o.shard_i, s->o.shard_n, path, sizeof path,
                                     &err) != DFLE_OK)
            dfle_lua_raise(L, &err);
        lua_pushstring(L, path);
        lua_setfield(L, ctx, "out");
    }

    /* The design's parameters, checked by dfle.lhs (params, order). */
    dfle_lua_push_module(L);
    lua_getfield(L, -1, "lhs");
    lua_createtable(L, 0, 5);
    lua_pushinteger(L, 1), lua_setfield(L, -2, "n"); /* the driver draws the design */
    lua_pushinteger(L, (lua_Integer)s->o.seed), lua_setfield(L, -2, "seed");
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
    lua_pushvalue(L, names), lua_setfield(L, ctx, "names");
    lua_getfield(L, arg, "params");
    read_design(L, ctx, lua_gettop(L), names, s);
    lua_settop(L, names);

    if (lua_getfield(L, arg, "outputs") != LUA_TTABLE || lua_rawlen(L, -1) == 0)
        luaL_error(L, "dfle.%s: parameter 'outputs' must be a non-empty array of names "
                      "(e.g. {\"S_df\", \"A_df\"})", fn);
    outputs = lua_gettop(L);
    s->o.noutputs = (size_t)lua_rawlen(L, outputs);
    {
        const char **on = held(L, ctx, "c_outputs", s->o.noutputs * sizeof *on);
        for (size_t k = 0; k < s->o.noutputs; k++) {
            if (lua_geti(L, outputs, (lua_Integer)k + 1) != LUA_TSTRING)
                luaL_error(L, "dfle.%s: outputs[%d] must be a name, got %s", fn, (int)k + 1,
                           luaL_typename(L, -1));
            on[k] = dfle_lua_check_string(L, -1, fn, "an output name"); /* held by outputs */
            lua_pop(L, 1);
        }
        s->o.outputs = on;
    }
    lua_pushvalue(L, outputs), lua_setfield(L, ctx, "outputs");
    /* Names, outputs and the file's lines: the driver's checks. */
    box = dfle_lua_ens_new_box(L); /* frees the texts if pushing them raises */
    if (dfle_ensemble_identity(&s->o, &box->meta, &box->header, &err) != DFLE_OK)
        dfle_lua_raise(L, &err);
    lua_pushstring(L, box->meta);
    lua_pushstring(L, box->header);
    lua_pushfstring(L, "%s\n%s", box->meta, box->header);
    free(box->meta);
    free(box->header);
    box->meta = box->header = NULL;
    lua_setfield(L, ctx, "identity");
    lua_setfield(L, ctx, "header");
    lua_setfield(L, ctx, "meta");
    lua_pop(L, 1); /* the box */
    read_units(L, arg, ctx, fn, s);
    read_describe(L, arg, ctx, s);
    lua_settop(L, ctx);
    *sp = s;
}
