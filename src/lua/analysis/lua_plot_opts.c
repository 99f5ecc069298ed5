/*
 * lua_plot_opts.c - the options table every dfle.plot function shares,
 * and the series tables, read in one place (declared in dfle_lua.h).
 *
 *   title, size = {17, 11, "cm"}, dpi, font = "Helvetica,10"        (page)
 *   xlabel, xrange = {lo, hi}, xlog, xticks, xformat; y...; c...      (axes)
 *   legend = "top left" | "below" | false | ...
 *
 * Lua reads the shapes (tables, booleans, strings); the names inside
 * them (units, legend positions, markers, dashes, colours) and every
 * value's bounds are checked by the library (dfle/plot.h), so C callers
 * and scripts get the same rules and messages.
 */
#include "lua/core/dfle_lua.h"

#include <string.h>

enum { MAX_KEYS = 64 };

static const char *const page_keys[] = {"title", "size", "font", NULL};
static const char *const axes_keys[] = {
    "xlabel", "ylabel", "clabel", "xrange", "yrange", "crange", "xlog", "ylog", "clog",
    "logx",   "logy",   "logc",   "xticks", "yticks", "cticks", "xformat", "yformat",
    "cformat", "legend", NULL};

int dfle_lua_plot_raise(lua_State *L, const char *fn, const dfle_error *err)
{
    const char *m = err->msg;
    if (strncmp(m, "plot: ", 6) == 0)
        m += 6;
    return luaL_error(L, "dfle.%s: %s", fn, m);
}

/* nil: 0 (the figure's own), true: 1, false: -1. */
static int opt_tri(lua_State *L, int idx, const char *key, const char *fn)
{
    int t = lua_getfield(L, idx, key), v = 0;
    if (t == LUA_TBOOLEAN)
        v = lua_toboolean(L, -1) ? 1 : -1;
    else if (t != LUA_TNIL)
        luaL_error(L, "dfle.%s: parameter '%s' must be a boolean, got %s", fn, key,
                   dfle_lua_typename(L, -1));
    lua_pop(L, 1);
    return v;
}

/* Element k of the table on top: a number (*v, returns 1), nil
 * (returns 0), or an error naming key[k]. */
static int opt_elem(lua_State *L, const char *fn, const char *key, int k, double *v)
{
    int t = lua_geti(L, -1, k), have = 0;
    if (t == LUA_TNUMBER) {
        *v = lua_tonumber(L, -1);
        have = 1;
    } else if (t != LUA_TNIL) {
        luaL_error(L, "dfle.%s: %s[%d] must be a number or nil, got %s", fn, key, k,
                   dfle_lua_typename(L, -1));
    }
    lua_pop(L, 1);
    return have;
}

/* <axis>ticks: false (none), a spacing, or an array of values or of
 * {value, "label"} pairs. */
static void read_ticks(lua_State *L, int idx, const char *fn, const char *key, dfle_plot_axis *a)
{
    static const double none[1] = {0};
    int t = lua_getfield(L, idx, key);
    if (t == LUA_TNIL) {
        lua_pop(L, 1);
    } else if (t == LUA_TBOOLEAN && !lua_toboolean(L, -1)) {
        a->ticks = none;
        a->nticks = 0;
        lua_pop(L, 1);
    } else if (t == LUA_TNUMBER) {
        a->step = lua_tonumber(L, -1);
        lua_pop(L, 1);
    } else if (t == LUA_TTABLE) {
        size_t n = lua_rawlen(L, -1);
        double *v;
        const char **lab;
        if (n > DFLE_PLOT_MAXTICKS)
            luaL_error(L, "dfle.%s: %s: at most %d ticks (got %d)", fn, key,
                       DFLE_PLOT_MAXTICKS, (int)n);
        /* the values and labels live in userdata left on the stack
         * (under the table, which holds the label strings) */
        v = lua_newuserdatauv(L, (n + 1) * sizeof *v, 0);
        lab = lua_newuserdatauv(L, (n + 1) * sizeof *lab, 0);
        lua_rotate(L, -3, 2); /* userdata below the ticks table */
        for (size_t i = 0; i < n; i++) {
            int e = lua_geti(L, -1, (lua_Integer)i + 1);
            lab[i] = NULL;
            if (e == LUA_TNUMBER) {
                v[i] = lua_tonumber(L, -1);
            } else if (e == LUA_TTABLE && lua_geti(L, -1, 1) == LUA_TNUMBER) {
                v[i] = lua_tonumber(L, -1);
                if (lua_geti(L, -2, 2) == LUA_TSTRING)
                    lab[i] = dfle_lua_check_string(L, -1, fn, key); /* the pair holds it */
                else if (!lua_isnil(L, -1))
                    luaL_error(L, "dfle.%s: %s[%d]: the label must be a string, got %s", fn, key,
                               (int)i + 1, dfle_lua_typename(L, -1));
                lua_pop(L, 2);
            } else {
                luaL_error(L, "dfle.%s: %s[%d] must be a number or {value, \"label\"}", fn, key,
                           (int)i + 1);
            }
            lua_pop(L, 1);
        }
        a->ticks = v;
        a->tick_labels = lab;
        a->nticks = n;
        lua_pop(L, 1); /* the table; the userdata stay */
    } else {
        luaL_error(L, "dfle.%s: %s must be a spacing, an array of ticks or false, got %s", fn,
                   key, dfle_lua_typename(L, -1));
    }
}

