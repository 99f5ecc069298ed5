/*
 * lua_invert_spec.c - the dfle.invert table checked into a problem: the
 * free parameters and their priors, the fixed ones, the binned data, the
 * channel the data's A(x) gives, the sampler's settings (the driver's
 * options, dfle/invert_run.h, checked by it), and what identifies the
 * problem in the chain file's first line.
 *
 * Every state that evaluates the posterior runs this on the same table
 * (workers replay the script to it), so it must be a pure function of
 * the table: names are sorted, data binned the same way, and the identity
 * line lets a worker, or a resumed run, check that it has the same
 * problem as the main state, or the file.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lua/invert/lua_invert_internal.h"


#define DEFAULT_NBINS 30
#define DEFAULT_STEPS 2000

/* ------------------------------------------------------------------ */
/* The box: C memory of a run, freed by __gc if anything raises.       */

static int box_gc(lua_State *L)
{
    inv_run *R = luaL_checkudata(L, 1, INV_BOX);
    dfle_invert_free(R->inv);
    dfle_csv_free(R->csv);
    free(R->prior);
    free(R->logs);
    free(R->custom);
    free(R->A_obs);
    free(R->lnS_obs);
    free(R->r);
    free(R->text[0]);
    free(R->text[1]);
    if (R->ev_set)
        dfle_lua_evaluator_release(&R->ev);
    memset(R, 0, sizeof *R);
    return 0;
}

void inv_push_box(lua_State *L)
{
    inv_run *R = lua_newuserdatauv(L, sizeof *R, 0);
    memset(R, 0, sizeof *R);
    if (luaL_newmetatable(L, INV_BOX)) {
        lua_pushcfunction(L, box_gc);
        lua_setfield(L, -2, "__gc");
    }
    lua_setmetatable(L, -2);
}

static void *box_alloc(lua_State *L, size_t n, size_t size)
{
    void *p = calloc(n ? n : 1, size);
    if (p == NULL)
        luaL_error(L, "dfle.invert: out of memory");
    return p;
}

/* ------------------------------------------------------------------ */
/* The identity line's pieces.                                        */

/* FNV-1a, 64 bits: a fingerprint of data in the identity line. */
static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
    const unsigned char *c = p;
    for (size_t i = 0; i < n; i++) {
        h ^= c[i];
        h *= 0x100000001b3ULL;
    }
    return h;
}
#define FNV0 0xcbf29ce484222325ULL

static void text_hex(lua_State *L, dfle_lua_text *p, uint64_t h)
{
    char buf[24];
    snprintf(buf, sizeof buf, "%016llx", (unsigned long long)h);
    dfle_lua_text_str(L, p, buf);
}

/* A value as text for the identity line: numbers with 17 digits, other
 * text without line breaks. */
static void text_value(lua_State *L, dfle_lua_text *p, int idx)
{
    char buf[40];
    idx = lua_absindex(L, idx);
    if (lua_type(L, idx) == LUA_TNUMBER && !lua_isinteger(L, idx)) {
        snprintf(buf, sizeof buf, "%.17g", lua_tonumber(L, idx));
        dfle_lua_text_str(L, p, buf);
    } else {
        const char *s = luaL_tolstring(L, idx, NULL);
        luaL_Buffer b;
        luaL_buffinit(L, &b);
        for (; *s != '\0'; s++)
            luaL_addchar(&b, (*s == '\n' || *s == '\r' || *s == ' ') ? '_' : *s);
        luaL_pushresult(&b);
        lua_remove(L, -2);
        dfle_lua_text_add(L, p);
    }
}

/* ------------------------------------------------------------------ */
/* Names and priors.                                                   */

/* lua_call of a dfle method from here, its error raised again from
 * dfle.invert, which has the script's position (a method called from C
 * has none to give). */
