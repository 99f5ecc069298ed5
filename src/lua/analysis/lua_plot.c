/*
 * lua_plot.c - dfle.plot.*: figures through gnuplot (see plot.h).
 *
 *   dfle.plot.slope_area(m, "slope_area.png" [, fit [, {title =, nbins =}]])
 *   dfle.plot.profile(m, "profile.png" [, {title =}])
 *   dfle.plot.xy{ path =, series = {{x =, y =, label =, lines =, lo =, hi =,
 *                                     rgb =, dash =}, ...},
 *                 title =, xlabel =, ylabel =, logx =, logy = }
 */
#include "lua/core/dfle_lua.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dfle/analysis.h"
#include "dfle/plot.h"

#define DEFAULT_NBINS 100

static int opt_bool(lua_State *L, int idx, const char *key, const char *fn)
{
    int v = 0;
    if (lua_istable(L, idx)) {
        int t = lua_getfield(L, idx, key);
        if (t != LUA_TNIL && t != LUA_TBOOLEAN)
            luaL_error(L, "dfle.%s: parameter '%s' must be a boolean, got %s", fn, key,
                       luaL_typename(L, -1));
        v = lua_toboolean(L, -1);
        lua_pop(L, 1);
    }
    return v;
}

static double fit_field(lua_State *L, int idx, const char *key)
{
    double v;
    if (lua_getfield(L, idx, key) != LUA_TNUMBER)
        luaL_error(L, "dfle.plot.slope_area: fit table lacks number '%s'", key);
    v = lua_tonumber(L, -1);
    lua_pop(L, 1);
    return v;
}

/* The options table at idx: absent, or a table of known keys. */
static void check_opts(lua_State *L, int idx, const char *fn, const dfle_lua_param *params,
                       size_t np)
{
    static const char *const title[] = {"title", NULL};
    if (!lua_isnoneornil(L, idx) && !lua_istable(L, idx))
        luaL_error(L, "dfle.%s: options must be a table, got %s", fn, dfle_lua_typename(L, idx));
    dfle_lua_read_params(L, idx, fn, params, np, title);
}

static int l_plot_slope_area(lua_State *L)
{
    const double *A = NULL, *S = NULL;
    const char *path, *title;
    double nbins = DEFAULT_NBINS;
    const dfle_lua_param params[] = {{"nbins", &nbins}};
    dfle_eq2_fit fit, *fitp = NULL;
    dfle_bins bins;
    dfle_error err;
    size_t n;
    int st;

    lua_settop(L, 4); /* scratch arrays go above the arguments */
    path = dfle_lua_check_string(L, 2, "plot.slope_area", "the path");
    check_opts(L, 4, "plot.slope_area", params, 1);
    title = dfle_lua_opt_string(L, 4, "title", "plot.slope_area");
    dfle_lua_check_whole(L, nbins, "plot.slope_area", "nbins", 1, 1e6);
    memset(&fit, 0, sizeof fit);
    if (lua_istable(L, 3)) {
        fit.S_df = fit_field(L, 3, "S_df");
        fit.A_df = fit_field(L, 3, "A_df");
        fit.a2 = fit_field(L, 3, "a2");
        fit.r2 = fit_field(L, 3, "r2");
        fitp = &fit;
    } else if (!lua_isnil(L, 3) && !(lua_isboolean(L, 3) && !lua_toboolean(L, 3))) {
        luaL_argerror(L, 3, "expected a fit table from dfle.fit_slope_area, nil or false");
    }
    n = dfle_lua_slope_area(L, 1, "plot.slope_area", &A, &S);
    memset(&bins, 0, sizeof bins);
    st = dfle_bins_compute(n, A, S, (size_t)nbins, &bins, &err);
    if (st != DFLE_OK)
        return luaL_error(L, "dfle.plot.slope_area: %s", err.msg);
    /* No fit given: fit now; a fit that fails just leaves the curve out. */
    if (fitp == NULL && lua_isnil(L, 3)) {
        dfle_error fit_err;
        if (dfle_slope_area_fit(n, A, S, (size_t)nbins, NULL, &fit, &fit_err) == DFLE_OK)
            fitp = &fit;
    }
    st = dfle_plot_slope_area(path, title, n, A, S, &bins, fitp, &err);
    dfle_bins_release(&bins);
    if (st != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path); /* for run records */
    return 0;
}