void dfle_lua_plot_axis(lua_State *L, int idx, const char *fn, char axis, dfle_plot_axis *a)
{
    char key[16], old[8];
    idx = lua_absindex(L, idx);
    memset(a, 0, sizeof *a);
    if (!lua_istable(L, idx))
        return;
    snprintf(key, sizeof key, "%clabel", axis);
    a->label = dfle_lua_opt_string(L, idx, key, fn);
    snprintf(key, sizeof key, "%cformat", axis);
    a->format = dfle_lua_opt_string(L, idx, key, fn);
    snprintf(key, sizeof key, "%clog", axis);
    a->log = opt_tri(L, idx, key, fn);
    snprintf(old, sizeof old, "log%c", axis); /* the older spelling */
    if (a->log == 0)
        a->log = opt_tri(L, idx, old, fn);
    snprintf(key, sizeof key, "%crange", axis);
    if (lua_getfield(L, idx, key) == LUA_TTABLE) {
        a->has_lo = opt_elem(L, fn, key, 1, &a->lo);
        a->has_hi = opt_elem(L, fn, key, 2, &a->hi);
    } else if (!lua_isnil(L, -1)) {
        luaL_error(L, "dfle.%s: %s must be a table {lo, hi} (either may be nil), got %s", fn,
                   key, dfle_lua_typename(L, -1));
    }
    lua_pop(L, 1);
    snprintf(key, sizeof key, "%cticks", axis);
    read_ticks(L, idx, fn, key, a);
}

/* size = {width, height [, unit]}: either side may be nil. */
static void read_size(lua_State *L, int idx, const char *fn, dfle_plot_opts *o)
{
    dfle_error err;
    int t = lua_getfield(L, idx, "size");
    if (t == LUA_TTABLE) {
        int hw = opt_elem(L, fn, "size", 1, &o->width);
        int hh = opt_elem(L, fn, "size", 2, &o->height);
        int u = lua_geti(L, -1, 3);
        if (!hw && !hh)
            luaL_error(L, "dfle.%s: size needs a width or a height: {width, height [, unit]}, "
                       "e.g. {17, 11, \"cm\"}", fn);
        if (!hw)
            o->width = 0;
        if (!hh)
            o->height = 0;
        if (u == LUA_TSTRING) {
            int unit = dfle_plot_parse_unit(lua_tostring(L, -1), "size unit", &err);
            if (unit < 0)
                dfle_lua_plot_raise(L, fn, &err);
            o->unit = unit;
        } else if (u != LUA_TNIL) {
            luaL_error(L, "dfle.%s: size[3] (the unit) must be \"cm\", \"in\" or \"px\", got %s",
                       fn, dfle_lua_typename(L, -1));
        }
        lua_pop(L, 1);
    } else if (t != LUA_TNIL) {
        luaL_error(L, "dfle.%s: size must be a table {width, height [, unit]}, e.g. "
                   "{17, 11, \"cm\"}, got %s", fn, dfle_lua_typename(L, -1));
    }
    lua_pop(L, 1);
}