static void call_method(lua_State *L, int nargs, const char *what)
{
    if (lua_pcall(L, nargs, 1, 0) != LUA_OK)
        luaL_error(L, "dfle.invert: %s: %s", what,
                   lua_isstring(L, -1) ? lua_tostring(L, -1) : "failed");
}

static void check_name(lua_State *L, const char *what, const char *name)
{
    static const char *const reserved[] = {"index", "step", "walker", "log_post", "log_like",
                                           "proposal", "sigma", "channel", NULL};
    if (name[0] == '\0' || strpbrk(name, ",\"\r\n =;:[]") != NULL)
        luaL_error(L, "dfle.invert: %s name '%s' cannot be a CSV column (no commas, quotes, "
                      "spaces, '=', ';', ':', brackets or line breaks)", what, name);
    for (int k = 0; reserved[k] != NULL; k++)
        if (strcmp(name, reserved[k]) == 0)
            luaL_error(L, "dfle.invert: %s name '%s' is reserved%s", what, name,
                       strcmp(name, "sigma") == 0 ? " for the noise scale: give its prior or "
                       "value as the key 'sigma'" : "");
}

static double spec_number(lua_State *L, int sp, const char *key, lua_Integer i,
                          const char *name, double dflt, int required)
{
    int t = key != NULL ? lua_getfield(L, sp, key) : lua_geti(L, sp, i);
    double v = dflt;
    if (t == LUA_TNIL) {
        if (required)
            luaL_error(L, "dfle.invert: parameter '%s': the range needs %s (give {lo, hi}, "
                          "{lo, hi, log = true}, {normal = {mean, sd}} or {lo, hi, density = "
                          "function(x) ... end})", name, i == 1 ? "lo" : "hi");
    } else if (t != LUA_TNUMBER) {
        luaL_error(L, "dfle.invert: parameter '%s': %s must be a number, got %s", name,
                   key != NULL ? key : i == 1 ? "lo" : "hi", luaL_typename(L, -1));
    } else {
        v = lua_tonumber(L, -1);
    }
    lua_pop(L, 1);
    return v;
}

/* The prior sp at index sp for parameter `name`; a density function
 * is stored in ctx.density[name]. */
