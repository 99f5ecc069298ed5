/*
 * lua_population.c - dfle.router.population{...}: debris flows as a
 * population (router_population.h).
 *
 *   dfle.router.population{
 *       router = dfle.router.empirical{...},  -- the characteristic flow
 *       volume = {kind = "lognormal", sigma = 1, median = 1},
 *       frequency = 2,                         -- events per year (1)
 *       order = 8,                             -- quadrature order (8)
 *       mu = {...}, tau_y = {...},             -- factors on mu, tau_y (fixed)
 *       mobility_order = 8,                    -- their quadrature order (8)
 *   }
 *
 * volume kinds: "lognormal" (sigma, median), "power_law" (b, f_min,
 * f_max), "uniform" (f_min, f_max), "table" (values, weights) and
 * "sampler" (sample = function(k) -> factor, called `order` times: the
 * population is then those draws with equal weights).  The result is a
 * dfle.router like any other.
 */
#include "lua/core/dfle_lua.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dfle/model_events.h"
#include "dfle/router_population.h"
#include "lua/objects/lua_events.h"

#define FN "router.population"

/* A Lua array of n numbers at idx, checked, into a scratch userdata. */
static double *numbers(lua_State *L, int idx, const char *what, size_t *n)
{
    return dfle_lua_check_array(L, idx, what, n);
}

/* The distribution `what` ("volume", "mu", "tau_y") at idx into d
 * (arrays in userdata left on the stack). */
static void read_dist(lua_State *L, int idx, dfle_dist *d, double order, const char *what)
{
    static const char *const kinds[] = {"lognormal", "power_law", "uniform", "table", "sampler",
                                        NULL};
    static const char *const keys_ln[] = {"kind", NULL};
    static const char *const keys_table[] = {"kind", "values", "weights", NULL};
    static const char *const keys_sampler[] = {"kind", "sample", NULL};
    char where[64];
    int kind;

    snprintf(where, sizeof where, FN ": %s", what);
    idx = lua_absindex(L, idx);
    if (!lua_istable(L, idx))
        luaL_error(L, "dfle." FN ": parameter '%s' must be a table {kind = ...}, got %s", what,
                   dfle_lua_typename(L, idx));
    lua_getfield(L, idx, "kind");
    if (lua_isnil(L, -1))
        luaL_error(L, "dfle." FN ": %s needs a kind ('lognormal', 'power_law', 'uniform', "
                      "'table' or 'sampler')", what);
    lua_pushfstring(L, "%s kind", what);
    kind = dfle_lua_check_option(L, -2, FN, lua_tostring(L, -1), kinds);
    lua_pop(L, 1);
    lua_pop(L, 1);
    memset(d, 0, sizeof *d);
    d->median = 1.0;
    if (kind == DFLE_DIST_LOGNORMAL) {
        const dfle_lua_param p[] = {{"sigma", &d->sigma}, {"median", &d->median}};
        d->kind = kind;
        d->sigma = NAN;
        dfle_lua_read_params(L, idx, where, p, 2, keys_ln);
        if (isnan(d->sigma))
            luaL_error(L, "dfle." FN ": a lognormal %s needs sigma (the spread of ln f)", what);
    } else if (kind == DFLE_DIST_POWER_LAW || kind == DFLE_DIST_UNIFORM) {
        const dfle_lua_param p[] = {{"f_min", &d->f_min}, {"f_max", &d->f_max}, {"b", &d->b}};
        d->kind = kind;
        d->f_min = d->f_max = d->b = NAN;
        dfle_lua_read_params(L, idx, where, p, kind == DFLE_DIST_POWER_LAW ? 3 : 2,
                             keys_ln);
        if (isnan(d->f_min) || isnan(d->f_max) || (kind == DFLE_DIST_POWER_LAW && isnan(d->b)))
            luaL_error(L, "dfle." FN ": a %s %s needs %s", kinds[kind], what,
                       kind == DFLE_DIST_POWER_LAW ? "b, f_min and f_max" : "f_min and f_max");
    } else if (kind == DFLE_DIST_TABLE) {
        size_t nv, nw;
        double *v, *w;
        dfle_lua_read_params(L, idx, where, NULL, 0, keys_table);
        lua_getfield(L, idx, "values");
        lua_pushfstring(L, FN ": %s.values", what);
        v = numbers(L, -2, lua_tostring(L, -1), &nv);
        lua_pop(L, 1);
        lua_getfield(L, idx, "weights");
        if (lua_isnil(L, -1)) { /* equal weights */
            lua_pop(L, 1);
            w = lua_newuserdatauv(L, (nv > 0 ? nv : 1) * sizeof *w, 0);
            for (size_t i = 0; i < nv; i++)
                w[i] = 1.0;
            nw = nv;
        } else {
            lua_pushfstring(L, FN ": %s.weights", what);
            w = numbers(L, -2, lua_tostring(L, -1), &nw);
            lua_pop(L, 1);
        }
        if (nw != nv)
            luaL_error(L, "dfle." FN ": %s.values has %d entries, %s.weights %d", what, (int)nv,
                       what, (int)nw);
        d->kind = DFLE_DIST_TABLE;
        d->n = nv, d->values = v, d->weights = w;
    } else { /* sampler: `order` draws of equal weight */
        lua_Integer q = dfle_lua_check_whole(L, order, FN, "order", 1, 64);
        double *v, *w;
        dfle_lua_read_params(L, idx, where, NULL, 0, keys_sampler);
        v = lua_newuserdatauv(L, 2 * (size_t)q * sizeof *v, 0);
        w = v + q;
        for (lua_Integer k = 1; k <= q; k++) {
            int isnum;
            if (lua_getfield(L, idx, "sample") != LUA_TFUNCTION)
                luaL_error(L, "dfle." FN ": a sampler %s needs sample = function(k) -> factor",
                           what);
            lua_pushinteger(L, k);
            lua_call(L, 1, 1);
            v[k - 1] = lua_tonumberx(L, -1, &isnum);
            if (!isnum)
                luaL_error(L, "dfle." FN ": %s.sample(%d) must return a number, got %s", what,
                           (int)k, dfle_lua_typename(L, -1));
            lua_pop(L, 1);
            w[k - 1] = 1.0;
        }
        d->kind = DFLE_DIST_TABLE;
        d->n = (size_t)q, d->values = v, d->weights = w;
    }
}