/* legend = "position" | false | true (automatic). */
static int read_legend(lua_State *L, int idx, const char *fn)
{
    dfle_error err;
    int t = lua_getfield(L, idx, "legend"), v = DFLE_LEGEND_AUTO;
    if (t == LUA_TBOOLEAN)
        v = lua_toboolean(L, -1) ? DFLE_LEGEND_AUTO : DFLE_LEGEND_NONE;
    else if (t == LUA_TSTRING && (v = dfle_plot_parse_legend(lua_tostring(L, -1), "legend",
                                                             &err)) < 0)
        dfle_lua_plot_raise(L, fn, &err);
    else if (t != LUA_TNIL && t != LUA_TSTRING)
        luaL_error(L, "dfle.%s: legend must be a position (\"top left\", \"below\", ...) or "
                   "false, got %s", fn, dfle_lua_typename(L, -1));
    lua_pop(L, 1);
    return v;
}

/* dst = a ++ b (NULL-terminated lists), at most MAX_KEYS - 1 keys. */
static void append_keys(const char **dst, size_t *n, const char *const *src)
{
    for (; src != NULL && *src != NULL && *n < MAX_KEYS - 1; src++)
        dst[(*n)++] = *src;
    dst[*n] = NULL;
}

void dfle_lua_plot_opts(lua_State *L, int idx, const char *fn, unsigned which,
                        const dfle_lua_param *params, size_t np, const char *const *own,
                        dfle_plot_opts *o)
{
    const char *keys[MAX_KEYS];
    dfle_lua_param nums[16];
    size_t nk = 0;
    dfle_error err;
    double dpi = 0;

    idx = lua_absindex(L, idx);
    memset(o, 0, sizeof *o);
    if (!lua_isnoneornil(L, idx) && !lua_istable(L, idx))
        luaL_error(L, "dfle.%s: options must be a table, got %s", fn, dfle_lua_typename(L, idx));
    keys[0] = NULL;
    append_keys(keys, &nk, own);
    append_keys(keys, &nk, page_keys);
    if (which & DFLE_LUA_PLOT_AXES)
        append_keys(keys, &nk, axes_keys);
    if (np > 15)
        np = 15;
    if (np > 0) /* params may be NULL when there are none: memcpy must not see it */
        memcpy(nums, params, np * sizeof *nums);
    nums[np] = (dfle_lua_param){"dpi", &dpi};
    dfle_lua_read_params(L, idx, fn, nums, np + 1, keys);
    if (!lua_istable(L, idx))
        return;
    o->dpi = dpi;
    o->title = dfle_lua_opt_string(L, idx, "title", fn);
    o->font = dfle_lua_opt_string(L, idx, "font", fn);
    read_size(L, idx, fn, o);
    if (which & DFLE_LUA_PLOT_AXES) {
        dfle_lua_plot_axis(L, idx, fn, 'x', &o->x);
        dfle_lua_plot_axis(L, idx, fn, 'y', &o->y);
        dfle_lua_plot_axis(L, idx, fn, 'c', &o->c);
        o->legend = read_legend(L, idx, fn);
    }
    if (dfle_plot_opts_check(o, &err) != DFLE_OK)
        dfle_lua_plot_raise(L, fn, &err);
}

/* An array field of the series at s_idx, or NULL when absent. */
static const double *series_array(lua_State *L, int s_idx, const char *fn, size_t k,
                                  const char *key, size_t *n)
{
    char what[64];
    if (lua_getfield(L, s_idx, key) == LUA_TNIL) {
        lua_pop(L, 1);
        return NULL;
    }
    snprintf(what, sizeof what, "%s: series[%d].%s", fn, (int)k, key);
    return dfle_lua_check_array(L, -1, what, n); /* the table and its copy stay */
}

