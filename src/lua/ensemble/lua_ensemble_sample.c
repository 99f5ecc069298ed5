/*
 * lua_ensemble_sample.c - one sample of dfle.ensemble: build its model,
 * run it to steady state, fit and measure it, all protected, into one
 * CSV row, and the text of the row's fields.
 *
 * The row is the same text whichever state ran the sample.  A sample that
 * fails (no steady state, a failed fit, a NaN output, an error in the
 * script's build or measure) is a row too, whose status and reason say
 * why: one bad corner of the design does not stop an ensemble.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "lua/ensemble/lua_ensemble_internal.h"

/* ------------------------------------------------------------------ */
/* The text of a field.                                                */

void dfle_lua_ens_push_number_text(lua_State *L, double v)
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
void dfle_lua_ens_push_value_text(lua_State *L, int idx, int quote)
{
    idx = lua_absindex(L, idx);
    if (lua_isinteger(L, idx)) {
        char buf[32];
        snprintf(buf, sizeof buf, "%lld", (long long)lua_tointeger(L, idx));
        lua_pushstring(L, buf);
    } else if (lua_type(L, idx) == LUA_TNUMBER) {
        dfle_lua_ens_push_number_text(L, lua_tonumber(L, idx));
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
        dfle_lua_ens_push_value_text(L, -1, 1);
        dfle_lua_text_add(L, &pc);
        lua_pop(L, 1);
    }
    for (lua_Integer k = 1; k <= nout; k++) {
        dfle_lua_text_str(L, &pc, ",");
        if (lua_istable(L, top)) {
            lua_geti(L, top, k);
            dfle_lua_ens_push_number_text(L, lua_tonumber(L, -1));
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
    dfle_lua_ens_push_value_text(L, top - 1, 1);
    dfle_lua_text_add(L, &pc);
    dfle_lua_text_finish(L, &pc);
    lua_replace(L, top - 2);
    lua_settop(L, top - 2);
    return failed;
}
