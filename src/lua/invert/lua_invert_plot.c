/*
 * lua_invert_plot.c - the two figures of an inversion, through the plot
 * machinery of src/io:
 *
 *   dfle.plot.corner(res, "corner.png" [, {params =, labels =, truth =, scale =, <page options>}])
 *   dfle.plot.posterior_predictive(res, "pp.png" [, {n =, truth =, raw =, <options>}])
 *
 * The corner plot shows the posterior's marginals and every pair (the
 * trade-offs); the posterior-predictive plot shows whether the model, at
 * parameters the data allow, reproduces the data: bands of the model's
 * slope-area curve over the binned data (and the raw slopes of a DEM).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "lua/invert/lua_invert_internal.h"

#include "dfle/plot.h"

/* The arguments (res, path [, opts]) of both figures: the result's
 * context index; *path the image; *o the shared options (`which` of
 * them), nums and keys the figure's own. */
static int plot_args(lua_State *L, const char *fn, unsigned which, const dfle_lua_param *nums,
                     size_t nnums, const char *const *keys, const char **path, dfle_plot_opts *o)
{
    int ctx;
    lua_settop(L, 3);
    ctx = inv_result_ctx(L, 1);
    *path = dfle_lua_check_string(L, 2, fn, "the path");
    dfle_lua_plot_opts(L, 3, fn, which, nums, nnums, keys, o);
    return ctx;
}

