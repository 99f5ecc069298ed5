/*
 * lua_dem.c - dfle.dem: DEMs, channel profiles and networks from Lua.
 *
 *   local dem = dfle.dem.read("srtm_bigtujunga30m_utm11.tif")
 *   dem:fill()
 *   local p = dem:profile{ outlet = {396887, 3799338} }
 *   local fit = dfle.fit_slope_area(p)
 *   p:write_csv("profile.csv")
 *   local ch = p:channel{ dx = 5 }          -- a model channel on A(x)
 *   local net = dem:network{ A_min = 1e5, outlet = {396887, 3799338} }
 *
 * Two userdata types: "dfle.dem" (the grid, filled and routed in place)
 * and "dfle.profile" (a profile or network: arrays copied out of the
 * DEM, so it outlives the DEM).  dfle.fit_slope_area and
 * dfle.plot.slope_area take a profile through its slope_area() method
 * (see dfle_lua_slope_area in lua_util.c).
 */
#include "lua/analysis/lua_dem.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dfle/raster.h"

static dfle_dem *check_dem(lua_State *L, int arg)
{
    return dfle_lua_check_object(L, arg, DFLE_LUA_DEM);
}

static dfle_profile *check_profile(lua_State *L, int arg)
{
    return dfle_lua_check_object(L, arg, DFLE_LUA_PROFILE);
}

static void set_number(lua_State *L, const char *k, double v)
{
    lua_pushnumber(L, v);
    lua_setfield(L, -2, k);
}

/* Push {E, N} (also as .E, .N) or nil when not finite. */
static void push_point(lua_State *L, double E, double N)
{
    if (!(isfinite(E) && isfinite(N))) {
        lua_pushnil(L);
        return;
    }
    lua_createtable(L, 2, 2);
    lua_pushnumber(L, E), lua_rawseti(L, -2, 1);
    lua_pushnumber(L, N), lua_rawseti(L, -2, 2);
    set_number(L, "E", E);
    set_number(L, "N", N);
}

/* Field `key` of the options table: {E, N} in map units, finite. */
int dfle_lua_dem_read_point(lua_State *L, int opts, const char *key, const char *fn, double *E,
                            double *N)
{
    int t = lua_getfield(L, opts, key);
    if (t == LUA_TNIL) {
        lua_pop(L, 1);
        return 0;
    }
    if (t != LUA_TTABLE || lua_rawlen(L, -1) != 2 || lua_rawgeti(L, -1, 1) != LUA_TNUMBER ||
        lua_rawgeti(L, -2, 2) != LUA_TNUMBER)
        return luaL_error(L, "dfle.%s: parameter '%s' must be {E, N}, two map coordinates in m, "
                             "got %s", fn, key, t == LUA_TTABLE ? "another table" :
                             dfle_lua_typename(L, -1));
    *E = lua_tonumber(L, -2);
    *N = lua_tonumber(L, -1);
    if (!(isfinite(*E) && isfinite(*N)))
        luaL_error(L, "dfle.%s: parameter '%s' must hold finite coordinates (got %s, %s)", fn, key,
                   dfle_lua_number_text(L, *E), dfle_lua_number_text(L, *N));
    lua_pop(L, 3);
    return 1;
}

/* A key the chosen mode ignores is an error, never silently dropped. */
static void forbid(lua_State *L, int opts, const char *key, const char *fn, const char *why)
{
    if (lua_getfield(L, opts, key) != LUA_TNIL)
        luaL_error(L, "dfle.%s: '%s' %s", fn, key, why);
    lua_pop(L, 1);
}

/* The snapping radius [m]: absent (NaN) means the default. */
static double check_radius(lua_State *L, double radius, const char *fn)
{
    if (isnan(radius))
        return -1.0;
    if (radius < 0)
        luaL_error(L, "dfle.%s: radius must be >= 0 m (got %s)", fn,
                   dfle_lua_number_text(L, radius));
    return radius;
}

/* ---------------------------------------------------------------- */
/* dfle.dem                                                         */
/* ---------------------------------------------------------------- */