static void read_prior(lua_State *L, int sp, const char *name, int density_tab, dfle_prior *p)
{
    static const char *const keys[] = {"log", "normal", "density", "lo", "hi", NULL};
    int has_log = 0;
    dfle_error err;

    memset(p, 0, sizeof *p);
    sp = lua_absindex(L, sp);
    if (!lua_istable(L, sp))
        luaL_error(L, "dfle.invert: parameter '%s': a prior is a table ({lo, hi}, {lo, hi, log = "
                      "true}, {normal = {mean, sd}}, {lo, hi, density = function(x) ... end}), "
                      "got %s", name, luaL_typename(L, sp));
    lua_pushnil(L);
    while (lua_next(L, sp) != 0) {
        int ok = lua_type(L, -2) == LUA_TNUMBER && lua_tointeger(L, -2) >= 1 &&
                 lua_tointeger(L, -2) <= 2;
        for (int k = 0; !ok && keys[k] != NULL; k++)
            ok = lua_type(L, -2) == LUA_TSTRING && strcmp(lua_tostring(L, -2), keys[k]) == 0;
        if (!ok)
            luaL_error(L, "dfle.invert: parameter '%s': unknown key '%s' in its prior (known: "
                          "1, 2, log, normal, density, lo, hi)", name,
                       luaL_tolstring(L, -2, NULL));
        lua_pop(L, 1);
    }
    if (lua_getfield(L, sp, "log") != LUA_TNIL) {
        if (!lua_isboolean(L, -1))
            luaL_error(L, "dfle.invert: parameter '%s': log must be a boolean", name);
        has_log = lua_toboolean(L, -1);
    }
    lua_pop(L, 1);
    if (lua_getfield(L, sp, "normal") != LUA_TNIL) {
        if (!lua_istable(L, -1) || lua_geti(L, -1, 1) != LUA_TNUMBER ||
            lua_geti(L, -2, 2) != LUA_TNUMBER)
            luaL_error(L, "dfle.invert: parameter '%s': normal must be {mean, sd}", name);
        p->kind = has_log ? DFLE_PRIOR_LOG_NORMAL : DFLE_PRIOR_NORMAL;
        p->mean = lua_tonumber(L, -2);
        p->sd = lua_tonumber(L, -1);
        lua_pop(L, 3);
        lua_geti(L, sp, 1);
        if (!lua_isnil(L, -1))
            luaL_error(L, "dfle.invert: parameter '%s': a normal prior takes lo = and hi = for "
                          "a truncation, not {lo, hi}", name);
        lua_pop(L, 1);
        p->lo = spec_number(L, sp, "lo", 0, name, has_log ? 0.0 : -INFINITY, 0);
        p->hi = spec_number(L, sp, "hi", 0, name, INFINITY, 0);
    } else {
        lua_pop(L, 1);
        p->lo = spec_number(L, sp, NULL, 1, name, 0, 1);
        p->hi = spec_number(L, sp, NULL, 2, name, 0, 1);
        if (lua_getfield(L, sp, "lo") != LUA_TNIL || lua_getfield(L, sp, "hi") != LUA_TNIL)
            luaL_error(L, "dfle.invert: parameter '%s': lo = and hi = go with a normal prior; a "
                          "range is {lo, hi}", name);
        lua_pop(L, 2);
        if (lua_getfield(L, sp, "density") != LUA_TNIL) {
            if (!lua_isfunction(L, -1))
                luaL_error(L, "dfle.invert: parameter '%s': density must be a function(x) "
                              "returning ln p(x), got %s", name, luaL_typename(L, -1));
            lua_setfield(L, density_tab, name);
            p->kind = DFLE_PRIOR_CUSTOM;
            p->log_scale = has_log;
        } else {
            lua_pop(L, 1);
            p->kind = has_log ? DFLE_PRIOR_LOG_UNIFORM : DFLE_PRIOR_UNIFORM;
        }
    }
    if (dfle_prior_check(p, name, &err) != DFLE_OK)
        luaL_error(L, "dfle.invert: parameter %s", err.msg);
}

/* ------------------------------------------------------------------ */
/* The identity line.                                                  */

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

/* What the first line of the chain file says after the sampler's
 * settings and the priors (the driver writes those): the fixed sigma and
 * parameters, fingerprints of the data and the channel, the run options
 * and build's byte code.  Pushed (ctx.problem). */