static int l_router_population(lua_State *L)
{
    static const char *const other[] = {"router", "volume", "mu", "tau_y", NULL};
    dfle_population_opts o;
    double order, mobility_order;
    dfle_router *base;
    dfle_lua_router *u;
    dfle_error err;
    const dfle_lua_param params[] = {{"frequency", &o.frequency}, {"order", &order},
                                     {"mobility_order", &mobility_order}};

    dfle_population_opts_default(&o);
    order = (double)o.order;
    mobility_order = (double)o.mobility_order;
    luaL_checktype(L, 1, LUA_TTABLE);
    dfle_lua_read_params(L, 1, FN, params, 3, other);
    o.order = (size_t)dfle_lua_check_whole(L, order, FN, "order", 1, 64);
    o.mobility_order = (size_t)dfle_lua_check_whole(L, mobility_order, FN, "mobility_order", 1, 64);
    if (lua_getfield(L, 1, "router") == LUA_TNIL)
        luaL_error(L, "dfle." FN ": parameter 'router' is required (the characteristic flow's "
                      "dfle.router.empirical{...})");
    base = dfle_lua_check_router(L, lua_gettop(L));
    if (lua_getfield(L, 1, "volume") == LUA_TNIL)
        luaL_error(L, "dfle." FN ": parameter 'volume' is required ({kind = 'lognormal', "
                      "sigma = ...}, ...)");
    read_dist(L, -1, &o.volume, order, "volume");
    /* Mobility: factors on the router's mu and tau_y (absent: fixed). */
    if (lua_getfield(L, 1, "mu") != LUA_TNIL)
        read_dist(L, -1, &o.mu, mobility_order, "mu");
    if (lua_getfield(L, 1, "tau_y") != LUA_TNIL)
        read_dist(L, -1, &o.tau_y, mobility_order, "tau_y");
    u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_ROUTER, 0);
    if (dfle_router_new_population(base, &o, &u->rt, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

/* rt:quadrature(): the population's flows, {f = {...}, rate = {...},
 * mu = {...}, tau_y = {...}} (the last two: factors). */
static int l_population_quadrature(lua_State *L)
{
    const dfle_population *p = dfle_router_get_population(dfle_lua_check_router(L, 1));
    size_t q;
    if (p == NULL)
        luaL_error(L, "dfle.router:quadrature: not a population (dfle.router.population{...})");
    q = dfle_population_size(p);
    lua_createtable(L, 0, 3);
    lua_createtable(L, (int)q, 0);
    for (size_t j = 0; j < q; j++)
        lua_pushnumber(L, dfle_population_factor(p, j)), lua_rawseti(L, -2, (lua_Integer)j + 1);
    lua_setfield(L, -2, "f");
    lua_createtable(L, (int)q, 0);
    for (size_t j = 0; j < q; j++)
        lua_pushnumber(L, dfle_population_rate(p, j)), lua_rawseti(L, -2, (lua_Integer)j + 1);
    lua_setfield(L, -2, "rate");
    lua_createtable(L, (int)q, 0);
    for (size_t j = 0; j < q; j++)
        lua_pushnumber(L, dfle_population_mu_factor(p, j)), lua_rawseti(L, -2, (lua_Integer)j + 1);
    lua_setfield(L, -2, "mu");
    lua_createtable(L, (int)q, 0);
    for (size_t j = 0; j < q; j++)
        lua_pushnumber(L, dfle_population_tau_y_factor(p, j)),
            lua_rawseti(L, -2, (lua_Integer)j + 1);
    lua_setfield(L, -2, "tau_y");
    lua_pushnumber(L, dfle_population_frequency(p)), lua_setfield(L, -2, "frequency");
    return 1;
}

/* dfle.population_moment(volume, k): E[f^k] of a volume distribution
 * in closed form (a table: its weighted sum). */
static int l_population_moment(lua_State *L)
{
    dfle_dist d;
    dfle_error err;
    double k = luaL_checknumber(L, 2);
    read_dist(L, 1, &d, 8, "volume");
    if (dfle_dist_check(&d, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    lua_pushnumber(L, dfle_dist_moment(&d, k));
    return 1;
}

void dfle_lua_open_router_population(lua_State *L)
{
    /* The router table is on the top of the stack. */
    lua_pushcfunction(L, l_router_population);
    lua_setfield(L, -2, "population");
    lua_pushcfunction(L, l_population_moment);
    lua_setfield(L, -2, "moment");
    lua_pushcfunction(L, l_population_quadrature);
    lua_setfield(L, -2, "quadrature");
}

void dfle_lua_read_events_opts(lua_State *L, int idx, const char *fn, int hold_default,
                               dfle_events_opts *o)
{
    static const char *const other[] = {"hold", NULL};
    double seed = 1;
    const dfle_lua_param params[] = {{"years", &o->years}, {"dt", &o->dt}, {"seed", &seed}};

    *o = (dfle_events_opts){.years = NAN, .dt = 1.0, .seed = 1, .hold = hold_default};
    luaL_checktype(L, idx, LUA_TTABLE);
    dfle_lua_read_params(L, idx, fn, params, 3, other);
    if (isnan(o->years))
        luaL_error(L, "dfle.%s: parameter 'years' is required", fn);
    o->seed = (unsigned long)dfle_lua_check_whole(L, seed, fn, "seed", 0, 4294967295.0);
    if (lua_getfield(L, idx, "hold") != LUA_TNIL) {
        if (!lua_isboolean(L, -1))
            luaL_error(L, "dfle.%s: parameter 'hold' must be a boolean, got %s", fn,
                       dfle_lua_typename(L, -1));
        o->hold = lua_toboolean(L, -1);
    }
    lua_pop(L, 1);
}

void dfle_lua_push_events_result(lua_State *L, const dfle_events_result *res, const double *sum,
                                 const double *sum2, size_t n)
{
    lua_createtable(L, 0, 5);
    lua_pushinteger(L, (lua_Integer)res->events), lua_setfield(L, -2, "events");
    lua_pushinteger(L, (lua_Integer)res->steps), lua_setfield(L, -2, "steps");
    lua_pushnumber(L, res->years), lua_setfield(L, -2, "years");
    lua_createtable(L, (int)n, 0);
    for (size_t i = 0; i < n; i++)
        lua_pushnumber(L, sum[i] / res->years), lua_rawseti(L, -2, (lua_Integer)i + 1);
    lua_setfield(L, -2, "mean");
    lua_createtable(L, (int)n, 0);
    for (size_t i = 0; i < n; i++)
        lua_pushnumber(L, sqrt(sum2[i]) / res->years), lua_rawseti(L, -2, (lua_Integer)i + 1);
    lua_setfield(L, -2, "se");
}

/* m:run_events{years =, dt =, seed =, hold = false}: debris flows of
 * the model's population as events in time (model_events.h).  Returns
 * {events, steps, years, mean = {rate per node [m/yr]}, se = {its
 * standard error}}. */
int dfle_lua_model_run_events(lua_State *L)
{
    dfle_model *m = dfle_lua_check_model(L, 1);
    const size_t n = dfle_model_size(m);
    dfle_events_opts o;
    dfle_events_result res;
    dfle_error err;
    double *sum;
    int st;

    dfle_lua_read_events_opts(L, 2, "model:run_events", 0, &o);
    sum = lua_newuserdatauv(L, 2 * n * sizeof *sum, 0);
    dfle_lua_begin_use(L, 1, "dfle.model:run_events");
    st = dfle_run_events(m, &o, &res, sum, sum + n, &err);
    dfle_lua_end_use(L, 1);
    if (st != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_push_events_result(L, &res, sum, sum + n, n);
    return 1;
}
