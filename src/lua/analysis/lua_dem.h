/*
 * lua_dem.h - what the two files of dfle.dem's binding share: the
 * userdata of DEMs and profiles, reading an {E, N} option, and the GIS
 * methods of lua_dem_gis.c (resampling, cropping, GeoPackages), which
 * lua_dem.c registers.  Internal to the binding.
 */
#ifndef DFLE_LUA_DEM_H
#define DFLE_LUA_DEM_H

#include "lua/core/dfle_lua.h"

#include "dfle/dem.h"

#define DFLE_LUA_DEM "dfle.dem"
#define DFLE_LUA_PROFILE "dfle.profile"

typedef struct { dfle_dem *dem; DFLE_LUA_IN_USE; } dfle_lua_dem;
typedef struct { dfle_profile *p; DFLE_LUA_IN_USE; } dfle_lua_profile;

/* Field `key` of the options table at opts as {E, N} (finite, in m):
 * 1 and *E, *N when given, 0 when absent; raises otherwise. */
int dfle_lua_dem_read_point(lua_State *L, int opts, const char *key, const char *fn, double *E,
                            double *N);

/* lua_dem_gis.c */
int dfle_lua_dem_resample(lua_State *L);     /* dem:resample{ dx =, dy =, method = } */
int dfle_lua_dem_crop(lua_State *L);         /* dem:crop{ E_min =, ..., data = }     */
int dfle_lua_dem_write_gpkg(lua_State *L);   /* dem:write_gpkg(path, { outlet = })   */
int dfle_lua_profile_write_gpkg(lua_State *L); /* p:write_gpkg(path)                 */

#endif