static void push_problem(lua_State *L, int ctx, inv_run *R)
{
    dfle_lua_text t;
    char buf[512];
    uint64_t h = FNV0;
    int names, fixed;

    lua_getfield(L, ctx, "names");
    names = lua_gettop(L);
    lua_getfield(L, ctx, "fixed");
    fixed = lua_gettop(L);
    dfle_lua_text_init(L, &t);
    if (!R->sigma_free) {
        snprintf(buf, sizeof buf, " sigma=%.17g", R->sigma);
        dfle_lua_text_str(L, &t, buf);
    }
    dfle_lua_text_str(L, &t, " fixed=");
    {
        /* sorted keys: a table has no order */
        size_t nk = 0, k = 0;
        const char **keys;
        lua_pushnil(L);
        while (lua_next(L, fixed) != 0) {
            lua_pop(L, 1);
            nk++;
        }
        keys = lua_newuserdatauv(L, (nk ? nk : 1) * sizeof *keys, 0);
        lua_pushnil(L);
        while (lua_next(L, fixed) != 0) {
            lua_pop(L, 1);
            keys[k++] = lua_tostring(L, -1); /* held by the fixed table */
        }
        qsort(keys, nk, sizeof *keys, cmp_str);
        for (k = 0; k < nk; k++) {
            if (k > 0)
                dfle_lua_text_str(L, &t, ",");
            dfle_lua_text_str(L, &t, keys[k]);
            dfle_lua_text_str(L, &t, ":");
            lua_getfield(L, fixed, keys[k]);
            text_value(L, &t, -1);
            lua_pop(L, 1);
        }
        lua_pop(L, 1);
    }
    dfle_lua_text_str(L, &t, " data=");
    snprintf(buf, sizeof buf, "%zu:", R->nobs);
    dfle_lua_text_str(L, &t, buf);
    h = fnv(h, R->A_obs, R->nobs * sizeof *R->A_obs);
    h = fnv(h, R->lnS_obs, R->nobs * sizeof *R->lnS_obs);
    text_hex(L, &t, h);
    dfle_lua_text_str(L, &t, " channel=");
    if (lua_getfield(L, ctx, "channel") == LUA_TNIL) {
        lua_pop(L, 1);
        dfle_lua_text_str(L, &t, "none");
    } else {
        const dfle_channel *ch = dfle_lua_check_channel(L, -1);
        lua_pop(L, 1);
        snprintf(buf, sizeof buf, "%zu:", dfle_channel_size(ch));
        dfle_lua_text_str(L, &t, buf);
        text_hex(L, &t, fnv(fnv(FNV0, dfle_channel_A(ch), dfle_channel_size(ch) * sizeof(double)),
                            dfle_channel_w(ch), dfle_channel_size(ch) * sizeof(double)));
    }
    dfle_lua_text_str(L, &t, " run=");
    {
        int run;
        lua_getfield(L, ctx, "run");
        run = lua_gettop(L);
        /* the run options, in a fixed order */
        static const char *const ro[] = {"method", "tol", "max_time", "max_steps", "direct_tol",
                                         NULL};
        for (int k = 0; ro[k] != NULL; k++) {
            if (lua_getfield(L, run, ro[k]) != LUA_TNIL) {
                dfle_lua_text_str(L, &t, ro[k]);
                dfle_lua_text_str(L, &t, ":");
                text_value(L, &t, -1);
                dfle_lua_text_str(L, &t, ",");
            }
            lua_pop(L, 1);
        }
        lua_pop(L, 1);
    }
    dfle_lua_text_str(L, &t, " build=");
    /* The build function's byte code (stripped: comments and line numbers
     * do not count); its upvalues' values are not seen. */
    lua_getglobal(L, "string");
    if (lua_istable(L, -1) && lua_getfield(L, -1, "dump") == LUA_TFUNCTION) {
        lua_getfield(L, ctx, "build");
        lua_pushboolean(L, 1);
        if (lua_pcall(L, 2, 1, 0) == LUA_OK && lua_type(L, -1) == LUA_TSTRING) {
            size_t len;
            const char *code = lua_tolstring(L, -1, &len);
            uint64_t hb = fnv(FNV0, code, len);
            lua_pop(L, 2);
            text_hex(L, &t, hb);
        } else {
            lua_pop(L, 2);
            dfle_lua_text_str(L, &t, "C");
        }
    } else {
        lua_pop(L, 2);
        dfle_lua_text_str(L, &t, "?");
    }
    dfle_lua_text_finish(L, &t);
    lua_setfield(L, ctx, "problem");
    lua_settop(L, names - 1);
}

/* The chain file's first lines, by the driver (which checks the
 * sampler's settings): ctx.meta, ctx.header, ctx.identity. */
