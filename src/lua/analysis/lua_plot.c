/*
 * lua_plot.c - dfle.plot.*: figures through gnuplot (see plot.h).
 *
 *   dfle.plot.slope_area(m, "slope_area.png" [, fit [, {nbins =, <options>}]])
 *   dfle.plot.profile(m, "profile.pdf" [, {<options>}])
 *   dfle.plot.flow(m, r, "flow.png" [, {exaggeration = 50, <options>}])
 *   dfle.plot.xy{ path =, series = {{x =, y =, label =, style =, ...}, ...}, <options> }
 *   dfle.plot.panels{ path =, panels = {{series =, ylabel =, ...}, ...}, <options> }
 *   dfle.plot.sheet{ path =, images = {...}, titles =, columns =, <page options> }
 *   dfle.plot.label(name) -> label, factor;  dfle.plot.number(v) -> "1.42×10^{5}"
 *
 * <options> are the keys every figure shares, read by lua_plot_opts.c.
 */
#include "lua/core/dfle_lua.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dfle/analysis.h"
#include "dfle/plot.h"

#define DEFAULT_NBINS 100

static double fit_field(lua_State *L, int idx, const char *fn, const char *key)
{
    double v;
    if (lua_getfield(L, idx, key) != LUA_TNUMBER)
        luaL_error(L, "dfle.%s: fit table lacks number '%s'", fn, key);
    v = lua_tonumber(L, -1);
    lua_pop(L, 1);
    return v;
}

const dfle_eq2_fit *dfle_lua_plot_slope_area_data(lua_State *L, int src, int fit_idx,
                                                  const char *fn, size_t nbins, size_t *n,
                                                  const double **A, const double **S,
                                                  dfle_bins *bins, dfle_eq2_fit *fit)
{
    const dfle_eq2_fit *fitp = NULL;
    dfle_error err;
    memset(fit, 0, sizeof *fit);
    memset(bins, 0, sizeof *bins);
    if (lua_istable(L, fit_idx)) {
        fit->S_df = fit_field(L, fit_idx, fn, "S_df");
        fit->A_df = fit_field(L, fit_idx, fn, "A_df");
        fit->a2 = fit_field(L, fit_idx, fn, "a2");
        fit->r2 = fit_field(L, fit_idx, fn, "r2");
        fitp = fit;
    } else if (!lua_isnil(L, fit_idx) &&
               !(lua_isboolean(L, fit_idx) && !lua_toboolean(L, fit_idx))) {
        luaL_argerror(L, fit_idx, "expected a fit table from dfle.fit_slope_area, nil or false");
    }
    *n = dfle_lua_slope_area(L, src, fn, A, S);
    if (dfle_bins_compute(*n, *A, *S, nbins, bins, &err) != DFLE_OK)
        luaL_error(L, "dfle.%s: %s", fn, err.msg);
    /* No fit given: fit now; a fit that fails just leaves the curve out. */
    if (fitp == NULL && lua_isnil(L, fit_idx)) {
        dfle_error fit_err;
        if (dfle_slope_area_fit(*n, *A, *S, nbins, NULL, fit, &fit_err) == DFLE_OK)
            fitp = fit;
    }
    return fitp;
}

