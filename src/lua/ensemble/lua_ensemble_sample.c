/*
 * lua_ensemble_sample.c - one sample of dfle.ensemble in Lua, the kind
 * the Lua evaluator runs (lua/drive/lua_parallel.h): the
 * parameter table p from the driver's x, then build(p), its steady
 * state, the slope-area fit and measure, and the outputs by name.  The
 * driver makes the row (dfle/ensemble_run.h), the same text whichever
 * state ran the sample.
 *
 * A sample that fails (no steady state, a failed fit, a NaN output, an
 * error in the script's build or measure) is a result too, whose status
 * and reason say why: one bad corner of the design does not stop an
 * ensemble.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lua/ensemble/lua_ensemble_internal.h"

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

/* The reason (a value at idx: the run's reason, the fit's message) of a
 * failed sample. */
static void fail_with(lua_State *L, dfle_eval_out *out, int status, int idx, const char *dflt)
{
    out->status = status;
    if (lua_type(L, idx) == LUA_TNUMBER) {
        dfle_lua_push_field_text(L, idx, 0);
        dfle_eval_reason(out, "%s", lua_tostring(L, -1));
        out->flags |= DFLE_EVAL_REASON_NUMBER;
        lua_pop(L, 1);
    } else if (lua_type(L, idx) == LUA_TSTRING) {
        dfle_eval_reason(out, "%s", lua_tostring(L, idx));
    } else if (lua_isnil(L, idx)) {
        dfle_eval_reason(out, "%s", dflt);
    } else {
        dfle_eval_reason(out, "%s", luaL_tolstring(L, idx, NULL));
        lua_pop(L, 1);
    }
}

/* sample(ctx, job): runs protected (lua_evaluator.c). */
static int sample(lua_State *L)
{
    const dfle_lua_job *jb = lua_touserdata(L, 2);
    dfle_eval_out *out = jb->out;
    int p, m, res, fit, extra, names, values;
    lua_Integer nout, np;

    lua_settop(L, 2);
    /* p: the sample's parameters (a discrete one's chosen value) */
    lua_getfield(L, 1, "names");
    names = lua_gettop(L);
    lua_getfield(L, 1, "values");
    values = lua_gettop(L);
    np = (lua_Integer)lua_rawlen(L, names);
    lua_createtable(L, 0, (int)np);
    p = lua_gettop(L);
    for (lua_Integer k = 1; k <= np; k++) {
        lua_geti(L, names, k);
        if (lua_geti(L, values, k) == LUA_TTABLE) {
            lua_geti(L, -1, (lua_Integer)jb->x[k - 1] + 1);
            lua_remove(L, -2);
        } else {
            lua_pop(L, 1);
            lua_pushnumber(L, jb->x[k - 1]);
        }
        lua_rawset(L, p);
    }
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
        lua_getfield(L, res, "reason");
        fail_with(L, out, DFLE_EVAL_NOT_CONVERGED, -1, "no steady state");
        return 0;
    }
    lua_pop(L, 1);

    dfle_lua_push_module(L);
    lua_getfield(L, -1, "fit_slope_area");
    lua_pushvalue(L, m);
    lua_getfield(L, 1, "fit");
    lua_call(L, 2, 2);
    if (lua_isnil(L, -2)) {
        fail_with(L, out, DFLE_EVAL_FIT_FAILED, -1, "nil");
        return 0;
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
    for (lua_Integer k = 1; k <= nout; k++) {
        int top = lua_gettop(L), t = LUA_TNIL;
        const char *name;
        double v;
        lua_geti(L, top, k);
        name = lua_tostring(L, -1);
        if (extra)
            t = lua_getfield(L, extra, name);
        if (t == LUA_TNIL) {
            lua_settop(L, top + 1);
            lua_pushstring(L, name);
            t = lua_rawget(L, fit); /* raw: the fit table raises on unknown keys */
        }
        if (t == LUA_TNIL) {
            lua_settop(L, top + 1);
            lua_pushstring(L, name);
            t = lua_rawget(L, res);
        }
        if (t == LUA_TNIL && (strcmp(name, "runout_A") == 0 || strcmp(name, "runout_x") == 0)) {
            lua_settop(L, top + 1);
            push_runout(L, m, name);
            t = LUA_TNUMBER;
        }
        if (t != LUA_TNUMBER)
            return luaL_error(L, "output '%s' is %s (not a fit value%s)", name,
                              t == LUA_TNIL ? "missing" : luaL_typename(L, -1),
                              extra ? " nor returned by measure" : "; compute it in measure");
        v = lua_tonumber(L, -1);
        out->y[k - 1] = v;
        if (!isfinite(v))
            return 0; /* the driver names it: status "nan" */
        lua_settop(L, top);
    }
    return 0;
}

/* prepare(table): a worker's context. */
static int prepare(lua_State *L)
{
    spec *s;
    lua_settop(L, 1);
    dfle_lua_ens_read_spec(L, 1, "ensemble", &s, dfle_lua_host_of(L));
    return 1;
}

const dfle_lua_kind dfle_lua_ens_kind = {
    .kind = DFLE_LUA_PAR_ENSEMBLE,
    .name = "lua.ensemble",
    .prepare = prepare,
    .what = "ensemble",
    .sample = sample,
    .raw_numbers = 1,
    .gc_step = 0,
};

/* ------------------------------------------------------------------ */
/* The evaluator other processes open from a key.                      */

int dfle_lua_ensemble_remote(const dfle_lua_host *host, const char *key, dfle_evaluator **ev,
                             dfle_error *err)
{
    dfle_lua_eval_spec *s = calloc(1, sizeof *s);
    int st;
    *ev = NULL;
    if (s == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "out of memory");
    if ((st = dfle_lua_evaluator_from_key(s, &dfle_lua_ens_kind, host, key, err)) != DFLE_OK) {
        free(s);
        return st;
    }
    *ev = &s->ev;
    return DFLE_OK;
}

void dfle_lua_ensemble_remote_free(dfle_evaluator *ev)
{
    dfle_lua_eval_spec *s;
    if (ev == NULL)
        return;
    s = ev->ud;
    dfle_lua_evaluator_release(s);
    free(s);
}