static void push_identity(lua_State *L, int ctx, inv_run *R)
{
    dfle_error err;
    lua_getfield(L, ctx, "problem");
    R->o.identity = lua_tostring(L, -1); /* held by ctx */
    lua_pop(L, 1);
    /* the texts are the box's until freed (its __gc frees them if a push
     * raises) */
    if (dfle_invert_identity(&R->o, &R->text[0], &R->text[1], &err) != DFLE_OK)
        dfle_lua_raise(L, &err);
    lua_pushstring(L, R->text[0]);
    lua_setfield(L, ctx, "meta");
    lua_pushstring(L, R->text[1]);
    lua_setfield(L, ctx, "header");
    lua_pushfstring(L, "%s\n%s", R->text[0], R->text[1]);
    lua_setfield(L, ctx, "identity");
    free(R->text[0]);
    free(R->text[1]);
    R->text[0] = R->text[1] = NULL;
}

/* ------------------------------------------------------------------ */
/* The table.                                                          */

static const char *const spec_keys[] = {"data",  "build", "params",        "fixed",
                                        "sigma", "channel", "run",        "lsq",
                                        "out",   "resume", "move_stranded", "units", NULL};

/* The units of the chain's parameter columns: `units = { name = "unit" }`,
 * else the ones dfle knows (U in m/yr, gamma, sigma dimensionless, ...).
 * Held by ctx.c_units (the strings by ctx.units). */
static void read_units(lua_State *L, int arg, int ctx, inv_run *R)
{
    const char **u = lua_newuserdatauv(L, R->d * sizeof *u, 0);
    int given;
    lua_setfield(L, ctx, "c_units");
    lua_newtable(L);
    given = lua_gettop(L);
    if (lua_getfield(L, arg, "units") != LUA_TNIL) {
        if (!lua_istable(L, -1))
            luaL_error(L, "dfle.invert: parameter 'units' must be a table { name = \"unit\" }, "
                          "got %s", luaL_typename(L, -1));
        lua_pushnil(L);
        while (lua_next(L, -2) != 0) {
            if (lua_type(L, -2) != LUA_TSTRING || lua_type(L, -1) != LUA_TSTRING)
                luaL_error(L, "dfle.invert: 'units' maps parameter names to unit texts");
            dfle_lua_check_string(L, -1, "invert", "a unit");
            lua_pushvalue(L, -2);
            lua_insert(L, -2);
            lua_rawset(L, given);
        }
    }
    lua_pop(L, 1);
    lua_getfield(L, ctx, "names");
    for (size_t j = 0; j < R->d; j++) {
        const char *name;
        lua_geti(L, -1, (lua_Integer)j + 1);
        name = lua_tostring(L, -1);
        if (lua_getfield(L, given, name) == LUA_TSTRING)
            u[j] = lua_tostring(L, -1); /* held by ctx.units */
        else
            u[j] = dfle_lua_known_unit(name);
        lua_pop(L, 2);
    }
    lua_pop(L, 1);
    lua_setfield(L, ctx, "units");
    R->o.units = u;
}

