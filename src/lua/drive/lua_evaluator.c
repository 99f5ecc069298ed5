/*
 * lua_evaluator.c - the Lua evaluator (dfle/evaluator.h) that
 * dfle.ensemble and dfle.invert hand their drivers: worker 0 evaluates
 * in the calling state with the call's own context table; every other
 * worker opens a state of its own from the host, replays the script to
 * the same call (lua_replay.c) and has the kind read the call's table
 * there, checking that it is the same call.  A sample runs protected: a
 * Lua error is a failed sample, whose reason is the error value, never
 * an error that unwinds the driver; an interrupt of the calling state
 * cuts the sample short (DFLE_ECANCELED), so it never becomes a row.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lua/drive/lua_parallel.h"

typedef struct lua_worker {
    const dfle_lua_eval_spec *spec;
    lua_State *L;
    int own;     /* L was made for this worker (closed with it)   */
    int ctx;     /* the context table's index in L                */
    worker_mode wm;
} lua_worker;

void dfle_lua_push_field_text(lua_State *L, int idx, int quote)
{
    idx = lua_absindex(L, idx);
    if (lua_isinteger(L, idx)) {
        char buf[32];
        snprintf(buf, sizeof buf, "%lld", (long long)lua_tointeger(L, idx));
        lua_pushstring(L, buf);
    } else if (lua_type(L, idx) == LUA_TNUMBER) {
        double v = lua_tonumber(L, idx);
        char buf[40];
        if (isnan(v))
            lua_pushliteral(L, "nan");
        else if (isinf(v))
            lua_pushstring(L, v > 0 ? "inf" : "-inf");
        else {
            snprintf(buf, sizeof buf, "%.17g", v);
            lua_pushstring(L, buf);
        }
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

/* The text of the number at idx without pushing anything (nothing may
 * raise here): as a field (raw: "%lld", 17 digits, nan, inf), or as
 * lua_tostring writes it ("%.14g", with ".0" on a whole float). */
static void number_text(lua_State *L, int idx, int raw, char *buf, size_t cap)
{
    double v;
    if (lua_isinteger(L, idx)) {
        snprintf(buf, cap, "%lld", (long long)lua_tointeger(L, idx));
        return;
    }
    v = lua_tonumber(L, idx);
    if (raw && (isnan(v) || isinf(v))) {
        snprintf(buf, cap, "%s", isnan(v) ? "nan" : v > 0 ? "inf" : "-inf");
        return;
    }
    snprintf(buf, cap, raw ? "%.17g" : LUA_NUMBER_FMT, v);
    if (!raw && buf[strspn(buf, "-0123456789")] == '\0')
        strncat(buf, ".0", cap - strlen(buf) - 1);
}

/* The reason of a sample whose Lua code raised the value on top (called
 * unprotected: it pushes nothing). */
static void raised(lua_State *L, const dfle_lua_kind *k, dfle_eval_out *out)
{
    char num[64];
    out->status = DFLE_EVAL_ERROR;
    if (lua_type(L, -1) == LUA_TNUMBER) {
        number_text(L, -1, k->raw_numbers, num, sizeof num);
        dfle_eval_reason(out, "%s", num);
        if (k->raw_numbers)
            out->flags |= DFLE_EVAL_REASON_NUMBER;
    } else if (lua_type(L, -1) == LUA_TSTRING) {
        dfle_eval_reason(out, "%s", lua_tostring(L, -1));
    } else if (k->raw_numbers) {
        dfle_eval_reason(out, "(error object is a %s value)", luaL_typename(L, -1));
    } else {
        dfle_eval_reason(out, "(error object is not a string)");
    }
}

/* eval_p(sample, ctx, job): the kind's sample as a parallel call in
 * progress (calls made inside it are nested), protected by the caller;
 * the sample's own error is raised again once the count is back. */
static int eval_p(lua_State *L)
{
    int st;
    dfle_lua_par_depth(L, +1);
    st = lua_pcall(L, 2, 0, 0);
    dfle_lua_par_depth(L, -1);
    if (st != LUA_OK)
        return lua_error(L);
    return 0;
}

static int lua_eval(void *state, size_t index, const double *x, dfle_eval_out *out,
                    dfle_error *err)
{
    lua_worker *w = state;
    const dfle_lua_kind *k = w->spec->kind;
    lua_State *L = w->L;
    int top = lua_gettop(L);
    dfle_lua_job job = {index, x, out};
    (void)err;

    /* Nothing here may raise (the driver's C frames are below): all of
     * it runs protected. */
    lua_pushcfunction(L, eval_p);
    lua_pushcfunction(L, k->sample);
    lua_pushvalue(L, w->ctx);
    lua_pushlightuserdata(L, &job);
    if (lua_pcall(L, 3, 0, 0) != LUA_OK)
        raised(L, k, out);
    lua_settop(L, top);
    if (k->gc_step) /* keep the collector up with what each run leaves behind */
        lua_gc(L, LUA_GCSTEP, 0);
    /* A sample the interrupt cut short is not a result: a resumed run
     * does it again. */
    return dfle_lua_interrupted(L) ? DFLE_ECANCELED : DFLE_OK;
}

/* prepare(table) in protected mode, and the same call as the main
 * state's; leaves the context. */
static int prepare_p(lua_State *L)
{
    const dfle_lua_eval_spec *s = lua_touserdata(L, 2);
    lua_settop(L, 1);
    lua_pushcfunction(L, s->kind->prepare);
    lua_insert(L, 1);
    lua_call(L, 1, 1);
    lua_getfield(L, -1, "identity");
    if (lua_type(L, -1) != LUA_TSTRING || strcmp(lua_tostring(L, -1), s->identity) != 0)
        return luaL_error(L, "worker: the script built a different %s when run again (the script "
                             "must do the same thing on every run up to %s)",
                          s->kind->what, dfle_lua_par_name(s->kind->kind));
    lua_pop(L, 1);
    return 1;
}

static int lua_open(void *ud, int worker, void **state, dfle_error *err)
{
    const dfle_lua_eval_spec *s = ud;
    lua_worker *w = calloc(1, sizeof *w);
    int nargs = 0, st;

    if (w == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "worker: out of memory");
    w->spec = s;
    if (worker == 0 && s->main != NULL) {
        w->L = s->main;
        w->ctx = s->main_ctx;
        *state = w;
        return DFLE_OK;
    }
    w->own = 1;
    w->wm.kind = s->kind->kind;
    w->wm.target = s->call;
    if ((w->L = dfle_lua_par_open(s->host, &nargs, err)) == NULL) {
        free(w);
        return err != NULL && err->code != DFLE_OK ? err->code : DFLE_ECALLBACK;
    }
    if ((st = dfle_lua_par_replay(w->L, nargs, &w->wm, s->host, err)) != DFLE_OK) {
        lua_close(w->L);
        free(w);
        return st;
    }
    /* stack: the call's table -> its context */
    lua_pushcfunction(w->L, prepare_p);
    lua_insert(w->L, 1);
    lua_pushlightuserdata(w->L, (void *)s);
    if (lua_pcall(w->L, 2, 1, 0) != LUA_OK) {
        const char *m = lua_tostring(w->L, -1);
        st = dfle_error_set(err, DFLE_ECALLBACK, "%s", m != NULL ? m : "worker failed");
        lua_close(w->L);
        free(w);
        return st;
    }
    w->ctx = lua_gettop(w->L);
    *state = w;
    return DFLE_OK;
}

static void lua_close_worker(void *state)
{
    lua_worker *w = state;
    if (w == NULL)
        return;
    if (w->own)
        lua_close(w->L);
    free(w);
}

static const dfle_evaluator_ops lua_evaluator_ops = {
    .version = DFLE_EVALUATOR_VERSION,
    .name = "lua",
    .open = lua_open,
    .eval = lua_eval,
    .close = lua_close_worker,
};

static char *dup_text(const char *s)
{
    char *p = malloc(strlen(s) + 1);
    if (p != NULL)
        strcpy(p, s);
    return p;
}

static const char *kind_word(const dfle_lua_kind *k)
{
    return k->kind == DFLE_LUA_PAR_INVERT ? "invert" : "ensemble";
}

int dfle_lua_evaluator_init(dfle_lua_eval_spec *s, const dfle_lua_kind *kind,
                            const dfle_lua_host *host, lua_State *main, int main_ctx,
                            lua_Integer call, const char *identity, dfle_error *err)
{
    size_t len = strlen(identity) + 64;
    memset(s, 0, sizeof *s);
    s->kind = kind;
    s->host = host;
    s->main = main;
    s->main_ctx = main_ctx;
    s->call = call;
    s->identity = dup_text(identity);
    s->key = malloc(len);
    if (s->identity == NULL || s->key == NULL) {
        dfle_lua_evaluator_release(s);
        return dfle_error_set(err, DFLE_ENOMEM, "out of memory");
    }
    snprintf(s->key, len, "dfle.lua %s %lld\n%s", kind_word(kind), (long long)call, identity);
    s->ev.ops = &lua_evaluator_ops;
    s->ev.ud = s;
    /* Other processes can replay a script that runs in the command, not a
     * call nested in another one. */
    s->ev.key = host != NULL && host->open_state != NULL && call > 0 ? s->key : NULL;
    return DFLE_OK;
}

int dfle_lua_evaluator_from_key(dfle_lua_eval_spec *s, const dfle_lua_kind *kind,
                                const dfle_lua_host *host, const char *key, dfle_error *err)
{
    char word[16];
    long long call = 0;
    const char *nl = strchr(key, '\n');
    memset(s, 0, sizeof *s);
    if (nl == NULL || sscanf(key, "dfle.lua %15s %lld", word, &call) != 2 || call < 1 ||
        strcmp(word, kind_word(kind)) != 0)
        return dfle_error_set(err, DFLE_EINVAL, "worker: '%.40s' names no %s call of this "
                              "binding", key, dfle_lua_par_name(kind->kind));
    return dfle_lua_evaluator_init(s, kind, host, NULL, 0, (lua_Integer)call, nl + 1, err);
}

void dfle_lua_evaluator_release(dfle_lua_eval_spec *s)
{
    free(s->identity);
    free(s->key);
    s->identity = s->key = NULL;
}
