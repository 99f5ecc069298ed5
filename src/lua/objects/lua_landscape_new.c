/*
 * lua_landscape_new.c - dfle.landscape{...}: building a landscape from
 * Lua (synthetic grids, a DEM and its catchment, components, fields as
 * numbers, arrays or functions, the combine rule).  The methods are in
 * lua_landscape.c.
 *
 * Fields given as Lua functions and a custom combine rule are kept as
 * registry references and called back during runs, under lua_pcall with
 * a message handler, on the thread that runs the call; a failure is kept
 * in the userdata's cb_err and raised by dfle_lua_ls_raise.
 */
#include "lua/objects/lua_landscape.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/crs.h"
#include "dfle/dem.h"
#include "dfle/plausible.h"
#include "dfle/raster.h"

/* The plausibility table's word (dfle/plausible.h) on a field given as
 * an array, a raster or a function, as dfle.model gives it on numbers:
 * its largest and smallest values, one warning a field. */
static void warn_implausible_field(lua_State *L, const char *key, const char *kind, double lo,
                                   double hi)
{
    char msg[400], full[520];
    if (!(lo <= hi))
        return; /* no finite value: the checks of values say why */
    if (lo == hi) {
        dfle_lua_warn_implausible(L, "landscape", key, lo);
        return;
    }
    if (dfle_plausible_check(key, hi, msg, sizeof msg) ||
        dfle_plausible_check(key, lo, msg, sizeof msg)) {
        snprintf(full, sizeof full, "%s %s, at its %s: %s", kind, key,
                 dfle_plausible_check(key, hi, msg, sizeof msg) ? "largest" : "smallest", msg);
        dfle_lua_warn(L, "landscape", full);
    }
}

static int msgh(lua_State *L)
{
    const char *msg = lua_tostring(L, 1);
    luaL_traceback(L, L, msg != NULL ? msg : "(error object is not a string)", 1);
    return 1;
}

/* Cell centre of index c in map coordinates. */
static void centre(const lua_ls *u, size_t nx, double dx, double dy, size_t c, double *x,
                   double *y)
{
    *x = u->x0 + ((double)(c % nx) + 0.5) * dx;
    *y = u->y0 - ((double)(c / nx) + 0.5) * dy;
}