void inv_read_spec(lua_State *L, int arg, inv_run **box)
{
    double nbins = DEFAULT_NBINS, walkers = 0, steps = DEFAULT_STEPS, burn = -1, seed = 1,
           a = 2, workers = 0;
    const dfle_lua_param nums[] = {{"nbins", &nbins}, {"walkers", &walkers}, {"steps", &steps},
                                   {"burn", &burn},   {"seed", &seed},       {"a", &a},
                                   {"workers", &workers}};
    int ctx, params, names, density, fixed, dem;
    size_t np = 0;
    inv_run *R;
    const char **sorted;

    arg = lua_absindex(L, arg);
    luaL_checktype(L, arg, LUA_TTABLE);
    dfle_lua_read_params(L, arg, "invert", nums, sizeof nums / sizeof nums[0], spec_keys);
    lua_newtable(L);
    ctx = lua_gettop(L);
    inv_push_box(L);
    R = lua_touserdata(L, -1);
    lua_setfield(L, ctx, "box");
    *box = R;

    if (lua_getfield(L, arg, "build") != LUA_TFUNCTION)
        luaL_error(L, "dfle.invert: parameter 'build' must be a function(p, channel) returning "
                      "a dfle.model, got %s", luaL_typename(L, -1));
    lua_setfield(L, ctx, "build");

    /* Free parameters, sorted by name: a table has no order. */
    if (lua_getfield(L, arg, "params") != LUA_TTABLE)
        luaL_error(L, "dfle.invert: parameter 'params' must be a table of priors, e.g. { U = "
                      "{1e-4, 1e-3, log = true} }, got %s", luaL_typename(L, -1));
    params = lua_gettop(L);
    lua_pushnil(L);
    while (lua_next(L, params) != 0) {
        if (lua_type(L, -2) != LUA_TSTRING)
            luaL_error(L, "dfle.invert: 'params' is keyed by parameter name; got a %s key",
                       luaL_typename(L, -2));
        check_name(L, "parameter", lua_tostring(L, -2));
        np++;
        lua_pop(L, 1);
    }
    if (np == 0)
        luaL_error(L, "dfle.invert: 'params' is empty: name at least one parameter to infer");
    sorted = lua_newuserdatauv(L, np * sizeof *sorted, 0);
    np = 0;
    lua_pushnil(L);
    while (lua_next(L, params) != 0) {
        lua_pop(L, 1);
        sorted[np++] = lua_tostring(L, -1); /* the key stays in params */
    }
    qsort(sorted, np, sizeof *sorted, cmp_str);
    lua_getfield(L, arg, "sigma");
    R->sigma_free = !(lua_type(L, -1) == LUA_TNUMBER);
    R->nmodel = np;
    R->d = np + (size_t)R->sigma_free;
    R->prior = box_alloc(L, R->d, sizeof *R->prior);
    R->logs = box_alloc(L, R->d, sizeof *R->logs);
    R->custom = box_alloc(L, R->d, 1);
    lua_newtable(L);
    density = lua_gettop(L);
    lua_createtable(L, (int)R->d, 0);
    names = lua_gettop(L);
    for (size_t j = 0; j < np; j++) {
        lua_getfield(L, params, sorted[j]);
        read_prior(L, -1, sorted[j], density, &R->prior[j]);
        lua_pop(L, 1);
        lua_pushstring(L, sorted[j]);
        lua_rawseti(L, names, (lua_Integer)j + 1);
    }
    /* The noise scale: a number fixes it; else a prior, by default
     * log-uniform over [0.005, 2] in ln S. */
    if (!R->sigma_free) {
        R->sigma = lua_tonumber(L, names - 2);
        if (!(isfinite(R->sigma) && R->sigma > 0))
            luaL_error(L, "dfle.invert: sigma (the noise sd of ln S) must be > 0 (got %s)",
                       dfle_lua_number_text(L, R->sigma));
    } else {
        dfle_prior *p = &R->prior[np];
        if (lua_isnil(L, names - 2)) {
            memset(p, 0, sizeof *p);
            p->kind = DFLE_PRIOR_LOG_UNIFORM;
            p->lo = 0.005;
            p->hi = 2.0;
        } else {
            read_prior(L, names - 2, "sigma", density, p);
            if (!(p->lo >= 0))
                luaL_error(L, "dfle.invert: sigma is a standard deviation: its prior needs lo "
                              ">= 0");
        }
        lua_pushliteral(L, "sigma");
        lua_rawseti(L, names, (lua_Integer)R->d);
    }
    for (size_t j = 0; j < R->d; j++) {
        R->logs[j] = dfle_prior_log_scale(&R->prior[j]);
        R->custom[j] = R->prior[j].kind == DFLE_PRIOR_CUSTOM;
    }
    lua_pushvalue(L, names), lua_setfield(L, ctx, "names");
    lua_pushvalue(L, density), lua_setfield(L, ctx, "density");

    /* Fixed parameters: passed to build with the free ones. */
    lua_newtable(L);
    fixed = lua_gettop(L);
    if (lua_getfield(L, arg, "fixed") != LUA_TNIL) {
        if (!lua_istable(L, -1))
            luaL_error(L, "dfle.invert: parameter 'fixed' must be a table of values, got %s",
                       luaL_typename(L, -1));
        lua_pushnil(L);
        while (lua_next(L, -2) != 0) {
            int t = lua_type(L, -1);
            if (lua_type(L, -2) != LUA_TSTRING)
                luaL_error(L, "dfle.invert: 'fixed' is keyed by parameter name");
            check_name(L, "fixed parameter", lua_tostring(L, -2));
            if (t != LUA_TNUMBER && t != LUA_TSTRING && t != LUA_TBOOLEAN)
                luaL_error(L, "dfle.invert: fixed parameter '%s' must be a number, string or "
                              "boolean, got %s (pass other values as upvalues of build)",
                           lua_tostring(L, -2), luaL_typename(L, -1));
            lua_getfield(L, params, lua_tostring(L, -2));
            if (!lua_isnil(L, -1))
                luaL_error(L, "dfle.invert: '%s' is both a free and a fixed parameter",
                           lua_tostring(L, -3));
            lua_pop(L, 1);
            lua_pushvalue(L, -2);
            lua_insert(L, -2);
            lua_rawset(L, fixed);
        }
    }
    lua_pop(L, 1);
    lua_pushvalue(L, fixed), lua_setfield(L, ctx, "fixed");

    /* run_to_steady options, without a progress bar. */
    lua_newtable(L);
    if (lua_getfield(L, arg, "run") != LUA_TNIL) {
        if (!lua_istable(L, -1))
            luaL_error(L, "dfle.invert: parameter 'run' must be a table of options for "
                          "m:run_to_steady, got %s", luaL_typename(L, -1));
        dfle_lua_copy_table(L, -1, -2);
    }
    lua_pop(L, 1);
    lua_pushboolean(L, 0), lua_setfield(L, -2, "progress");
    lua_setfield(L, ctx, "run");

    /* Data, then the channel on its A(x). */
    {
        int given = 0;
        lua_getfield(L, arg, "nbins");
        given = !lua_isnil(L, -1);
        lua_pop(L, 1);
        dfle_lua_check_whole(L, nbins, "invert", "nbins", 2, 1e6);
        dem = inv_read_data(L, arg, R, (size_t)nbins, given);
    }
    {
        int data = lua_gettop(L), t = lua_getfield(L, arg, "channel");
        size_t dropped = 0;
        if (t == LUA_TBOOLEAN && !lua_toboolean(L, -1)) {
            lua_pop(L, 1);
            lua_pushnil(L);
        } else if (luaL_testudata(L, -1, DFLE_LUA_CHANNEL) != NULL) {
            /* the user's own geometry */
        } else if (t == LUA_TNIL || t == LUA_TTABLE) {
            if (!dem) {
                if (t == LUA_TTABLE)
                    luaL_error(L, "dfle.invert: a channel from options {dx = ...} follows a DEM "
                                  "profile's A(x); for binned data give a dfle.channel or none");
            } else {
                /* p:main_stem():channel(options), default dx = 5 m */
                int opts = lua_gettop(L);
                lua_getfield(L, arg, "data");
                lua_getfield(L, -1, "main_stem");
                lua_insert(L, -2);
                call_method(L, 1, "the data's main stem");
                lua_getfield(L, -1, "channel");
                lua_insert(L, -2);
                if (t == LUA_TNIL) {
                    lua_newtable(L);
                } else {
                    lua_pushvalue(L, opts);
                }
                call_method(L, 2, "the data's channel");
                lua_remove(L, opts);
            }
        } else {
            luaL_error(L, "dfle.invert: parameter 'channel' must be a dfle.channel, options for "
                          "the data's channel {dx =, k_w =, b =}, or false, got %s",
                       dfle_lua_typename(L, -1));
        }
        if (!lua_isnil(L, -1))
            dropped = inv_clip_to_channel(R, dfle_lua_check_channel(L, -1));
        lua_setfield(L, ctx, "channel");
        lua_pushinteger(L, (lua_Integer)dropped);
        lua_setfield(L, data, "outside");
        /* the binned data as used, for results and plots */
        {
            double *S = lua_newuserdatauv(L, (R->nobs ? R->nobs : 1) * sizeof *S, 0);
            for (size_t i = 0; i < R->nobs; i++)
                S[i] = exp(R->lnS_obs[i]);
            dfle_lua_push_array(L, R->A_obs, R->nobs);
            lua_setfield(L, data, "A");
            dfle_lua_push_array(L, S, R->nobs);
            lua_setfield(L, data, "S");
            lua_pop(L, 1);
        }
        lua_setfield(L, ctx, "data");
    }
    if (R->nobs < R->nmodel + 2 || R->nobs < 3)
        luaL_error(L, "dfle.invert: %d data bins%s for %d free parameters: too few to infer "
                      "them (use more bins, or fix parameters)", (int)R->nobs,
                   R->nobs == 0 ? " (none inside the channel's areas)" : "", (int)R->nmodel);

    /* Sampler settings, read here, checked by the driver (below). */
    dfle_invert_opts_default(&R->o);
    R->o.d = R->d;
    R->o.priors = R->prior;
    {
        const char **nm = lua_newuserdatauv(L, R->d * sizeof *nm, 0);
        lua_getfield(L, ctx, "names");
        for (size_t j = 0; j < R->d; j++) {
            lua_geti(L, -1, (lua_Integer)j + 1);
            nm[j] = lua_tostring(L, -1); /* held by ctx.names */
            lua_pop(L, 1);
        }
        lua_pop(L, 1);
        lua_setfield(L, ctx, "c_names");
        R->o.names = R->names = nm;
    }
    R->o.steps = (size_t)dfle_lua_check_whole(L, steps, "invert", "steps", 0, 1e7);
    if (burn >= 0)
        R->o.burn = (size_t)dfle_lua_check_whole(L, burn, "invert", "burn", 0, 1e7);
    if (walkers != 0)
        R->o.walkers = (size_t)dfle_lua_check_whole(L, walkers, "invert", "walkers", 4, 1e5);
    R->o.seed = (unsigned long)dfle_lua_check_whole(L, seed, "invert", "seed", 0, 4294967295.0);
    R->o.a = a;
    R->o.workers = (int)dfle_lua_check_whole(L, workers, "invert", "workers", 0, 4096);
    R->lsq = 1;
    for (int k = 0; k < 3; k++) {
        static const char *const keys[] = {"lsq", "resume", "move_stranded"};
        int *flag = k == 0 ? &R->lsq : k == 1 ? &R->o.resume : &R->o.move_stranded;
        if (lua_getfield(L, arg, keys[k]) != LUA_TNIL) {
            if (!lua_isboolean(L, -1))
                luaL_error(L, "dfle.invert: parameter '%s' must be a boolean, got %s", keys[k],
                           luaL_typename(L, -1));
            *flag = lua_toboolean(L, -1);
        }
        lua_pop(L, 1);
    }
    if (lua_getfield(L, arg, "out") != LUA_TNIL) {
        if (lua_type(L, -1) != LUA_TSTRING)
            luaL_error(L, "dfle.invert: parameter 'out' (the chain's CSV file) must be a file "
                          "name, got %s", luaL_typename(L, -1));
        dfle_lua_check_string(L, -1, "invert", "parameter 'out'");
    }
    R->o.out = lua_tostring(L, -1); /* held by ctx */
    lua_setfield(L, ctx, "out");
    read_units(L, arg, ctx, R);

    push_problem(L, ctx, R);
    push_identity(L, ctx, R);
    lua_settop(L, ctx);
}