static int l_plot_slope_area(lua_State *L)
{
    const double *A = NULL, *S = NULL;
    const char *path;
    double nbins = DEFAULT_NBINS;
    const dfle_lua_param params[] = {{"nbins", &nbins}};
    dfle_plot_opts o;
    dfle_eq2_fit fit;
    const dfle_eq2_fit *fitp;
    dfle_bins bins;
    dfle_error err;
    size_t n;
    int st;

    lua_settop(L, 4); /* scratch arrays go above the arguments */
    path = dfle_lua_check_string(L, 2, "plot.slope_area", "the path");
    dfle_lua_plot_opts(L, 4, "plot.slope_area", DFLE_LUA_PLOT_AXES, params, 1, NULL, &o);
    dfle_lua_check_whole(L, nbins, "plot.slope_area", "nbins", 1, 1e6);
    fitp = dfle_lua_plot_slope_area_data(L, 1, 3, "plot.slope_area", (size_t)nbins, &n, &A, &S,
                                         &bins, &fit);
    st = dfle_plot_slope_area(path, &o, n, A, S, &bins, fitp, &err);
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
    const double *x, *z, *S;
    dfle_plot_opts o;
    dfle_error err;

    lua_settop(L, 3);
    dfle_lua_plot_opts(L, 3, "plot.profile", DFLE_LUA_PLOT_AXES, NULL, 0, NULL, &o);
    x = dfle_lua_model_field(L, 1, DFLE_FIELD_X, "dfle.plot.profile");
    z = dfle_lua_model_field(L, 1, DFLE_FIELD_Z, "dfle.plot.profile");
    S = dfle_lua_model_field(L, 1, DFLE_FIELD_S, "dfle.plot.profile");
    if (dfle_plot_profile(path, &o, dfle_model_size(m), x, z, S, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path); /* for run records */
    return 0;
}

/* dfle.plot.flow(m, route_result, path [, {exaggeration = 50, ...}]):
 * like the paper's Fig. E1, in two panels: the bed with the flow's
 * surface z + e h at each snapshot (depth exaggerated so it shows at
 * all), and below it the depth h itself, where later, thinner flows
 * still show (on a log axis).  Each snapshot is drawn only where the
 * flow is (h >= 1 mm): zero depths would lie on the bed and on the
 * axis, hiding each other. */
static int l_plot_flow(lua_State *L)
{
    dfle_model *m = dfle_lua_check_model(L, 1);
    const char *path = dfle_lua_check_string(L, 3, "plot.flow", "the path");
    double e = 50.0;
    const dfle_lua_param params[] = {{"exaggeration", &e}};
    const size_t n = dfle_model_size(m);
    const double *x, *z;
    double *base;
    dfle_plot_series *top, *bot;
    dfle_plot_panel panels[2];
    dfle_plot_opts o;
    char *labels, elabel[96];
    size_t ns, k = 0;
    double reach = -HUGE_VAL; /* the farthest node any snapshot's flow is at */
    dfle_error err;

    luaL_checktype(L, 2, LUA_TTABLE);
    lua_settop(L, 4);
    dfle_lua_plot_opts(L, 4, "plot.flow", DFLE_LUA_PLOT_AXES, params, 1, NULL, &o);
    if (!(e > 0))
        luaL_error(L, "dfle.plot.flow: exaggeration must be > 0 (got %s)", dfle_lua_number_text(L, e));
    x = dfle_lua_model_field(L, 1, DFLE_FIELD_X, "dfle.plot.flow");
    z = dfle_lua_model_field(L, 1, DFLE_FIELD_Z, "dfle.plot.flow");
    if (lua_getfield(L, 2, "snapshots") != LUA_TTABLE || lua_rawlen(L, -1) == 0)
        luaL_error(L, "dfle.plot.flow: the routing has no snapshots; route with "
                      "rt:route(m, {snapshots = {t1, t2, ...}})");
    ns = lua_rawlen(L, -1);
    {
        int snaps = lua_gettop(L);
        double zmin = HUGE_VAL;
        top = lua_newuserdatauv(L, (ns + 2) * sizeof *top, 0);
        bot = lua_newuserdatauv(L, (ns + 1) * sizeof *bot, 0);
        labels = lua_newuserdatauv(L, (ns + 1) * 48, 0);
        base = lua_newuserdatauv(L, n * sizeof *base, 0);
        memset(top, 0, (ns + 2) * sizeof *top);
        memset(bot, 0, (ns + 1) * sizeof *bot);
        for (size_t i = 0; i < n; i++)
            zmin = fmin(zmin, z[i]);
        for (size_t i = 0; i < n; i++)
            base[i] = zmin;
        /* the rock, grey, with the bed line on it */
        top[0] = (dfle_plot_series){.n = n, .x = x, .lo = base, .hi = z, .rgb = "#d9d9d9"};
        top[1] = (dfle_plot_series){.label = "Bed", .n = n, .x = x, .y = z,
                                    .style = DFLE_PLOT_LINES, .rgb = "black", .width = 1};
        for (size_t j = 1; j <= ns; j++) {
            size_t nh;
            double t, *h, *surf;
            luaL_checkstack(L, 6, "too many snapshots");
            lua_rawgeti(L, snaps, (lua_Integer)j);
            if (!lua_istable(L, -1) || lua_getfield(L, -1, "t") != LUA_TNUMBER)
                luaL_error(L, "dfle.plot.flow: snapshot %d lacks its time t", (int)j);
            t = lua_tonumber(L, -1);
            lua_pop(L, 1);
            if (isnan(t)) { /* the flow ended before this time */
                lua_pop(L, 1);
                continue;
            }
            lua_getfield(L, -1, "h");
            h = dfle_lua_check_array(L, -1, "plot.flow: snapshot h", &nh);
            if (nh != n)
                luaL_error(L, "dfle.plot.flow: snapshot %d has %d depths, the model %d nodes",
                           (int)j, (int)nh, (int)n);
            surf = lua_newuserdatauv(L, n * sizeof *surf, 0);
            size_t wet = 0;
            for (size_t i = 0; i < n; i++) {
                if (!(h[i] >= 1e-3))
                    h[i] = NAN; /* no flow here (under 1 mm): draw nothing */
                else
                    reach = fmax(reach, x[i]), wet++;
                surf[i] = z[i] + e * h[i];
            }
            /* a flow on one or two nodes (a coarse grid's first step) is
             * no line, or a dot-long one: markers show it */
            int style = wet < 3 ? DFLE_PLOT_LINESPOINTS : DFLE_PLOT_LINES;
            snprintf(labels + k * 48, 48, "{/:Italic t} = %.3g s", t);
            top[k + 2] = (dfle_plot_series){.n = n, .x = x, .y = surf, .style = style,
                                            .rgb = NULL, .width = 1.5,
                                            .marker = DFLE_MARKER_CIRCLE};
            bot[k] = (dfle_plot_series){.label = labels + k * 48, .n = n, .x = x, .y = h,
                                        .style = style, .width = 1.5,
                                        .marker = DFLE_MARKER_CIRCLE};
            k++;
            /* leave the arrays on the stack: they back the series */
        }
    }
    if (k == 0)
        luaL_error(L, "dfle.plot.flow: the flow ended before every snapshot");
    /* the surfaces take the palette's colours in the order of the depths */
    for (size_t j = 0; j < k; j++) {
        static const char *const pal[] = {"blue", "vermillion", "green", "purple", "orange",
                                          "sky blue"};
        top[j + 2].rgb = bot[j].rgb = pal[j % 6];
    }
    memset(panels, 0, sizeof panels);
    panels[0].series = top;
    panels[0].nseries = k + 2;
    panels[0].y = o.y;
    snprintf(elabel, sizeof elabel, "Elevation, {/:Italic z}; flow surface {/:Italic z} + "
             "%g {/:Italic h} (m)", e);
    if (panels[0].y.label == NULL)
        panels[0].y.label = elabel;
    panels[0].weight = 1.4;
    panels[1].series = bot;
    panels[1].nseries = k;
    panels[1].y.label = dfle_plot_label("h", NULL);
    /* a log axis: the thin tails of later flows show next to the
     * metres-deep front of an early one */
    panels[1].y.log = 1;
    panels[1].weight = 1;
    if (o.x.label == NULL)
        o.x.label = dfle_plot_label("x", NULL);
    /* the figure is the flow: x from the head to a little past its
     * farthest front, unless the caller says */
    if (!o.x.has_hi && reach > x[0] && reach < x[n - 1]) {
        o.x.has_hi = 1;
        o.x.hi = fmin(x[n - 1], x[0] + 1.1 * (reach - x[0]));
    }
    if (!o.x.has_lo && !(o.x.has_hi && o.x.hi <= x[0])) { /* from the head, markers or not */
        o.x.has_lo = 1;
        o.x.lo = x[0];
    }
    if (dfle_plot_panels(path, &o, panels, 2, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path); /* for run records */
    return 0;
}

/* The series array at idx (named `what` in messages) into scratch
 * userdata left on the stack; returns it, *ns its length. */
static dfle_plot_series *read_series(lua_State *L, int idx, const char *fn, const char *what,
                                     size_t *ns)
{
    dfle_plot_series *series;
    int list;
    if (lua_getfield(L, idx, what) != LUA_TTABLE)
        luaL_error(L, "dfle.%s: parameter '%s' must be an array of {x =, y =}", fn, what);
    list = lua_gettop(L);
    if ((*ns = lua_rawlen(L, list)) == 0)
        luaL_error(L, "dfle.%s: '%s' is empty", fn, what);
    series = lua_newuserdatauv(L, *ns * sizeof *series, 0);
    for (size_t k = 0; k < *ns; k++) {
        lua_rawgeti(L, list, (lua_Integer)k + 1);
        /* the series table and its scratch arrays stay on the stack,
         * which keeps them alive until the plot is written */
        dfle_lua_plot_series(L, -1, fn, k + 1, &series[k]);
    }
    return series;
}

static const char *required_path(lua_State *L, const char *fn)
{
    const char *path = dfle_lua_opt_string(L, 1, "path", fn);
    if (path == NULL)
        luaL_error(L, "dfle.%s: parameter 'path' is required", fn);
    return path;
}

/* dfle.plot.xy{path =, series = {...}, ...}: any curves, e.g. several
 * models' slope-area data on one figure. */
static int l_plot_xy(lua_State *L)
{
    static const char *const own[] = {"path", "series", NULL};
    dfle_plot_opts o;
    dfle_plot_series *series;
    const char *path;
    size_t ns;
    dfle_error err;

    luaL_checktype(L, 1, LUA_TTABLE);
    lua_settop(L, 1);
    dfle_lua_plot_opts(L, 1, "plot.xy", DFLE_LUA_PLOT_AXES, NULL, 0, own, &o);
    path = required_path(L, "plot.xy");
    series = read_series(L, 1, "plot.xy", "series", &ns);
    if (dfle_plot_xy(path, &o, series, ns, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path); /* for run records */
    return 0;
}

/* dfle.plot.panels{path =, panels = {{series =, ylabel =, ylog =, yrange =,
 * yticks =, yformat =, weight =}, ...}, ...}: panels over one x axis. */
static int l_plot_panels(lua_State *L)
{
    static const char *const own[] = {"path", "panels", NULL};
    static const char *const panel_keys[] = {"series", "ylabel", "ylog",   "logy",
                                             "yrange", "yticks", "yformat", NULL};
    dfle_plot_opts o;
    dfle_plot_panel *panels;
    const char *path;
    size_t np = 0;
    int list;
    dfle_error err;

    luaL_checktype(L, 1, LUA_TTABLE);
    lua_settop(L, 1);
    dfle_lua_plot_opts(L, 1, "plot.panels", DFLE_LUA_PLOT_AXES, NULL, 0, own, &o);
    path = required_path(L, "plot.panels");
    if (lua_getfield(L, 1, "panels") != LUA_TTABLE || (np = lua_rawlen(L, -1)) == 0)
        luaL_error(L, "dfle.plot.panels: parameter 'panels' must be a non-empty array of "
                   "{series = {...}, ylabel = ...}");
    if (np > 16)
        luaL_error(L, "dfle.plot.panels: at most 16 panels (got %d)", (int)np);
    list = lua_gettop(L);
    panels = lua_newuserdatauv(L, np * sizeof *panels, 0);
    for (size_t p = 0; p < np; p++) {
        char fn[40];
        int pidx;
        double weight = 0;
        const dfle_lua_param nums[] = {{"weight", &weight}};
        luaL_checkstack(L, 8, "too many panels");
        lua_rawgeti(L, list, (lua_Integer)p + 1);
        pidx = lua_gettop(L);
        snprintf(fn, sizeof fn, "plot.panels: panels[%d]", (int)p + 1);
        if (!lua_istable(L, pidx))
            luaL_error(L, "dfle.%s must be a table", fn);
        dfle_lua_read_params(L, pidx, fn, nums, 1, panel_keys);
        dfle_lua_plot_axis(L, pidx, fn, 'y', &panels[p].y);
        {
            dfle_plot_opts check = {.y = panels[p].y}; /* the checks of the shared y */
            if (dfle_plot_opts_check(&check, &err) != DFLE_OK)
                dfle_lua_plot_raise(L, fn, &err);
        }
        panels[p].weight = weight;
        panels[p].series = read_series(L, pidx, fn, "series", &panels[p].nseries);
    }
    if (dfle_plot_panels(path, &o, panels, np, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path); /* for run records */
    return 0;
}

/* dfle.plot.sheet{path =, images = {...}, titles = {...}, columns = 3, ...} */
static int l_plot_sheet(lua_State *L)
{
    static const char *const own[] = {"path", "images", "titles", NULL};
    double columns = 3;
    const dfle_lua_param nums[] = {{"columns", &columns}};
    dfle_plot_opts o;
    const char **paths, **titles = NULL;
    const char *path;
    size_t n = 0;
    dfle_error err;

    luaL_checktype(L, 1, LUA_TTABLE);
    lua_settop(L, 1);
    dfle_lua_plot_opts(L, 1, "plot.sheet", DFLE_LUA_PLOT_PAGE, nums, 1, own, &o);
    dfle_lua_check_whole(L, columns, "plot.sheet", "columns", 1, 20);
    path = required_path(L, "plot.sheet");
    if (lua_getfield(L, 1, "images") != LUA_TTABLE || (n = lua_rawlen(L, -1)) == 0)
        luaL_error(L, "dfle.plot.sheet: parameter 'images' must be a non-empty array of paths");
    paths = lua_newuserdatauv(L, n * sizeof *paths, 0);
    for (size_t k = 0; k < n; k++) {
        lua_rawgeti(L, 2, (lua_Integer)k + 1);
        if (lua_type(L, -1) != LUA_TSTRING)
            luaL_error(L, "dfle.plot.sheet: images[%d] must be a path, got %s", (int)k + 1,
                       dfle_lua_typename(L, -1));
        paths[k] = dfle_lua_check_string(L, -1, "plot.sheet", "an image path");
        lua_pop(L, 1); /* images holds it */
    }
    if (lua_getfield(L, 1, "titles") == LUA_TTABLE) {
        int t = lua_gettop(L);
        titles = lua_newuserdatauv(L, n * sizeof *titles, 0);
        for (size_t k = 0; k < n; k++) {
            int ty = lua_rawgeti(L, t, (lua_Integer)k + 1);
            if (ty != LUA_TNIL && ty != LUA_TSTRING)
                luaL_error(L, "dfle.plot.sheet: titles[%d] must be a string, got %s", (int)k + 1,
                           dfle_lua_typename(L, -1));
            titles[k] = lua_tostring(L, -1); /* titles holds it */
            lua_pop(L, 1);
        }
    } else if (!lua_isnil(L, -1)) {
        luaL_error(L, "dfle.plot.sheet: parameter 'titles' must be an array of strings, got %s",
                   dfle_lua_typename(L, -1));
    }
    if (dfle_plot_sheet(path, &o, paths, titles, n, (size_t)columns, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path); /* for run records */
    return 0;
}

/* dfle.plot.label(name) -> the house axis label, the factor to its unit */
static int l_plot_label(lua_State *L)
{
    const char *name = dfle_lua_check_string(L, 1, "plot.label", "the name");
    double factor = 1;
    const char *label = dfle_plot_label(name, &factor);
    if (label == NULL) {
        luaL_Buffer b;
        luaL_buffinit(L, &b);
        for (size_t i = 0; dfle_plot_label_name(i) != NULL; i++) {
            luaL_addstring(&b, i ? ", " : "");
            luaL_addstring(&b, dfle_plot_label_name(i));
        }
        luaL_pushresult(&b);
        return luaL_error(L, "dfle.plot.label: no house label for '%s' (known: %s)", name,
                          lua_tostring(L, -1));
    }
    lua_pushstring(L, label);
    lua_pushnumber(L, factor);
    return 2;
}

/* dfle.plot.number(v) -> "1.42×10^{5}": a number as labels show it */
static int l_plot_number(lua_State *L)
{
    char buf[64];
    dfle_plot_number(buf, sizeof buf, luaL_checknumber(L, 1));
    lua_pushstring(L, buf);
    return 1;
}

void dfle_lua_open_plot(lua_State *L)
{
    static const luaL_Reg funcs[] = {
        {"slope_area", l_plot_slope_area},
        {"profile", l_plot_profile},
        {"flow", l_plot_flow},
        {"xy", l_plot_xy},
        {"panels", l_plot_panels},
        {"sheet", l_plot_sheet},
        {"label", l_plot_label},
        {"number", l_plot_number},
        {NULL, NULL}};
    lua_newtable(L);
    luaL_setfuncs(L, funcs, 0);
    lua_setfield(L, -2, "plot");
}
