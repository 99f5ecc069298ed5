/*
 * lua_dem_gis.c - dfle.dem's GIS methods: a DEM resampled or cropped
 * through GDAL, and profiles, networks and catchments as GeoPackage
 * layers (vector.h).
 *
 *   local coarse = dem:resample{ dx = 90 }              -- average of 3 x 3
 *   local box = dem:crop{ E_min = 390000, N_max = 3805000 }
 *   dem:write_gpkg("catchment.gpkg", { outlet = {396887, 3799338}, A_min = 1e5 })
 *   net:write_gpkg("network.gpkg")
 */
#include "lua/analysis/lua_dem.h"

#include <math.h>
#include <string.h>

#include "dfle/vector.h"

static dfle_dem *check_dem(lua_State *L, int arg)
{
    return dfle_lua_check_object(L, arg, DFLE_LUA_DEM);
}

/* A new dfle.dem for `made` on the stack (a raise on failure). */
static int push_dem(lua_State *L, int (*make)(lua_State *, dfle_dem **, dfle_error *))
{
    dfle_lua_dem *u = dfle_lua_newobject(L, sizeof *u, DFLE_LUA_DEM, 0);
    dfle_error err;
    if (make(L, &u->dem, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

static int make_resampled(lua_State *L, dfle_dem **out, dfle_error *err)
{
    static const char *const other[] = {"method", NULL};
    static const char *const methods[] = {"nearest", "bilinear", "cubic", "cubicspline",
                                          "lanczos", "average", "min", "max", "median", "mode",
                                          NULL};
    double dx = NAN, dy = 0;
    const dfle_lua_param params[] = {{"dx", &dx}, {"dy", &dy}};
    const char *method = NULL;
    dfle_lua_read_params(L, 2, "dem:resample", params, 2, other);
    if (isnan(dx))
        luaL_error(L, "dfle.dem:resample: parameter 'dx' (the new cell size, m) is required");
    if (lua_getfield(L, 2, "method") != LUA_TNIL)
        method = methods[dfle_lua_check_option(L, -1, "dem:resample", "method", methods)];
    lua_pop(L, 1);
    return dfle_dem_resample(check_dem(L, 1), dx, dy, method, out, err);
}

/* dem:resample{ dx = [, dy =, method = ] } -> a new dfle.dem */
int dfle_lua_dem_resample(lua_State *L)
{
    check_dem(L, 1);
    luaL_checktype(L, 2, LUA_TTABLE);
    lua_settop(L, 2);
    return push_dem(L, make_resampled);
}

static int make_cropped(lua_State *L, dfle_dem **out, dfle_error *err)
{
    static const char *const other[] = {"data", NULL};
    dfle_dem *dem = check_dem(L, 1);
    double box[4] = {NAN, NAN, NAN, NAN}, e[4];
    const dfle_lua_param params[] = {{"E_min", &box[0]}, {"E_max", &box[1]},
                                     {"N_min", &box[2]}, {"N_max", &box[3]}};
    int data;
    dfle_lua_read_params(L, 2, "dem:crop", params, 4, other);
    lua_getfield(L, 2, "data");
    if (!lua_isnil(L, -1) && !lua_isboolean(L, -1))
        luaL_error(L, "dfle.dem:crop: parameter 'data' must be true or false");
    data = lua_toboolean(L, -1);
    lua_pop(L, 1);
    dfle_dem_extent(dem, e);
    if (data) {
        for (int k = 0; k < 4; k++)
            if (!isnan(box[k]))
                luaL_error(L, "dfle.dem:crop: give 'data = true' (the data's bounding box) or "
                              "the box's edges, not both");
        dfle_dem_data_extent(dem, box); /* a DEM has data somewhere */
    } else {
        if (isnan(box[0]) && isnan(box[1]) && isnan(box[2]) && isnan(box[3]))
            luaL_error(L, "dfle.dem:crop: give the box (E_min, E_max, N_min, N_max in m; an "
                          "edge left out is the grid's) or data = true");
        for (int k = 0; k < 4; k++)
            if (isnan(box[k]))
                box[k] = e[k];
    }
    return dfle_dem_crop(dem, box, out, err);
}

/* dem:crop{ E_min =, E_max =, N_min =, N_max = } or dem:crop{ data = true } */
int dfle_lua_dem_crop(lua_State *L)
{
    check_dem(L, 1);
    luaL_checktype(L, 2, LUA_TTABLE);
    lua_settop(L, 2);
    return push_dem(L, make_cropped);
}

/* dem:write_gpkg(path, { outlet = {E, N} [, radius =, A_min = ] }): the
 * catchment above the outlet, and its channels with A_min. */
int dfle_lua_dem_write_gpkg(lua_State *L)
{
    static const char *const fn = "dem:write_gpkg";
    static const char *const other[] = {"outlet", NULL};
    dfle_dem *dem = check_dem(L, 1);
    const char *path = dfle_lua_check_string(L, 2, fn, "the path");
    double radius = NAN, A_min = NAN;
    const dfle_lua_param params[] = {{"radius", &radius}, {"A_min", &A_min}};
    dfle_vector_opts o;
    dfle_lua_profile *net = NULL;
    dfle_record *rec;
    dfle_error err;

    luaL_checktype(L, 3, LUA_TTABLE);
    lua_settop(L, 3);
    dfle_lua_read_params(L, 3, fn, params, 2, other);
    dfle_vector_opts_default(&o);
    if (!dfle_lua_dem_read_point(L, 3, "outlet", fn, &o.outlet[0], &o.outlet[1]))
        return luaL_error(L, "dfle.%s: parameter 'outlet' ({E, N} in m) is required: the "
                             "catchment is the area draining to it", fn);
    if (!isnan(radius)) {
        if (!(radius >= 0))
            return luaL_error(L, "dfle.%s: radius must be >= 0 m", fn);
        o.radius = radius;
    }
    o.catchment_of = dem;
    rec = dfle_lua_push_record(L, "a catchment (and its channels) from a DEM");
    dfle_dem_describe(dem, rec);
    dfle_record_section(rec, "catchment", NULL);
    dfle_record_number(rec, "outlet_E", o.outlet[0], "m");
    dfle_record_number(rec, "outlet_N", o.outlet[1], "m");
    if (!isnan(A_min)) {
        dfle_network_opts no;
        dfle_network_opts_default(&no);
        no.A_min = A_min;
        no.has_outlet = 1;
        no.E = o.outlet[0], no.N = o.outlet[1];
        no.radius = o.radius;
        net = dfle_lua_newobject(L, sizeof *net, DFLE_LUA_PROFILE, 0); /* freed by its __gc */
        if (dfle_dem_network(dem, &no, &net->p, &err) != DFLE_OK)
            return dfle_lua_raise(L, &err);
        dfle_profile_describe(net->p, rec);
        o.channels = net->p;
    }
    o.provenance = rec;
    if (dfle_vector_write_gpkg(path, &o, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path);
    lua_settop(L, 1);
    return 1;
}

/* p:write_gpkg(path): the profile's or network's channels and cells. */
int dfle_lua_profile_write_gpkg(lua_State *L)
{
    static const char *const fn = "profile:write_gpkg";
    dfle_profile *p = dfle_lua_check_object(L, 1, DFLE_LUA_PROFILE);
    const char *path = dfle_lua_check_string(L, 2, fn, "the path");
    dfle_vector_opts o;
    dfle_record *rec;
    dfle_error err;

    lua_settop(L, 2);
    dfle_vector_opts_default(&o);
    rec = dfle_lua_push_record(L, dfle_profile_is_network(p)
                                      ? "DEM channel network: a line a cell, to its receiver"
                                      : "DEM channel profile: a line a cell, to its receiver");
    dfle_profile_describe(p, rec);
    o.channels = p;
    o.provenance = rec;
    if (dfle_vector_write_gpkg(path, &o, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path);
    lua_settop(L, 1);
    return 1;
}