/* A field written as f(x, y [, t]): one call per data cell. */
static int field_fn(void *ud, double t, double *out, dfle_error *err)
{
    field_cb *cb = ud;
    lua_ls *u = cb->u;
    lua_State *L = u->L;
    const size_t nx = u->nx, n = nx * u->ny;
    const double dx = u->dx, dy = u->dy;
    const double *z = u->zmask;
    int top = lua_gettop(L);
    double lo = INFINITY, hi = -INFINITY;
    lua_pushcfunction(L, msgh);
    for (size_t c = 0; c < n; c++) {
        double x, y, v;
        if (isnan(z[c]))
            continue;
        centre(u, nx, dx, dy, c, &x, &y);
        lua_rawgeti(L, LUA_REGISTRYINDEX, cb->ref);
        lua_pushnumber(L, x);
        lua_pushnumber(L, y);
        lua_pushnumber(L, t);
        if (lua_pcall(L, 3, 1, top + 1) != LUA_OK) {
            dfle_error_set(err, DFLE_ECALLBACK, "landscape: %s(x, y, t) failed at x = %g, y = "
                           "%g, t = %g yr: %s", cb->name, x, y, t,
                           lua_tostring(L, -1) ? lua_tostring(L, -1) : "?");
            lua_settop(L, top);
            return DFLE_ECALLBACK;
        }
        if (lua_type(L, -1) != LUA_TNUMBER) {
            dfle_error_set(err, DFLE_ECALLBACK, "landscape: %s(x, y, t) must return a number, "
                           "got %s (at x = %g, y = %g)", cb->name, dfle_lua_typename(L, -1), x, y);
            lua_settop(L, top);
            return DFLE_ECALLBACK;
        }
        v = lua_tonumber(L, -1);
        if (isfinite(v)) {
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
        out[c] = v / cb->divide_by;
        lua_pop(L, 1);
    }
    lua_settop(L, top);
    if (!cb->judged) { /* its first values: once, not at every step */
        cb->judged = 1;
        warn_implausible_field(L, cb->name, "the function", lo, hi);
    }
    dfle_lua_touch(L);
    return DFLE_OK;
}

/* combine = function(count, A) -> factor. */
static double combine_fn(void *ud, double count, double A)
{
    lua_ls *u = ud;
    lua_State *L = u->L;
    int top = lua_gettop(L);
    double v = NAN;
    lua_pushcfunction(L, msgh);
    lua_rawgeti(L, LUA_REGISTRYINDEX, u->ref_combine);
    lua_pushnumber(L, count);
    lua_pushnumber(L, A);
    if (lua_pcall(L, 2, 1, top + 1) != LUA_OK)
        snprintf(u->cb_err, sizeof u->cb_err, "landscape: combine(count, A) failed: %s",
                 lua_tostring(L, -1) ? lua_tostring(L, -1) : "?");
    else if (lua_type(L, -1) != LUA_TNUMBER || !(lua_tonumber(L, -1) >= 0))
        snprintf(u->cb_err, sizeof u->cb_err, "landscape: combine(count = %g, A = %g) must return "
                 "a number >= 0, got %s", count, A, lua_tostring(L, -1) ? lua_tostring(L, -1)
                                                                        : dfle_lua_typename(L, -1));
    else
        v = lua_tonumber(L, -1);
    lua_settop(L, top);
    return v;
}


/* ---------------------------------------------------------------- */
/* Construction                                                     */
/* ---------------------------------------------------------------- */

static enum dfle_drainage_edge check_edge(lua_State *L, int idx, const char *what)
{
    static const char *const kinds[] = {"open", "base_level", "closed", NULL};
    const char *s;
    if (lua_type(L, idx) != LUA_TSTRING)
        luaL_error(L, "dfle.landscape: %s must be \"base_level\", \"closed\" or \"open\", got %s",
                   what, dfle_lua_typename(L, idx));
    s = lua_tostring(L, idx);
    for (int k = 0; kinds[k] != NULL; k++)
        if (strcmp(s, kinds[k]) == 0)
            return (enum dfle_drainage_edge)k;
    luaL_error(L, "dfle.landscape: %s must be \"base_level\", \"closed\" or \"open\", got '%s'",
               what, s);
    return DFLE_DRAINAGE_OPEN;
}

/* Keep the value on top of the stack alive until the constructor
 * returns (scratch arrays the C constructor reads): it goes into the
 * anchor table at stack index 3, and stays on top. */
static void anchor(lua_State *L)
{
    lua_pushvalue(L, -1);
    lua_rawseti(L, 3, (lua_Integer)lua_rawlen(L, 3) + 1);
}

/* The smallest and largest finite values of g over the grid's data
 * cells (the user's, before a scale divides them). */
static void data_range(const lua_ls *u, const double *g, size_t n, double *lo, double *hi)
{
    *lo = INFINITY;
    *hi = -INFINITY;
    for (size_t c = 0; c < n; c++)
        if (!isnan(u->zmask[c]) && isfinite(g[c])) {
            *lo = g[c] < *lo ? g[c] : *lo;
            *hi = g[c] > *hi ? g[c] : *hi;
        }
}

/* A raster for a field lies on the grid: the same cells, the same
 * corner (to a millionth of a cell).  It is not resampled. */
static void check_raster_grid(lua_State *L, const lua_ls *u, const dfle_dem *d, const char *key,
                              size_t nx, size_t ny)
{
    double e[4], rdx = dfle_dem_dx(d), rdy = dfle_dem_dy(d);
    char msg[600];
    dfle_dem_extent(d, e);
    if (dfle_dem_nx(d) != nx || dfle_dem_ny(d) != ny || fabs(rdx - u->dx) > 1e-9 * u->dx ||
        fabs(rdy - u->dy) > 1e-9 * u->dy || fabs(e[0] - u->x0) > 1e-6 * u->dx ||
        fabs(e[3] - u->y0) > 1e-6 * u->dy) {
        snprintf(msg, sizeof msg, "raster '%s' is %zu x %zu cells of %g x %g m with its "
                 "north-west corner at (%.10g, %.10g), the grid %zu x %zu cells of %g x %g m at "
                 "(%.10g, %.10g): it must lie on the grid (resample it first, e.g. with "
                 "gdalwarp, or give the grid's x0 and y0)", key, dfle_dem_nx(d), dfle_dem_ny(d),
                 rdx, rdy, e[0], e[3], nx, ny, u->dx, u->dy, u->x0, u->y0);
        luaL_error(L, "dfle.landscape: %s", msg);
    }
}

/* A field option: a number, an array of nx * ny, a dfle.dem on the grid,
 * or a function f(x, y [, t]).  Its values are the C library's to check
 * cell by cell (named as given here); the plausibility table warns. */
static void read_field(lua_State *L, lua_ls *u, int opts, const char *key, const char *named,
                       int which, dfle_landscape_field *f, size_t nx, size_t ny, double divide_by)
{
    int t = lua_getfield(L, opts, key);
    field_cb *cb = &u->cb[which];
    cb->u = u;
    cb->name = key;
    cb->divide_by = divide_by;
    f->name = named;
    f->show_scale = divide_by;
    if (t == LUA_TNIL) {
        lua_pop(L, 1);
        return;
    }
    if (t == LUA_TNUMBER) {
        f->value = lua_tonumber(L, -1) / divide_by;
        if (!isfinite(f->value))
            luaL_error(L, "dfle.landscape: parameter '%s' must be finite", key);
        dfle_lua_warn_implausible(L, "landscape", key, lua_tonumber(L, -1));
    } else if (t == LUA_TFUNCTION) {
        lua_Debug ar;
        lua_pushvalue(L, -1);
        lua_getinfo(L, ">u", &ar);
        cb->with_t = ar.nparams >= 3 || ar.isvararg;
        cb->ref = luaL_ref(L, LUA_REGISTRYINDEX);
        f->fn = field_fn;
        f->ud = cb;
        f->varies_in_time = cb->with_t;
        return;
    } else if (t == LUA_TUSERDATA && luaL_testudata(L, -1, "dfle.dem") != NULL) {
        dfle_dem *d = dfle_lua_check_object(L, lua_gettop(L), "dfle.dem");
        double *g, lo, hi;
        check_raster_grid(L, u, d, key, nx, ny);
        data_range(u, dfle_dem_z(d), nx * ny, &lo, &hi);
        warn_implausible_field(L, key, "the raster", lo, hi);
        g = lua_newuserdatauv(L, nx * ny * sizeof *g, 0);
        for (size_t c = 0; c < nx * ny; c++)
            g[c] = dfle_dem_z(d)[c] / divide_by;
        anchor(L);
        f->grid = g;
        lua_pop(L, 2);
        return;
    } else if (t == LUA_TTABLE) {
        size_t n;
        char what[64];
        double *g, lo, hi;
        snprintf(what, sizeof what, "landscape: %s", key);
        g = dfle_lua_check_array(L, -1, what, &n);
        if (n != nx * ny)
            luaL_error(L, "dfle.landscape: '%s' has %d values, the grid %d x %d = %d cells", key,
                       (int)n, (int)nx, (int)ny, (int)(nx * ny));
        data_range(u, g, n, &lo, &hi);
        warn_implausible_field(L, key, "the array", lo, hi);
        for (size_t c = 0; c < n; c++)
            g[c] /= divide_by;
        anchor(L);
        f->grid = g;
        lua_pop(L, 2);
        return;
    } else {
        luaL_error(L, "dfle.landscape: parameter '%s' must be a number, an array of nx * ny "
                      "values, a dfle.dem raster or a function f(x, y [, t]), got %s", key,
                   dfle_lua_typename(L, -1));
    }
    lua_pop(L, 1);
}

/* Push component `key` (or its default, or nil for false). */
static void push_component(lua_State *L, int opts, const char *key, const char *tname,
                           const char *sub, const char *ctor)
{
    int t = lua_getfield(L, opts, key);
    if (t == LUA_TBOOLEAN && !lua_toboolean(L, -1)) {
        lua_pop(L, 1);
        lua_pushnil(L);
        return;
    }
    if (t == LUA_TNIL) {
        lua_pop(L, 1);
        dfle_lua_push_module(L);
        lua_getfield(L, -1, sub);
        lua_getfield(L, -1, ctor);
        lua_call(L, 0, 1);
        lua_replace(L, -3);
        lua_pop(L, 1);
        return;
    }
    if (luaL_testudata(L, -1, tname) == NULL)
        luaL_error(L, "dfle.landscape: parameter '%s' must be a %s or false, got %s", key, tname,
                   dfle_lua_typename(L, -1));
}

/* Seeded noise (xorshift64*), the same on every machine. */
static double noise_next(uint64_t *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (double)((*s * 0x2545F4914F6CDD1Dull) >> 11) / 9007199254740992.0;
}

/* The catchment above an outlet of a DEM: its cells, the snapped outlet. */
static double *catchment(lua_State *L, dfle_dem *dem, double E, double N, size_t *outlet)
{
    const size_t n = dfle_dem_nx(dem) * dfle_dem_ny(dem);
    dfle_dem_geo g;
    double e[4], *z;
    dfle_dem *copy = NULL;
    dfle_profile *net = NULL;
    dfle_network_opts no;
    dfle_error err;
    int st;

    dfle_dem_extent(dem, e);
    g.x0 = e[0], g.y0 = e[3], g.dx = dfle_dem_dx(dem), g.dy = dfle_dem_dy(dem);
    z = lua_newuserdatauv(L, n * sizeof *z, 0);
    st = dfle_dem_new(dfle_dem_nx(dem), dfle_dem_ny(dem), dfle_dem_z(dem), &g, &copy, &err);
    if (st == DFLE_OK)
        st = dfle_dem_fill(copy, NULL, &err);
    dfle_network_opts_default(&no);
    no.A_min = g.dx * g.dy;
    no.has_outlet = 1;
    no.E = E, no.N = N;
    if (st == DFLE_OK)
        st = dfle_dem_network(copy, &no, &net, &err);
    if (st == DFLE_OK) {
        const size_t m = dfle_profile_size(net);
        const double *Ec = dfle_profile_field(net, DFLE_PROFILE_E);
        const double *Nc = dfle_profile_field(net, DFLE_PROFILE_N);
        double given[2], snapped[2];
        for (size_t c = 0; c < n; c++)
            z[c] = NAN;
        for (size_t k = 0; k < m && st == DFLE_OK; k++) {
            size_t c;
            if ((st = dfle_dem_cell_at(dem, Ec[k], Nc[k], "cell", &c, &err)) == DFLE_OK)
                z[c] = dfle_dem_z(dem)[c];
        }
        dfle_profile_point(net, given, snapped);
        if (st == DFLE_OK)
            st = dfle_dem_cell_at(dem, snapped[0], snapped[1], "outlet", outlet, &err);
    }
    dfle_profile_free(net);
    dfle_dem_free(copy);
    if (st != DFLE_OK)
        dfle_lua_raise(L, &err);
    return z;
}

/* crs = "EPSG:32611" (any CRS GDAL reads) for a synthetic grid: where
 * its metres lie, kept as WKT (user value UV_CRS) for every file. */
static void set_crs(lua_State *L, lua_ls *u, int self)
{
    char *wkt;
    dfle_error err;
    if (lua_getfield(L, 1, "crs") == LUA_TNIL) {
        lua_pop(L, 1);
        return;
    }
    wkt = lua_newuserdatauv(L, DFLE_CRS_WKT_MAX, 0); /* scratch: nothing to free on a raise */
    if (dfle_crs_from_text(dfle_lua_check_string(L, -2, "landscape", "crs"), "landscape: crs",
                           1, wkt, DFLE_CRS_WKT_MAX, NULL, &err) != DFLE_OK)
        dfle_lua_raise(L, &err);
    u->crs = (char *)lua_pushstring(L, wkt);
    lua_setiuservalue(L, self, UV_CRS);
    lua_pop(L, 2);
}

int dfle_lua_landscape_new(lua_State *L)
{
    dfle_landscape_opts o;
    double nx = 0, ny = 0, dx = 30, dy = NAN, x0 = 0, y0 = NAN;
    double *z = NULL, *zbuf;
    size_t *outs = NULL, n_out = 0, n;
    lua_ls *u;
    dfle_dem *dem = NULL;
    dfle_error err;
    int base;

    luaL_checktype(L, 1, LUA_TTABLE);
    lua_settop(L, 1);
    dfle_landscape_opts_default(&o);
    {
        const dfle_lua_param p[] = {{"nx", &nx}, {"ny", &ny}, {"dx", &dx}, {"dy", &dy},
                                    {"A0", &o.A0}, {"k_w", &o.k_w}, {"b", &o.b},
                                    {"S_c", &o.S_c}, {"D", &o.D}, {"x0", &x0}, {"y0", &y0}};
        static const char *const others[] = {"z", "noise", "dem", "outlet", "outlets", "edges",
                                             "nodata", "fluvial", "router", "law", "combine",
                                             "hillslope", "cap_channels", "U", "K", "k_e", "k_df",
                                             "crs", NULL};
        dfle_lua_read_params(L, 1, "landscape", p, sizeof p / sizeof p[0], others);
    }
    /* The userdata first (valid and empty), so refs made below are
     * released by its __gc if anything raises. */
    u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_LANDSCAPE, UV_COUNT);
    u->L = L;
    u->ref_combine = LUA_NOREF;
    for (int k = 0; k < F_COUNT; k++)
        u->cb[k].ref = LUA_NOREF;
    base = lua_gettop(L); /* 2 */
    lua_newtable(L);      /* 3: the anchor of scratch arrays */

    /* The grid: a DEM, or nx x ny cells of dx x dy. */
    if (lua_getfield(L, 1, "dem") != LUA_TNIL) {
        double e[4];
        dem = dfle_lua_check_object(L, -1, "dfle.dem");
        if (dfle_dem_check_metric(dem, "a landscape", &err) != DFLE_OK)
            return dfle_lua_raise(L, &err);
        for (const char *const *k = (const char *const[]){"nx", "ny", "dx", "dy", "z", "noise",
                                                          "x0", "y0", "crs", NULL};
             *k != NULL; k++) {
            if (lua_getfield(L, 1, *k) != LUA_TNIL)
                luaL_error(L, "dfle.landscape: '%s' comes from the DEM; do not give it with "
                              "'dem'", *k);
            lua_pop(L, 1);
        }
        nx = (double)dfle_dem_nx(dem);
        ny = (double)dfle_dem_ny(dem);
        dx = dfle_dem_dx(dem);
        dy = dfle_dem_dy(dem);
        dfle_dem_extent(dem, e);
        x0 = e[0];
        y0 = e[3];
        if (dfle_dem_crs_wkt(dem) != NULL) {
            /* Kept as a Lua string (user value): nothing to free if
             * the constructor raises. */
            u->crs = (char *)lua_pushstring(L, dfle_dem_crs_wkt(dem));
            lua_setiuservalue(L, base, UV_CRS);
        }
        o.nodata = DFLE_DRAINAGE_OPEN;
    } else {
        if (nx == 0 || ny == 0)
            luaL_error(L, "dfle.landscape: give the grid: 'nx' and 'ny' (and 'dx'), or 'dem'");
        set_crs(L, u, base);
    }
    lua_pop(L, 1);
    dfle_lua_check_whole(L, nx, "landscape", "nx", 1, 1e8);
    dfle_lua_check_whole(L, ny, "landscape", "ny", 1, 1e8);
    if (isnan(dy))
        dy = dx;
    if (!(dx > 0 && dy > 0))
        luaL_error(L, "dfle.landscape: dx and dy must be > 0 m (got %f, %f)", dx, dy);
    /* Cells of 1e300 m made areas and volumes inf and NaN: sizes no
     * grid has (the DEM reader draws the same line at 1000 km), and a
     * grid whose far edge is no number, are refused. */
    if (!(dx >= 1e-6 && dx <= 1e6 && dy >= 1e-6 && dy <= 1e6))
        luaL_error(L, "dfle.landscape: dx and dy are cell sizes from 1e-06 to 1e+06 m (got %f, "
                      "%f)", dx, dy);
    if (!(isfinite(x0) && isfinite(nx * dx + x0) && (isnan(y0) || isfinite(y0 - ny * dy))))
        luaL_error(L, "dfle.landscape: x0 and y0 must be finite, and the grid's far corner too "
                      "(got x0 = %f, y0 = %f)", x0, y0);
    if (nx * ny > 2e9)
        luaL_error(L, "dfle.landscape: %f x %f cells is too many", nx, ny);
    o.nx = (size_t)nx;
    o.ny = (size_t)ny;
    o.dx = dx;
    o.dy = dy;
    n = o.nx * o.ny;
    u->x0 = x0;
    u->y0 = isnan(y0) ? (double)o.ny * dy : y0;
    o.x0 = u->x0;
    o.y0 = u->y0;
    /* The corner and the memory before anything of the grid's size is
     * allocated (its elevations here: 8 bytes a cell).  The estimate
     * asks only whether there will be debris flows (a router: the
     * default, unless router = false); the router is read below. */
    {
        static char router_to_come;
        dfle_landscape_opts pre = o;
        int t = lua_getfield(L, 1, "router");
        pre.router = t == LUA_TBOOLEAN && !lua_toboolean(L, -1)
                         ? NULL : (dfle_router *)(void *)&router_to_come;
        lua_pop(L, 1);
        if (dfle_landscape_check_grid(&pre, n * sizeof(double), &err) != DFLE_OK)
            return dfle_lua_raise(L, &err);
    }

    /* Initial elevations. */
    zbuf = lua_newuserdatauv(L, n * sizeof *zbuf, 0);
    anchor(L);
    lua_pop(L, 1);
    if (dem != NULL) {
        double E, N;
        memcpy(zbuf, dfle_dem_z(dem), n * sizeof *zbuf);
        lua_getfield(L, 1, "outlet");
        if (!lua_isnil(L, -1)) {
            size_t cell;
            if (!lua_istable(L, -1) || lua_rawgeti(L, -1, 1) != LUA_TNUMBER ||
                lua_rawgeti(L, -2, 2) != LUA_TNUMBER)
                luaL_error(L, "dfle.landscape: 'outlet' must be {E, N} in map coordinates (m)");
            E = lua_tonumber(L, -2), N = lua_tonumber(L, -1);
            lua_pop(L, 2);
            z = catchment(L, dem, E, N, &cell);
            memcpy(zbuf, z, n * sizeof *zbuf);
            lua_pop(L, 1);
            outs = lua_newuserdatauv(L, sizeof *outs, 0);
            anchor(L);
            lua_pop(L, 1);
            outs[0] = cell;
            n_out = 1;
            o.nodata = DFLE_DRAINAGE_CLOSED;
            for (int s = 0; s < 4; s++)
                o.edge[s] = DFLE_DRAINAGE_CLOSED;
        }
        lua_pop(L, 1);
    } else {
        int t = lua_getfield(L, 1, "z");
        if (t == LUA_TTABLE) {
            size_t m;
            double *v = dfle_lua_check_array(L, -1, "landscape: z", &m);
            if (m != n)
                luaL_error(L, "dfle.landscape: 'z' has %d values, the grid %d x %d = %d cells",
                           (int)m, (int)o.nx, (int)o.ny, (int)n);
            memcpy(zbuf, v, n * sizeof *zbuf);
            lua_pop(L, 1);
        } else if (t == LUA_TFUNCTION) {
            for (size_t c = 0; c < n; c++) {
                double x, y;
                centre(u, o.nx, dx, dy, c, &x, &y);
                lua_pushvalue(L, -1);
                lua_pushnumber(L, x);
                lua_pushnumber(L, y);
                lua_call(L, 2, 1);
                if (lua_type(L, -1) != LUA_TNUMBER)
                    luaL_error(L, "dfle.landscape: z(x, y) must return a number, got %s (at x "
                                  "= %f, y = %f)", dfle_lua_typename(L, -1), x, y);
                zbuf[c] = lua_tonumber(L, -1);
                lua_pop(L, 1);
            }
        } else if (t == LUA_TNIL) {
            for (size_t c = 0; c < n; c++)
                zbuf[c] = 0.0;
        } else {
            luaL_error(L, "dfle.landscape: 'z' must be an array of nx * ny elevations or a "
                          "function z(x, y), got %s", dfle_lua_typename(L, -1));
        }
        lua_pop(L, 1);
        /* Seeded noise: noise = { amplitude = 1, seed = 1 } (or true);
         * the default start when z is not given. */
        {
            int tz = lua_getfield(L, 1, "z");
            t = lua_getfield(L, 1, "noise");
            if (t != LUA_TNIL || tz == LUA_TNIL) {
                double amp = 1.0, seed = 1.0;
                uint64_t sd;
                if (t == LUA_TTABLE) {
                    const dfle_lua_param p[] = {{"amplitude", &amp}, {"seed", &seed}};
                    dfle_lua_read_params(L, lua_gettop(L), "landscape: noise", p, 2, NULL);
                } else if (t != LUA_TNIL && t != LUA_TBOOLEAN) {
                    luaL_error(L, "dfle.landscape: 'noise' must be { amplitude =, seed = } or "
                                  "true, got %s", dfle_lua_typename(L, -1));
                }
                if (t == LUA_TBOOLEAN && !lua_toboolean(L, -1))
                    amp = 0.0;
                if (!(amp >= 0))
                    luaL_error(L, "dfle.landscape: noise amplitude must be >= 0 m");
                sd = 0x9E3779B97F4A7C15ull ^
                     (uint64_t)dfle_lua_check_whole(L, seed, "landscape", "noise seed", 0, 1e15);
                for (int k = 0; k < 8; k++)
                    (void)noise_next(&sd);
                for (size_t c = 0; c < n; c++)
                    zbuf[c] += amp * noise_next(&sd);
            }
        }
        lua_settop(L, base + 1);
    }
    o.z = zbuf;
    u->nx = o.nx, u->ny = o.ny, u->dx = dx, u->dy = dy;
    u->zmask = zbuf;
    lua_settop(L, base + 1);

    /* Edges and outlets. */
    if (lua_getfield(L, 1, "edges") == LUA_TSTRING) {
        enum dfle_drainage_edge e = check_edge(L, -1, "'edges'");
        for (int s = 0; s < 4; s++)
            o.edge[s] = e;
    } else if (lua_istable(L, -1)) {
        static const char *const sides[] = {"north", "east", "south", "west", NULL};
        lua_pushnil(L);
        while (lua_next(L, -2)) {
            int k = -1;
            if (lua_type(L, -2) == LUA_TSTRING)
                for (int s = 0; sides[s] != NULL; s++)
                    if (strcmp(lua_tostring(L, -2), sides[s]) == 0)
                        k = s;
            if (k < 0)
                luaL_error(L, "dfle.landscape: 'edges' keys are north, east, south, west");
            o.edge[k] = check_edge(L, -1, sides[k]);
            lua_pop(L, 1);
        }
    } else if (!lua_isnil(L, -1)) {
        luaL_error(L, "dfle.landscape: 'edges' must be a kind (\"base_level\", \"closed\", "
                      "\"open\") or a table { north =, east =, south =, west = }");
    }
    lua_pop(L, 1);
    if (lua_getfield(L, 1, "nodata") != LUA_TNIL)
        o.nodata = check_edge(L, -1, "'nodata'");
    lua_pop(L, 1);
    if (lua_getfield(L, 1, "outlets") != LUA_TNIL) {
        size_t m;
        if (!lua_istable(L, -1))
            luaL_error(L, "dfle.landscape: 'outlets' must be a list of {E, N} points");
        m = lua_rawlen(L, -1);
        outs = lua_newuserdatauv(L, (m ? m : 1) * sizeof *outs, 0);
        anchor(L);
        lua_pop(L, 1);
        for (size_t k = 0; k < m; k++) {
            double E, N, col, row;
            if (lua_rawgeti(L, -1, (lua_Integer)k + 1) != LUA_TTABLE ||
                lua_rawgeti(L, -1, 1) != LUA_TNUMBER || lua_rawgeti(L, -2, 2) != LUA_TNUMBER)
                luaL_error(L, "dfle.landscape: outlets[%d] must be {E, N}", (int)k + 1);
            E = lua_tonumber(L, -2), N = lua_tonumber(L, -1);
            col = floor((E - u->x0) / dx);
            row = floor((u->y0 - N) / dy);
            if (!(col >= 0 && col < nx && row >= 0 && row < ny))
                luaL_error(L, "dfle.landscape: outlets[%d] (%f, %f) is off the grid", (int)k + 1,
                           E, N);
            outs[k] = (size_t)row * o.nx + (size_t)col;
            lua_pop(L, 3);
        }
        n_out = m;
    }
    lua_pop(L, 1);
    o.outlets = outs;
    o.n_outlets = n_out;

    /* Hillslopes. */
    if (lua_getfield(L, 1, "hillslope") != LUA_TNIL) {
        static const char *const rules[] = {"threshold", "diffusion", "uplift", NULL};
        o.hillslope = dfle_lua_check_option(L, -1, "landscape", "hillslope", rules);
    }
    lua_pop(L, 1);
    if (lua_getfield(L, 1, "cap_channels") != LUA_TNIL) {
        if (!lua_isboolean(L, -1))
            luaL_error(L, "dfle.landscape: parameter 'cap_channels' must be a boolean (got %s)",
                       luaL_typename(L, -1));
        o.cap_channels = lua_toboolean(L, -1);
    }
    lua_pop(L, 1);

    /* Components: the model's defaults (Fig. 9), false switches off. */
    {
        int comp = lua_gettop(L) + 1;
        push_component(L, 1, "fluvial", DFLE_LUA_FLUVIAL, "fluvial", "stochastic_threshold");
        push_component(L, 1, "router", DFLE_LUA_ROUTER, "router", "empirical");
        if (lua_isnil(L, comp + 1)) {
            /* law = false says the same as router = false: no debris flows. */
            int t = lua_getfield(L, 1, "law");
            if (t != LUA_TNIL && !(t == LUA_TBOOLEAN && !lua_toboolean(L, -1)))
                luaL_error(L, "dfle.landscape: 'law' given but router = false (no debris flows)");
            lua_pop(L, 1);
            lua_pushnil(L);
        } else {
            push_component(L, 1, "law", DFLE_LUA_LAW, "law", "power");
        }
        for (int k = 0; k < 3; k++) {
            lua_pushvalue(L, comp + k);
            lua_setiuservalue(L, base, UV_FLUVIAL + k);
        }
        o.fluvial = lua_isnil(L, comp) ? NULL : dfle_lua_check_fluvial(L, comp);
        o.router = lua_isnil(L, comp + 1) ? NULL : dfle_lua_check_router(L, comp + 1);
        o.law = lua_isnil(L, comp + 2) ? NULL : dfle_lua_check_law(L, comp + 2);

        /* Fields in space.  K and k_e scale the fluvial K, k_df the
         * law's k_df. */
        read_field(L, u, 1, "U", "U (uplift, m/yr)", F_U, &o.U, o.nx, o.ny, 1.0);
        if (lua_getfield(L, 1, "K") != LUA_TNIL && lua_getfield(L, 1, "k_e") != LUA_TNIL)
            luaL_error(L, "dfle.landscape: give 'K' or 'k_e', not both");
        lua_settop(L, comp + 2);
        if (lua_getfield(L, 1, "k_e") != LUA_TNIL && lua_getfield(L, 1, "fluvial") != LUA_TNIL)
            luaL_error(L, "dfle.landscape: 'k_e' scales the default fluvial law (Appendix A, K "
                          "proportional to k_e = 5e-14); with your own fluvial law give 'K'");
        lua_settop(L, comp + 2);
        if (o.fluvial == NULL) {
            if (lua_getfield(L, 1, "K") != LUA_TNIL || lua_getfield(L, 1, "k_e") != LUA_TNIL)
                luaL_error(L, "dfle.landscape: 'K'/'k_e' given but fluvial = false");
            lua_settop(L, comp + 2);
        } else {
            double Kl = dfle_fluvial_K(o.fluvial);
            read_field(L, u, 1, "K", "K (fluvial erodibility)", F_K, &o.K_scale, o.nx, o.ny,
                       Kl > 0 ? Kl : 1.0);
            if (u->cb[F_K].ref == LUA_NOREF && o.K_scale.grid == NULL && o.K_scale.value == 1.0)
                read_field(L, u, 1, "k_e", "k_e (fluvial erodibility)", F_K, &o.K_scale, o.nx,
                           o.ny, 5e-14);
        }
        if (lua_getfield(L, 1, "k_df") != LUA_TNIL) {
            dfle_param p[32];
            size_t np = o.law != NULL ? dfle_law_params(o.law, p, 32) : 0;
            double kdf = NAN;
            for (size_t k = 0; k < np && k < 32 && np != (size_t)-1; k++)
                if (strcmp(p[k].name, "k_df") == 0)
                    kdf = p[k].value;
            if (o.law == NULL)
                luaL_error(L, "dfle.landscape: 'k_df' given but router = false");
            if (!(kdf > 0))
                luaL_error(L, "dfle.landscape: 'k_df' in space scales the law's own k_df, and "
                              "law '%s' has none", dfle_law_name(o.law));
            lua_pop(L, 1);
            read_field(L, u, 1, "k_df", "k_df (debris-flow erodibility)", F_DF, &o.df_scale, o.nx,
                       o.ny, kdf);
        } else {
            lua_pop(L, 1);
        }

        /* How joined debris flows combine. */
        if (lua_getfield(L, 1, "combine") == LUA_TSTRING) {
            static const char *const rules[] = {"any", "count", NULL};
            o.df_combine = dfle_lua_check_option(L, -1, "landscape", "combine", rules);
        } else if (lua_isfunction(L, -1)) {
            lua_pushvalue(L, -1);
            u->ref_combine = luaL_ref(L, LUA_REGISTRYINDEX);
            o.df_combine = DFLE_DF_CUSTOM;
            o.df_frequency = combine_fn;
            o.df_frequency_ud = u;
        } else if (!lua_isnil(L, -1)) {
            luaL_error(L, "dfle.landscape: 'combine' must be \"any\", \"count\" or a function "
                          "(count, A) -> factor, got %s", dfle_lua_typename(L, -1));
        }
        lua_pop(L, 1);

        if (dfle_landscape_new(&o, &u->ls, &err) != DFLE_OK)
            return dfle_lua_ls_raise(L, u, &err);
        u->zmask = dfle_landscape_z(u->ls); /* NoData stays NoData */
        for (int k = 0; k < 3; k++)
            if (!lua_isnil(L, comp + k))
                dfle_lua_hold(L, comp + k);
    }
    lua_settop(L, base);
    return 1;
}