void dfle_lua_plot_series(lua_State *L, int idx, const char *fn, size_t k, dfle_plot_series *s)
{
    static const char *const keys[] = {"x",   "y",    "label", "lines",  "style",  "color",
                                       "lo",  "hi",   "rgb",   "dash",   "marker", NULL};
    double width = 0, msize = 0;
    const dfle_lua_param nums[] = {{"width", &width}, {"marker_size", &msize}};
    char what[64];
    dfle_error err;
    size_t n, m;
    const char *str;
    int t;

    idx = lua_absindex(L, idx);
    if (!lua_istable(L, idx))
        luaL_error(L, "dfle.%s: series[%d] must be a table", fn, (int)k);
    luaL_checkstack(L, 16, "too many plot series");
    snprintf(what, sizeof what, "%s series[%d]", fn, (int)k);
    dfle_lua_read_params(L, idx, what, nums, 2, keys);
    memset(s, 0, sizeof *s);
    s->width = width;
    s->marker_size = msize;
    s->label = dfle_lua_opt_string(L, idx, "label", fn);
    s->rgb = dfle_lua_opt_string(L, idx, "rgb", fn);
    if ((str = dfle_lua_opt_string(L, idx, "style", fn)) != NULL) {
        snprintf(what, sizeof what, "series[%d].style", (int)k);
        if ((s->style = dfle_plot_parse_style(str, what, &err)) < 0)
            dfle_lua_plot_raise(L, fn, &err);
    } else {
        s->style = opt_tri(L, idx, "lines", fn) > 0 ? DFLE_PLOT_LINES : DFLE_PLOT_POINTS;
    }
    t = lua_getfield(L, idx, "dash");
    if (t == LUA_TBOOLEAN) {
        s->dash = lua_toboolean(L, -1) ? DFLE_DASH_DASH : DFLE_DASH_SOLID;
    } else if (t == LUA_TSTRING) {
        snprintf(what, sizeof what, "series[%d].dash", (int)k);
        if ((s->dash = dfle_plot_parse_dash(lua_tostring(L, -1), what, &err)) < 0)
            dfle_lua_plot_raise(L, fn, &err);
    } else if (t != LUA_TNIL) {
        luaL_error(L, "dfle.%s: series[%d].dash must be a boolean or a pattern name, got %s",
                   fn, (int)k, dfle_lua_typename(L, -1));
    }
    lua_pop(L, 1);
    if ((str = dfle_lua_opt_string(L, idx, "marker", fn)) != NULL) {
        snprintf(what, sizeof what, "series[%d].marker", (int)k);
        if ((s->marker = dfle_plot_parse_marker(str, what, &err)) < 0)
            dfle_lua_plot_raise(L, fn, &err);
    }
    s->x = series_array(L, idx, fn, k, "x", &s->n);
    if (s->x == NULL)
        luaL_error(L, "dfle.%s: series[%d] needs an array x", fn, (int)k);
    if ((s->lo = series_array(L, idx, fn, k, "lo", &n)) != NULL) {
        /* a band between lo and hi: y is not needed */
        s->hi = series_array(L, idx, fn, k, "hi", &m);
        if (s->hi == NULL || n != s->n || m != s->n)
            luaL_error(L, "dfle.%s: series[%d] has %d x but %d lo and %d hi values", fn, (int)k,
                       (int)s->n, (int)n, s->hi != NULL ? (int)m : 0);
    } else if (lua_getfield(L, idx, "hi") != LUA_TNIL) {
        luaL_error(L, "dfle.%s: series[%d] has hi but no lo", fn, (int)k);
    } else {
        lua_pop(L, 1);
    }
    s->y = series_array(L, idx, fn, k, "y", &n);
    if (s->y == NULL && s->lo == NULL)
        luaL_error(L, "dfle.%s: series[%d] needs an array y (or lo and hi)", fn, (int)k);
    if (s->y != NULL && n != s->n)
        luaL_error(L, "dfle.%s: series[%d] has %d x but %d y values", fn, (int)k, (int)s->n,
                   (int)n);
    /* a value per point, coloured on a continuous scale */
    if ((s->c = series_array(L, idx, fn, k, "color", &n)) != NULL && n != s->n)
        luaL_error(L, "dfle.%s: series[%d] has %d points but %d colour values", fn, (int)k,
                   (int)s->n, (int)n);
    if (dfle_plot_series_check(s, 1, &err) != DFLE_OK) {
        /* the library counts this one series as "series 1" */
        const char *msg = strncmp(err.msg, "plot: series 1", 14) == 0 ? err.msg + 14 : err.msg;
        luaL_error(L, "dfle.%s: series[%d]%s", fn, (int)k, msg);
    }
}