/* dfle.plot.corner(res, path [, opts]) */
static int l_corner(lua_State *L)
{
    static const char *const keys[] = {"params", "labels", "truth", "scale", NULL};
    double nbins = 0;
    const dfle_lua_param nums[] = {{"nbins", &nbins}};
    const char *path, **labels;
    int ctx, names, sel, *logs;
    inv_run *R;
    size_t d, m, np;
    double *x, *truth, *blo, *bhi;
    dfle_corner_opts o;
    dfle_plot_opts po;
    dfle_error err;

    ctx = plot_args(L, "plot.corner", DFLE_LUA_PLOT_PAGE, nums, 1, keys, &path, &po);
    lua_getfield(L, ctx, "box");
    R = luaL_checkudata(L, -1, INV_BOX);
    lua_pop(L, 1);
    if (R->steps < 1 || R->have < R->steps + 1)
        return luaL_error(L, "dfle.plot.corner: the inversion has no posterior samples");
    lua_getfield(L, ctx, "names");
    names = lua_gettop(L);
    /* The parameters shown: `params`, or every free one but sigma. */
    lua_newtable(L);
    sel = lua_gettop(L);
    np = 0;
    if (lua_istable(L, 3) && lua_getfield(L, 3, "params") != LUA_TNIL) {
        if (!lua_istable(L, -1))
            return luaL_error(L, "dfle.plot.corner: 'params' must be an array of names");
        for (lua_Integer k = 1, n = (lua_Integer)lua_rawlen(L, -1); k <= n; k++) {
            size_t j;
            lua_geti(L, -1, k);
            for (j = 0; j < R->d; j++) {
                lua_geti(L, names, (lua_Integer)j + 1);
                if (lua_rawequal(L, -1, -2)) {
                    lua_pop(L, 1);
                    break;
                }
                lua_pop(L, 1);
            }
            if (j == R->d)
                return luaL_error(L, "dfle.plot.corner: '%s' is not a parameter of the inversion",
                                  luaL_tolstring(L, -1, NULL));
            lua_pop(L, 1);
            lua_pushinteger(L, (lua_Integer)j);
            lua_rawseti(L, sel, (lua_Integer)++np);
        }
        lua_pop(L, 1);
    } else {
        if (lua_istable(L, 3))
            lua_pop(L, 1);
        for (size_t j = 0; j < R->nmodel; j++) {
            lua_pushinteger(L, (lua_Integer)j);
            lua_rawseti(L, sel, (lua_Integer)++np);
        }
        if (np == 0) { /* sigma alone */
            lua_pushinteger(L, 0);
            lua_rawseti(L, sel, (lua_Integer)++np);
        }
    }
    if (np == 0)
        return luaL_error(L, "dfle.plot.corner: 'params' is empty");
    d = np;
    m = (R->steps - R->burn) * R->walkers;
    x = lua_newuserdatauv(L, (m * d + 3 * d) * sizeof *x, 0);
    truth = x + m * d;
    blo = truth + d;
    bhi = blo + d;
    logs = lua_newuserdatauv(L, d * sizeof *logs, 0);
    labels = lua_newuserdatauv(L, d * sizeof *labels, 0);
    for (size_t c = 0; c < d; c++) {
        size_t j;
        lua_geti(L, sel, (lua_Integer)c + 1);
        j = (size_t)lua_tointeger(L, -1);
        lua_pop(L, 1);
        double scale = 1;
        logs[c] = R->logs[j];
        truth[c] = NAN;
        lua_geti(L, names, (lua_Integer)j + 1);
        labels[c] = lua_tostring(L, -1); /* held by names */
        if (lua_istable(L, 3)) {
            /* labels[name], truth[name], scale[name] (a unit's factor:
             * U in mm/yr is scale = {U = 1e3}) */
            for (int k = 0; k < 3; k++) {
                static const char *const field[] = {"labels", "truth", "scale"};
                int t = lua_getfield(L, 3, field[k]);
                if (t == LUA_TTABLE) {
                    lua_pushvalue(L, -2);
                    lua_gettable(L, -2);
                    if (k == 0 && lua_type(L, -1) == LUA_TSTRING)
                        labels[c] = lua_tostring(L, -1); /* held by opts.labels */
                    else if (k == 1 && lua_type(L, -1) == LUA_TNUMBER)
                        truth[c] = lua_tonumber(L, -1);
                    else if (k == 2 && lua_type(L, -1) == LUA_TNUMBER)
                        scale = lua_tonumber(L, -1);
                    else if (k == 2 && !lua_isnil(L, -1))
                        return luaL_error(L, "dfle.plot.corner: scale.%s must be a number, "
                                          "got %s", lua_tostring(L, -3),
                                          dfle_lua_typename(L, -1));
                    lua_pop(L, 1);
                } else if (t != LUA_TNIL) {
                    return luaL_error(L, "dfle.plot.corner: '%s' must be a table keyed by "
                                      "parameter name, got %s", field[k],
                                      dfle_lua_typename(L, -1));
                }
                lua_pop(L, 1);
            }
        }
        lua_pop(L, 1);
        if (!(isfinite(scale) && scale > 0))
            return luaL_error(L, "dfle.plot.corner: scale of '%s' must be > 0 (got %s)",
                              labels[c], dfle_lua_number_text(L, scale));
        for (size_t i = 0; i < m; i++)
            x[i * d + c] = scale * R->X[((R->burn + 1) * R->walkers + i) * R->d + j];
        truth[c] *= scale;
        /* the bounds that hold it: res.summary[name].bounded */
        blo[c] = bhi[c] = NAN;
        {
            int top = lua_gettop(L);
            if (lua_getfield(L, 1, "summary") == LUA_TTABLE &&
                (lua_geti(L, names, (lua_Integer)j + 1), lua_gettable(L, -2)) == LUA_TTABLE &&
                lua_getfield(L, -1, "bounded") == LUA_TSTRING) {
                const char *b = lua_tostring(L, -1);
                if (strcmp(b, "lower") == 0 || strcmp(b, "both") == 0)
                    blo[c] = scale * R->prior[j].lo;
                if (strcmp(b, "upper") == 0 || strcmp(b, "both") == 0)
                    bhi[c] = scale * R->prior[j].hi;
            }
            lua_settop(L, top);
        }
    }
    memset(&o, 0, sizeof o);
    o.labels = labels;
    o.logaxis = logs;
    o.truth = truth;
    o.bound_lo = blo;
    o.bound_hi = bhi;
    o.nbins = (size_t)dfle_lua_check_whole(L, nbins, "plot.corner", "nbins", 0, 1000);
    if (dfle_plot_corner(path, &po, &o, d, m, x, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path); /* for run records */
    return 0;
}

/* A truth curve: a dfle.model (its slope-area pairs) or {A =, S =}. */
static size_t truth_curve(lua_State *L, int opts, const double **A, const double **S)
{
    if (!lua_istable(L, opts) || lua_getfield(L, opts, "truth") == LUA_TNIL)
        return 0;
    return dfle_lua_slope_area(L, -1, "plot.posterior_predictive: truth", A, S);
}

/* dfle.plot.posterior_predictive(res, path [, {n = 100, truth =, raw =, ...}]) */
static int l_predictive(lua_State *L)
{
    static const char *const keys[] = {"truth", "raw", NULL};
    double n = 100;
    const dfle_lua_param nums[] = {{"n", &n}};
    const char *path;
    int ctx, pred, data, raw = 1, ns = 0;
    size_t nA = 0, nd, nt, nraw = 0;
    const double *tA = NULL, *tS = NULL, *rA = NULL, *rS = NULL;
    dfle_plot_series s[8];
    dfle_plot_opts o;
    dfle_error err;
    double *arr[9];
    char lab[96];
    static const char *const fields[] = {"A", "median", "lo68", "hi68", "lo95", "hi95",
                                         "obs_lo95", "obs_hi95"};

    ctx = plot_args(L, "plot.posterior_predictive", DFLE_LUA_PLOT_AXES, nums, 1, keys, &path,
                    &o);
    if (lua_istable(L, 3) && lua_getfield(L, 3, "raw") != LUA_TNIL)
        raw = lua_toboolean(L, -1);
    lua_settop(L, 4);
    /* res:predict{ n = n } */
    lua_getfield(L, 1, "predict");
    lua_pushvalue(L, 1);
    lua_createtable(L, 0, 1);
    lua_pushnumber(L, n);
    lua_setfield(L, -2, "n");
    /* predict's errors raised again from here, which a script called: a
     * C function called from C has no position to give them. */
    if (lua_pcall(L, 2, 1, 0) != LUA_OK)
        return luaL_error(L, "%s", lua_isstring(L, -1) ? lua_tostring(L, -1)
                                                        : "dfle.inversion:predict failed");
    pred = lua_gettop(L);
    for (int k = 0; k < 8; k++) {
        size_t len;
        lua_getfield(L, pred, fields[k]);
        arr[k] = dfle_lua_check_array(L, -1, "plot.posterior_predictive", &len);
        if (k == 0)
            nA = len;
    }
    lua_getfield(L, ctx, "data");
    data = lua_gettop(L);
    lua_getfield(L, data, "A");
    arr[8] = dfle_lua_check_array(L, -1, "plot.posterior_predictive: data.A", &nd);
    lua_getfield(L, data, "S");
    {
        size_t nS;
        double *dS = dfle_lua_check_array(L, -1, "plot.posterior_predictive: data.S", &nS);
        if (raw && lua_getfield(L, data, "raw") == LUA_TTABLE) {
            lua_getfield(L, -1, "A");
            rA = dfle_lua_check_array(L, -1, "plot.posterior_predictive: raw A", &nraw);
            lua_getfield(L, -3, "S");
            rS = dfle_lua_check_array(L, -1, "plot.posterior_predictive: raw S", &nraw);
        }
        nt = truth_curve(L, 3, &tA, &tS);
        memset(s, 0, sizeof s);
        if (nraw > 0)
            s[ns++] = (dfle_plot_series){.label = "Slopes of the DEM cells", .n = nraw, .x = rA,
                                         .y = rS, .rgb = "#c8c8c8"};
        s[ns++] = (dfle_plot_series){.label = "95 % of the posterior model", .n = nA,
                                     .x = arr[0], .lo = arr[4], .hi = arr[5], .rgb = "#9ecae1"};
        s[ns++] = (dfle_plot_series){.label = "68 %", .n = nA, .x = arr[0], .lo = arr[2],
                                     .hi = arr[3], .rgb = "#3182bd"};
        s[ns++] = (dfle_plot_series){.label = "Posterior median", .n = nA, .x = arr[0],
                                     .y = arr[1], .style = DFLE_PLOT_LINES, .rgb = "#08306b"};
        s[ns++] = (dfle_plot_series){.label = "95 % of binned slopes (with noise)", .n = nA,
                                     .x = arr[0], .y = arr[6], .style = DFLE_PLOT_LINES, .dash = 1,
                                     .rgb = "#6baed6"};
        s[ns++] = (dfle_plot_series){.label = NULL, .n = nA, .x = arr[0], .y = arr[7],
                                     .style = DFLE_PLOT_LINES, .dash = 1, .rgb = "#6baed6"};
        if (nt > 0)
            s[ns++] = (dfle_plot_series){.label = "True model", .n = nt, .x = tA, .y = tS,
                                         .style = DFLE_PLOT_LINES, .dash = 1, .rgb = "vermillion"};
        snprintf(lab, sizeof lab, "Binned data (%d bins)", (int)nd);
        s[ns++] = (dfle_plot_series){.label = lab, .n = nd, .x = arr[8], .y = dS,
                                     .rgb = "#000000"};
    }
    if (o.x.label == NULL)
        o.x.label = dfle_plot_label("A", NULL);
    if (o.y.label == NULL)
        o.y.label = dfle_plot_label("S", NULL);
    if (o.x.log == 0)
        o.x.log = 1;
    if (o.y.log == 0)
        o.y.log = 1;
    if (o.width == 0 && o.height == 0)
        o.width = 16, o.height = 11;
    if (dfle_plot_xy(path, &o, s, (size_t)ns, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path); /* for run records */
    return 0;
}

void inv_open_plot(lua_State *L)
{
    lua_getfield(L, -1, "plot");
    lua_pushcfunction(L, l_corner);
    lua_setfield(L, -2, "corner");
    lua_pushcfunction(L, l_predictive);
    lua_setfield(L, -2, "posterior_predictive");
    lua_pop(L, 1);
}