/* dfle.dem.read(path [, {nodata =, crs =, band =}]) */
static int l_dem_read(lua_State *L)
{
    static const char *const other[] = {"crs", NULL};
    const char *path = dfle_lua_check_string(L, 1, "dem.read", "the path");
    double nodata = NAN, band = 1;
    const dfle_lua_param params[] = {{"nodata", &nodata}, {"band", &band}};
    dfle_dem_read_opts o;
    dfle_lua_dem *u;
    dfle_error err;

    memset(&o, 0, sizeof o);
    if (!lua_isnoneornil(L, 2))
        luaL_checktype(L, 2, LUA_TTABLE);
    dfle_lua_read_params(L, 2, "dem.read", params, 2, other);
    o.band = (int)dfle_lua_check_whole(L, band, "dem.read", "band", 1, 1e6);
    if (!isnan(nodata)) {
        o.set_nodata = 1;
        o.nodata = nodata;
    }
    if (lua_istable(L, 2)) {
        int t = lua_getfield(L, 2, "crs");
        if (t != LUA_TNIL && t != LUA_TSTRING)
            luaL_error(L, "dfle.dem.read: parameter 'crs' must be a string such as "
                          "\"EPSG:32611\", got %s", dfle_lua_typename(L, -1));
        if (t == LUA_TSTRING) /* kept alive by the options table */
            o.crs = dfle_lua_check_string(L, -1, "dem.read", "crs");
    }
    u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_DEM, 0);
    if (dfle_dem_read(path, &o, &u->dem, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    {
        char msg[512];
        if (dfle_dem_check_plausible(u->dem, msg, sizeof msg)) {
            lua_pushfstring(L, "%s: %s", path, msg);
            dfle_lua_warn(L, "dem.read", lua_tostring(L, -1));
            lua_pop(L, 1);
        }
    }
    return 1;
}

/* dem:fill() -> {raised =, max_raise =, volume =} */
static int l_dem_fill(lua_State *L)
{
    dfle_dem *dem = check_dem(L, 1);
    dfle_dem_fill_stats st;
    dfle_error err;
    if (dfle_dem_fill(dem, &st, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    lua_createtable(L, 0, 3);
    lua_pushinteger(L, (lua_Integer)st.raised), lua_setfield(L, -2, "raised");
    set_number(L, "max_raise", st.max_raise);
    set_number(L, "volume", st.volume);
    return 1;
}

/* dem:flow() -> dem: D8, flats and drainage area now (else on demand). */
static int l_dem_flow(lua_State *L)
{
    dfle_dem *dem = check_dem(L, 1);
    dfle_error err;
    if (dfle_dem_route(dem, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    lua_settop(L, 1);
    return 1;
}


/* dem:write_geotiff(path [, { layers = {...}, A_min = }]): the DEM's
 * products as bands of one GeoTIFF on the DEM's grid and CRS. */
static int l_dem_write_geotiff(lua_State *L)
{
    static const char *const fn = "dem:write_geotiff";
    static const char *const all[] = {"z", "area", "d8", "slope", "channels", NULL};
    static const char *const other[] = {"layers", NULL};
    dfle_dem *dem = check_dem(L, 1);
    const char *path = dfle_lua_check_string(L, 2, fn, "the path");
    const char *names[5];
    dfle_raster_band bands[5];
    dfle_record *rec;
    double A_min = NAN, ext[4];
    const dfle_lua_param params[] = {{"A_min", &A_min}};
    size_t nb = 0, n = dfle_dem_nx(dem) * dfle_dem_ny(dem);
    dfle_raster_geo geo;
    dfle_error err;

    lua_settop(L, 3);
    if (!lua_isnil(L, 3))
        luaL_checktype(L, 3, LUA_TTABLE);
    dfle_lua_read_params(L, 3, fn, params, 1, other);
    if (lua_istable(L, 3) && lua_getfield(L, 3, "layers") != LUA_TNIL) {
        if (!lua_istable(L, -1) || lua_rawlen(L, -1) == 0 || lua_rawlen(L, -1) > 5)
            luaL_error(L, "dfle.%s: 'layers' must be a list of 1 to 5 names among z, area, d8, "
                          "slope, channels", fn);
        for (lua_Integer k = 1; k <= (lua_Integer)lua_rawlen(L, -1); k++) {
            lua_rawgeti(L, -1, k);
            names[nb++] = all[dfle_lua_check_option(L, -1, fn, "a layer", all)];
            lua_pop(L, 1);
        }
    } else {
        names[nb++] = "z", names[nb++] = "area", names[nb++] = "d8";
    }
    if (dfle_dem_route(dem, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    for (size_t k = 0; k < nb; k++) {
        const double *z = dfle_dem_z(dem), *A = dfle_dem_area(dem);
        const unsigned char *dir = dfle_dem_dir(dem);
        double *b;
        for (size_t j = 0; j < k; j++)
            if (strcmp(names[j], names[k]) == 0)
                luaL_error(L, "dfle.%s: layer '%s' is listed twice", fn, names[k]);
        bands[k].name = names[k];
        if (strcmp(names[k], "z") == 0) {
            bands[k].values = z;
            bands[k].units = "m";
            continue;
        }
        if (strcmp(names[k], "area") == 0) {
            bands[k].values = A;
            bands[k].units = "m^2";
            continue;
        }
        b = lua_newuserdatauv(L, n * sizeof *b, 0); /* kept on the stack until written */
        bands[k].values = b;
        bands[k].units = strcmp(names[k], "slope") == 0 ? "-" : NULL; /* codes, a mask */
        if (strcmp(names[k], "channels") == 0 && !(A_min > 0))
            luaL_error(L, "dfle.%s: layer 'channels' needs A_min (m^2, > 0): the drainage area "
                          "where channels begin", fn);
        for (size_t i = 0; i < n; i++) {
            long long r = dfle_dem_receiver(dem, i);
            if (isnan(z[i])) {
                b[i] = NAN;
            } else if (strcmp(names[k], "d8") == 0) {
                /* ESRI's codes: 1 E, 2 SE, 4 S, 8 SW, 16 W, 32 NW, 64 N, 128 NE; 0 none */
                b[i] = dir[i] < 8 ? (double)(1u << dir[i]) : 0.0;
            } else if (strcmp(names[k], "slope") == 0) {
                double Ei, Ni, Er, Nr;
                if (r < 0) {
                    b[i] = NAN;
                } else {
                    dfle_dem_cell_centre(dem, i, &Ei, &Ni);
                    dfle_dem_cell_centre(dem, (size_t)r, &Er, &Nr);
                    b[i] = (z[i] - z[r]) / hypot(Ei - Er, Ni - Nr);
                }
            } else {
                b[i] = A[i] >= A_min ? 1.0 : 0.0;
            }
        }
    }
    dfle_dem_extent(dem, ext);
    geo = (dfle_raster_geo){ext[0], ext[3], dfle_dem_dx(dem), dfle_dem_dy(dem),
                            dfle_dem_crs_wkt(dem)};
    rec = dfle_lua_push_record(L, "DEM products, one band each");
    dfle_dem_describe(dem, rec);
    if (A_min > 0)
        dfle_record_number(rec, "A_min", A_min, "m^2");
    if (dfle_raster_write_geotiff(path, dfle_dem_nx(dem), dfle_dem_ny(dem), &geo, nb, bands, rec,
                                  &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path);
    dfle_lua_note(L, DFLE_LUA_DETAIL, "wrote %s (%zu band%s)", path, nb, nb == 1 ? "" : "s");
    lua_settop(L, 1);
    return 1;
}
/* dem:at(E, N) -> z, A (nil, nil on NoData) */
static int l_dem_at(lua_State *L)
{
    dfle_dem *dem = check_dem(L, 1);
    double E = luaL_checknumber(L, 2), N = luaL_checknumber(L, 3);
    size_t i;
    dfle_error err;

    if (dfle_dem_cell_at(dem, E, N, "point", &i, &err) != DFLE_OK ||
        dfle_dem_route(dem, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    if (isnan(dfle_dem_z(dem)[i])) {
        lua_pushnil(L);
        lua_pushnil(L);
    } else {
        lua_pushnumber(L, dfle_dem_z(dem)[i]);
        lua_pushnumber(L, dfle_dem_area(dem)[i]);
    }
    return 2;
}

/* dem:profile{ outlet = {E, N}, radius =, A_min =, ds =, dz = }
 * dem:profile{ head = {E, N}, A_max =, ds =, dz = } */
static int l_dem_profile(lua_State *L)
{
    static const char *const other[] = {"outlet", "head", NULL};
    static const char *const fn = "dem:profile";
    dfle_dem *dem = check_dem(L, 1);
    dfle_profile_opts o;
    double radius = NAN, A_min = 0, A_max = 0, ds = 0, dz = 0;
    const dfle_lua_param params[] = {{"radius", &radius}, {"A_min", &A_min},
                                     {"A_max", &A_max},   {"ds", &ds},
                                     {"dz", &dz}};
    int has_outlet, has_head;
    dfle_lua_profile *u;
    dfle_error err;

    luaL_checktype(L, 2, LUA_TTABLE);
    dfle_lua_read_params(L, 2, fn, params, sizeof params / sizeof params[0], other);
    dfle_profile_opts_default(&o);
    has_outlet = dfle_lua_dem_read_point(L, 2, "outlet", fn, &o.E, &o.N);
    if ((has_head = dfle_lua_dem_read_point(L, 2, "head", fn, &o.E, &o.N)) && has_outlet)
        luaL_error(L, "dfle.%s: give 'outlet' (trace upstream) or 'head' (trace downstream), "
                      "not both", fn);
    if (!has_outlet && !has_head)
        luaL_error(L, "dfle.%s: parameter 'outlet' or 'head' ({E, N} in m) is required", fn);
    if (has_head) {
        forbid(L, 2, "radius", fn, "applies to an outlet only (a head is not snapped)");
        forbid(L, 2, "A_min", fn, "applies to an outlet only; with 'head' use A_max");
    } else {
        forbid(L, 2, "A_max", fn, "applies to a head only; with 'outlet' use A_min");
    }
    o.from_head = has_head;
    o.radius = check_radius(L, radius, fn);
    o.A_min = A_min;
    o.A_max = A_max;
    o.slope.ds = ds;
    o.slope.dz = dz;
    u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_PROFILE, 0);
    if (dfle_dem_profile(dem, &o, &u->p, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

/* dem:network{ A_min =, outlet = {E, N}, radius =, ds =, dz = } */
static int l_dem_network(lua_State *L)
{
    static const char *const other[] = {"outlet", NULL};
    static const char *const fn = "dem:network";
    dfle_dem *dem = check_dem(L, 1);
    dfle_network_opts o;
    double radius = NAN, A_min = NAN, ds = 0, dz = 0;
    const dfle_lua_param params[] = {{"A_min", &A_min}, {"radius", &radius}, {"ds", &ds},
                                     {"dz", &dz}};
    dfle_lua_profile *u;
    dfle_error err;

    luaL_checktype(L, 2, LUA_TTABLE);
    dfle_lua_read_params(L, 2, fn, params, sizeof params / sizeof params[0], other);
    if (isnan(A_min))
        luaL_error(L, "dfle.%s: parameter 'A_min' (m^2, the smallest drainage area of a channel "
                      "cell) is required", fn);
    dfle_network_opts_default(&o);
    o.A_min = A_min;
    o.has_outlet = dfle_lua_dem_read_point(L, 2, "outlet", fn, &o.E, &o.N);
    if (!o.has_outlet)
        forbid(L, 2, "radius", fn, "applies to an outlet only");
    o.radius = check_radius(L, radius, fn);
    o.slope.ds = ds;
    o.slope.dz = dz;
    u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_PROFILE, 0);
    if (dfle_dem_network(dem, &o, &u->p, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

static int l_dem_property(lua_State *L)
{
    dfle_dem *dem = check_dem(L, 1);
    const char *key = lua_tostring(L, 2);
    double e[4];

    if (strcmp(key, "nx") == 0)
        lua_pushinteger(L, (lua_Integer)dfle_dem_nx(dem));
    else if (strcmp(key, "ny") == 0)
        lua_pushinteger(L, (lua_Integer)dfle_dem_ny(dem));
    else if (strcmp(key, "n") == 0)
        lua_pushinteger(L, (lua_Integer)(dfle_dem_nx(dem) * dfle_dem_ny(dem)));
    else if (strcmp(key, "dx") == 0)
        lua_pushnumber(L, dfle_dem_dx(dem));
    else if (strcmp(key, "dy") == 0)
        lua_pushnumber(L, dfle_dem_dy(dem));
    else if (strcmp(key, "extent") == 0) {
        dfle_dem_extent(dem, e);
        lua_createtable(L, 0, 4);
        set_number(L, "E_min", e[0]);
        set_number(L, "E_max", e[1]);
        set_number(L, "N_min", e[2]);
        set_number(L, "N_max", e[3]);
    } else if (strcmp(key, "crs") == 0)
        lua_pushstring(L, dfle_dem_crs_name(dem)); /* nil when unknown */
    else if (strcmp(key, "crs_wkt") == 0)
        lua_pushstring(L, dfle_dem_crs_wkt(dem));
    else if (strcmp(key, "epsg") == 0) {
        if (dfle_dem_epsg(dem) > 0)
            lua_pushinteger(L, dfle_dem_epsg(dem));
        else
            lua_pushnil(L);
    } else if (strcmp(key, "geographic") == 0)
        lua_pushboolean(L, dfle_dem_is_geographic(dem));
    else if (strcmp(key, "path") == 0)
        lua_pushstring(L, dfle_dem_path(dem));
    else if (strcmp(key, "nodata_cells") == 0)
        lua_pushinteger(L, (lua_Integer)dfle_dem_nodata_count(dem));
    else if (strcmp(key, "filled") == 0)
        lua_pushboolean(L, dfle_dem_is_filled(dem));
    else if (strcmp(key, "routed") == 0)
        lua_pushboolean(L, dfle_dem_is_routed(dem));
    else if (strcmp(key, "sinks") == 0 || strcmp(key, "flats") == 0) {
        if (!dfle_dem_is_routed(dem))
            lua_pushnil(L);
        else
            lua_pushinteger(L, (lua_Integer)(key[0] == 's' ? dfle_dem_sink_count(dem)
                                                           : dfle_dem_flat_count(dem)));
    } else if (strcmp(key, "z_min") == 0 || strcmp(key, "z_max") == 0) {
        const double *z = dfle_dem_z(dem);
        size_t n = dfle_dem_nx(dem) * dfle_dem_ny(dem);
        double v = NAN;
        for (size_t i = 0; i < n; i++)
            if (!isnan(z[i]) && (isnan(v) || (key[2] == 'm' && key[3] == 'i' ? z[i] < v
                                                                             : z[i] > v)))
                v = z[i];
        lua_pushnumber(L, v); /* at least one cell has data */
    } else
        return 0; /* not a field: __index says so */
    return 1;
}

static void dem_describe(lua_State *L, void *obj)
{
    const dfle_dem *dem = obj;
    char buf[512];
    double e[4];
    dfle_dem_extent(dem, e);
    snprintf(buf, sizeof buf, "dfle.dem(%zu x %zu cells of %g x %g m, E %.0f..%.0f, N %.0f..%.0f, "
             "%s%s)", dfle_dem_nx(dem), dfle_dem_ny(dem), dfle_dem_dx(dem), dfle_dem_dy(dem),
             e[0], e[1], e[2], e[3], dfle_dem_crs_name(dem) ? dfle_dem_crs_name(dem) : "no CRS",
             dfle_dem_is_filled(dem) ? ", filled" : "");
    lua_pushstring(L, buf);
}

static void dem_free(void *obj) { dfle_dem_free(obj); }

/* ---------------------------------------------------------------- */
/* dfle.profile                                                     */
/* ---------------------------------------------------------------- */

static const char *const profile_fields[] = {"E", "N", "x", "d", "z", "A", "S", "receiver",
                                             NULL};

static int l_profile_get(lua_State *L)
{
    dfle_profile *p = check_profile(L, 1);
    const char *name = dfle_lua_check_string(L, 2, "dem:get", "the field name");
    size_t n = dfle_profile_size(p);

    for (int k = 0; profile_fields[k] != NULL; k++) {
        if (strcmp(name, profile_fields[k]) != 0)
            continue;
        if (k == DFLE_PROFILE_NFIELDS) {
            const size_t *r = dfle_profile_receiver(p);
            lua_createtable(L, (int)n, 0);
            for (size_t i = 0; i < n; i++) {
                lua_pushinteger(L, (lua_Integer)r[i]);
                lua_rawseti(L, -2, (lua_Integer)i + 1);
            }
        } else {
            dfle_lua_push_array(L, dfle_profile_field(p, (enum dfle_profile_field)k), n);
        }
        return 1;
    }
    return luaL_error(L, "dfle.profile:get: no field '%s' (fields: E, N, x, d, z, A, S, "
                         "receiver)", name);
}

/* p:slope_area() -> {A = {...}, S = {...}}: the pairs the fit and the
 * plot use (every cell; see doc/dem.md for how S is measured). */
static int l_profile_slope_area(lua_State *L)
{
    dfle_profile *p = check_profile(L, 1);
    size_t n = dfle_profile_size(p);
    lua_createtable(L, 0, 2);
    dfle_lua_push_array(L, dfle_profile_field(p, DFLE_PROFILE_A), n);
    lua_setfield(L, -2, "A");
    dfle_lua_push_array(L, dfle_profile_field(p, DFLE_PROFILE_S), n);
    lua_setfield(L, -2, "S");
    return 1;
}

/* p:write_csv(path [, { record = true | false | "p.json" }]) */
static int l_profile_write_csv(lua_State *L)
{
    static const char *const keys[] = {"record", NULL};
    dfle_profile *p = check_profile(L, 1);
    const char *path = dfle_lua_check_string(L, 2, "profile:write_csv", "the path");
    dfle_record *rec;
    const char *jpath;
    dfle_error err;

    lua_settop(L, 3);
    if (!lua_isnil(L, 3)) {
        luaL_checktype(L, 3, LUA_TTABLE);
        dfle_lua_read_params(L, 3, "profile:write_csv", NULL, 0, keys);
    }
    rec = dfle_lua_push_record(L, dfle_profile_is_network(p)
                                      ? "DEM channel network: one row per cell, each before "
                                        "its receiver"
                                      : "DEM channel profile: one row per cell, from the head "
                                        "to the outlet");
    dfle_profile_describe(p, rec);
    jpath = dfle_lua_record_path(L, rec, 3, path, "profile:write_csv");
    if (dfle_profile_write_csv(p, path, rec, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_record_done(L, rec, path, jpath);
    dfle_lua_note(L, DFLE_LUA_DETAIL, "wrote %s (%zu cells)", path, dfle_profile_size(p));
    lua_settop(L, 1);
    return 1;
}

/* p:channel{ dx = 5, k_w = 0.05, b = 0.3 } -> dfle.channel */
static int l_profile_channel(lua_State *L)
{
    dfle_profile *p = check_profile(L, 1);
    dfle_channel_opts co;
    double dx, k_w, b;
    dfle_lua_channel *u;
    dfle_error err;

    dfle_channel_opts_default(&co);
    dx = co.dx;
    k_w = co.k_w;
    b = co.b;
    {
        const dfle_lua_param params[] = {{"dx", &dx}, {"k_w", &k_w}, {"b", &b}};
        if (!lua_isnoneornil(L, 2))
            luaL_checktype(L, 2, LUA_TTABLE);
        dfle_lua_read_params(L, 2, "profile:channel", params, 3, NULL);
    }
    u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_CHANNEL, 0);
    if (dfle_profile_channel(p, dx, k_w, b, &u->ch, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

/* p:main_stem() -> dfle.profile: a network's main stem (a profile's copy) */
static int l_profile_main_stem(lua_State *L)
{
    dfle_profile *p = check_profile(L, 1);
    dfle_lua_profile *u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_PROFILE, 0);
    dfle_error err;
    if (dfle_profile_main_stem(p, &u->p, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

static int l_profile_property(lua_State *L)
{
    dfle_profile *p = check_profile(L, 1);
    const char *key = lua_tostring(L, 2);
    size_t n = dfle_profile_size(p);
    const double *A = dfle_profile_field(p, DFLE_PROFILE_A);
    const double *D = dfle_profile_field(p, DFLE_PROFILE_D);
    double given[2], snapped[2];
    dfle_slope_opts s = dfle_profile_slope(p);

    dfle_profile_point(p, given, snapped);
    if (strcmp(key, "n") == 0)
        lua_pushinteger(L, (lua_Integer)n);
    else if (strcmp(key, "kind") == 0)
        lua_pushstring(L, dfle_profile_is_network(p) ? "network" : "profile");
    else if (strcmp(key, "length") == 0 || strcmp(key, "A_max") == 0 ||
             strcmp(key, "A_min") == 0) {
        /* Longest flow distance, largest and smallest area. */
        const double *v = key[0] == 'l' ? D : A;
        double m = v[0];
        for (size_t i = 1; i < n; i++)
            if (key[0] == 'A' && key[2] == 'm' && key[3] == 'i' ? v[i] < m : v[i] > m)
                m = v[i];
        lua_pushnumber(L, m);
    } else if (strcmp(key, "outlet") == 0 || strcmp(key, "head") == 0) {
        int is_head = key[0] == 'h';
        if (dfle_profile_is_network(p)) {
            if (is_head)
                lua_pushnil(L);
            else
                push_point(L, snapped[0], snapped[1]);
        } else {
            size_t i = is_head ? 0 : n - 1;
            push_point(L, dfle_profile_field(p, DFLE_PROFILE_E)[i],
                       dfle_profile_field(p, DFLE_PROFILE_N)[i]);
        }
    } else if (strcmp(key, "given") == 0)
        push_point(L, given[0], given[1]);
    else if (strcmp(key, "snap_distance") == 0) {
        if (isfinite(given[0]))
            lua_pushnumber(L, hypot(snapped[0] - given[0], snapped[1] - given[1]));
        else
            lua_pushnil(L);
    } else if (strcmp(key, "ds") == 0 || strcmp(key, "dz") == 0) {
        double v = key[1] == 's' ? s.ds : s.dz;
        if (v > 0)
            lua_pushnumber(L, v);
        else
            lua_pushnil(L);
    } else
        return 0; /* not a field: __index says so */
    return 1;
}

static int l_profile_len(lua_State *L)
{
    lua_pushinteger(L, (lua_Integer)dfle_profile_size(check_profile(L, 1)));
    return 1;
}

static void profile_describe(lua_State *L, void *obj)
{
    const dfle_profile *p = obj;
    const size_t n = dfle_profile_size(p);
    const double *A = dfle_profile_field(p, DFLE_PROFILE_A);
    const double *D = dfle_profile_field(p, DFLE_PROFILE_D);
    double Amin, Amax, len = 0;
    char buf[256];
    dfle_slope_opts s;

    Amin = Amax = A[0];
    for (size_t i = 0; i < n; i++) {
        Amin = A[i] < Amin ? A[i] : Amin;
        Amax = A[i] > Amax ? A[i] : Amax;
        len = D[i] > len ? D[i] : len;
    }
    s = dfle_profile_slope(p);
    snprintf(buf, sizeof buf, "dfle.profile(%s, %zu cells, %g m, A = %.4g..%.4g m^2, slope over "
             "%s = %g m)", dfle_profile_is_network(p) ? "network" : "profile", n, len, Amin,
             Amax, s.ds > 0 ? "ds" : "dz", s.ds > 0 ? s.ds : s.dz);
    lua_pushstring(L, buf);
}

static void profile_free(void *obj) { dfle_profile_free(obj); }

void dfle_lua_open_dem(lua_State *L)
{
    static const luaL_Reg dem_methods[] = {
        {"fill", l_dem_fill}, {"flow", l_dem_flow}, {"at", l_dem_at},
        {"profile", l_dem_profile}, {"network", l_dem_network},
        {"write_geotiff", l_dem_write_geotiff}, {"resample", dfle_lua_dem_resample},
        {"crop", dfle_lua_dem_crop}, {"write_gpkg", dfle_lua_dem_write_gpkg}, {NULL, NULL}};
    static const luaL_Reg profile_methods[] = {
        {"get", l_profile_get}, {"slope_area", l_profile_slope_area},
        {"write_csv", l_profile_write_csv}, {"channel", l_profile_channel},
        {"main_stem", l_profile_main_stem}, {"write_gpkg", dfle_lua_profile_write_gpkg},
        {NULL, NULL}};
    static const luaL_Reg profile_meta[] = {{"__len", l_profile_len}, {NULL, NULL}};
    static const dfle_lua_type dem_type = {
        .name = DFLE_LUA_DEM, .free = dem_free, .describe = dem_describe,
        .methods = dem_methods, .property = l_dem_property, .closable = 1,
        .fields = "nx, ny, n, dx, dy, extent, crs, crs_wkt, epsg, geographic, path, "
                  "nodata_cells, filled, routed, sinks, flats, z_min, z_max",
    };
    static const dfle_lua_type profile_type = {
        .name = DFLE_LUA_PROFILE, .free = profile_free, .describe = profile_describe,
        .methods = profile_methods, .property = l_profile_property, .meta = profile_meta,
        .fields = "n, kind, length, A_max, A_min, outlet, head, given, snap_distance, ds, dz",
        .closable = 1,
    };
    static const luaL_Reg funcs[] = {{"read", l_dem_read}, {NULL, NULL}};

    dfle_lua_register(L, &dem_type);
    dfle_lua_register(L, &profile_type);
    lua_newtable(L);
    luaL_setfuncs(L, funcs, 0);
    lua_setfield(L, -2, "dem");
}