static int l_plot_profile(lua_State *L)
{
    dfle_model *m = dfle_lua_check_model(L, 1);
    const char *path = dfle_lua_check_string(L, 2, "plot.profile", "the path");
    const char *title;
    const double *x, *z, *S;
    dfle_error err;

    check_opts(L, 3, "plot.profile", NULL, 0);
    title = dfle_lua_opt_string(L, 3, "title", "plot.profile");
    x = dfle_lua_model_field(L, 1, DFLE_FIELD_X, "dfle.plot.profile");
    z = dfle_lua_model_field(L, 1, DFLE_FIELD_Z, "dfle.plot.profile");
    S = dfle_lua_model_field(L, 1, DFLE_FIELD_S, "dfle.plot.profile");
    if (dfle_plot_profile(path, title, dfle_model_size(m), x, z, S, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path); /* for run records */
    return 0;
}

/* dfle.plot.flow(m, route_result, path [, {exaggeration = 50, title =}]):
 * the bed and the flow surface z + e h at each snapshot of a routing,
 * like the paper's Fig. E1 (depth exaggerated so it shows at all). */
static int l_plot_flow(lua_State *L)
{
    dfle_model *m = dfle_lua_check_model(L, 1);
    const char *path = dfle_lua_check_string(L, 3, "plot.flow", "the path");
    double e = 50.0;
    const dfle_lua_param params[] = {{"exaggeration", &e}};
    const size_t n = dfle_model_size(m);
    const double *x, *z;
    dfle_plot_series *series;
    dfle_plot_opts o;
    char *labels;
    size_t ns, k = 0;
    dfle_error err;

    luaL_checktype(L, 2, LUA_TTABLE);
    lua_settop(L, 4);
    check_opts(L, 4, "plot.flow", params, 1);
    if (!(e > 0))
        luaL_error(L, "dfle.plot.flow: exaggeration must be > 0 (got %s)", dfle_lua_number_text(L, e));
    x = dfle_lua_model_field(L, 1, DFLE_FIELD_X, "dfle.plot.flow");
    z = dfle_lua_model_field(L, 1, DFLE_FIELD_Z, "dfle.plot.flow");
    if (lua_getfield(L, 2, "snapshots") != LUA_TTABLE || lua_rawlen(L, -1) == 0)
        luaL_error(L, "dfle.plot.flow: the routing has no snapshots; route with "
                      "rt:route(m, {snapshots = {t1, t2, ...}})");
    ns = lua_rawlen(L, 5);
    series = lua_newuserdatauv(L, (ns + 1) * sizeof *series, 0);
    labels = lua_newuserdatauv(L, (ns + 1) * 48, 0);
    memset(&o, 0, sizeof o);
    o.title = dfle_lua_opt_string(L, 4, "title", "plot.flow");
    o.xlabel = "Distance from channel head, x (m)";
    o.ylabel = "Elevation (m)";
    series[k++] = (dfle_plot_series){.label = "bed", .n = n, .x = x, .y = z, .lines = 1};
    for (size_t j = 1; j <= ns; j++) {
        size_t nh;
        double t, *surf;
        luaL_checkstack(L, 4, "too many snapshots");
        lua_rawgeti(L, 5, (lua_Integer)j);
        if (!lua_istable(L, -1) || lua_getfield(L, -1, "t") != LUA_TNUMBER)
            luaL_error(L, "dfle.plot.flow: snapshot %d lacks its time t", (int)j);
        t = lua_tonumber(L, -1);
        lua_pop(L, 1);
        if (isnan(t)) { /* the flow ended before this time */
            lua_pop(L, 1);
            continue;
        }
        lua_getfield(L, -1, "h");
        surf = dfle_lua_check_array(L, -1, "plot.flow: snapshot h", &nh);
        if (nh != n)
            luaL_error(L, "dfle.plot.flow: snapshot %d has %d depths, the model %d nodes", (int)j,
                       (int)nh, (int)n);
        for (size_t i = 0; i < n; i++)
            surf[i] = z[i] + e * surf[i];
        snprintf(labels + k * 48, 48, "t = %.4g s", t);
        series[k] = (dfle_plot_series){.label = labels + k * 48, .n = n, .x = x, .y = surf, .lines = 1};
        k++;
        /* leave the arrays on the stack: they back the series */
    }
    if (dfle_plot_xy(path, &o, series, k, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path); /* for run records */
    return 0;
}

/* dfle.plot.xy{path =, series = {...}, ...}: any curves, e.g. several
 * models' slope-area data on one figure. */
static int l_plot_xy(lua_State *L)
{
    static const char *const keys[] = {"path", "series", "title", "xlabel", "ylabel",
                                       "logx", "logy", "clabel", "logc", NULL};
    static const char *const series_keys[] = {"x", "y", "label", "lines", "color", "lo", "hi",
                                              "rgb", "dash", NULL};
    dfle_plot_opts o;
    dfle_plot_series *series;
    const char *path;
    size_t ns;
    int list;
    dfle_error err;

    luaL_checktype(L, 1, LUA_TTABLE);
    dfle_lua_read_params(L, 1, "plot.xy", NULL, 0, keys);
    path = dfle_lua_opt_string(L, 1, "path", "plot.xy");
    if (path == NULL)
        luaL_error(L, "dfle.plot.xy: parameter 'path' is required");
    memset(&o, 0, sizeof o);
    o.title = dfle_lua_opt_string(L, 1, "title", "plot.xy");
    o.xlabel = dfle_lua_opt_string(L, 1, "xlabel", "plot.xy");
    o.ylabel = dfle_lua_opt_string(L, 1, "ylabel", "plot.xy");
    o.logx = opt_bool(L, 1, "logx", "plot.xy");
    o.logy = opt_bool(L, 1, "logy", "plot.xy");
    o.clabel = dfle_lua_opt_string(L, 1, "clabel", "plot.xy");
    o.logc = opt_bool(L, 1, "logc", "plot.xy");
    if (lua_getfield(L, 1, "series") != LUA_TTABLE)
        luaL_error(L, "dfle.plot.xy: parameter 'series' must be an array of {x =, y =}");
    list = lua_gettop(L);
    ns = lua_rawlen(L, -1);
    if (ns == 0)
        luaL_error(L, "dfle.plot.xy: 'series' is empty");
    series = lua_newuserdatauv(L, ns * sizeof *series, 0);
    for (size_t k = 0; k < ns; k++) {
        int s_idx;
        size_t ny;
        luaL_checkstack(L, 6, "too many plot series");
        lua_rawgeti(L, list, (lua_Integer)k + 1);
        s_idx = lua_gettop(L);
        if (!lua_istable(L, s_idx))
            luaL_error(L, "dfle.plot.xy: series[%d] must be a table", (int)k + 1);
        dfle_lua_read_params(L, s_idx, "plot.xy series", NULL, 0, series_keys);
        series[k].label = dfle_lua_opt_string(L, s_idx, "label", "plot.xy");
        series[k].lines = opt_bool(L, s_idx, "lines", "plot.xy");
        lua_getfield(L, s_idx, "x");
        series[k].x = dfle_lua_check_array(L, -1, "plot.xy: series.x", &series[k].n);
        series[k].lo = series[k].hi = NULL;
        series[k].rgb = dfle_lua_opt_string(L, s_idx, "rgb", "plot.xy");
        series[k].dash = opt_bool(L, s_idx, "dash", "plot.xy");
        if (lua_getfield(L, s_idx, "lo") != LUA_TNIL) {
            /* a band between lo and hi: y is not needed */
            size_t nl, nh;
            series[k].lo = dfle_lua_check_array(L, -1, "plot.xy: series.lo", &nl);
            lua_getfield(L, s_idx, "hi");
            series[k].hi = dfle_lua_check_array(L, -1, "plot.xy: series.hi", &nh);
            if (nl != series[k].n || nh != series[k].n)
                luaL_error(L, "dfle.plot.xy: series[%d] has %d x but %d lo and %d hi values",
                           (int)k + 1, (int)series[k].n, (int)nl, (int)nh);
        }
        if (series[k].lo == NULL || lua_getfield(L, s_idx, "y") != LUA_TNIL) {
            if (series[k].lo == NULL)
                lua_getfield(L, s_idx, "y");
            series[k].y = dfle_lua_check_array(L, -1, "plot.xy: series.y", &ny);
            if (ny != series[k].n)
                luaL_error(L, "dfle.plot.xy: series[%d] has %d x but %d y values", (int)k + 1,
                           (int)series[k].n, (int)ny);
        } else {
            series[k].y = NULL;
        }
        series[k].c = NULL;
        if (lua_getfield(L, s_idx, "color") != LUA_TNIL) {
            size_t nc;
            /* a value per point, coloured on a continuous scale */
            series[k].c = dfle_lua_check_array(L, -1, "plot.xy: series.color", &nc);
            if (nc != series[k].n)
                luaL_error(L, "dfle.plot.xy: series[%d] has %d points but %d colour values",
                           (int)k + 1, (int)series[k].n, (int)nc);
        }
        /* The series table and its two scratch arrays stay on the stack,
         * which keeps them alive until the plot is written. */
    }
    if (dfle_plot_xy(path, &o, series, ns, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path); /* for run records */
    return 0;
}

void dfle_lua_open_plot(lua_State *L)
{
    static const luaL_Reg funcs[] = {
        {"slope_area", l_plot_slope_area},
        {"profile", l_plot_profile},
        {"flow", l_plot_flow},
        {"xy", l_plot_xy},
        {NULL, NULL}};
    lua_newtable(L);
    luaL_setfuncs(L, funcs, 0);
    lua_setfield(L, -2, "plot");
}
