/*
 * lua_landscape.h - what the two halves of dfle.landscape's binding
 * share: the userdata (its components held as user values, the Lua
 * callbacks of fields and of the combine rule) and the two functions
 * that cross between construction (lua_landscape_new.c) and the
 * methods (lua_landscape.c).  Internal to the binding.
 */
#ifndef DFLE_LUA_LANDSCAPE_H
#define DFLE_LUA_LANDSCAPE_H

#include "lua/core/dfle_lua.h"

#include "dfle/landscape.h"
#include "dfle/raster.h"
#include "dfle/record.h"

#define DFLE_LUA_LANDSCAPE "dfle.landscape"

enum { UV_FLUVIAL = 1, UV_ROUTER, UV_LAW, UV_CRS, UV_COUNT = UV_CRS };
enum { F_U, F_K, F_DF, F_COUNT };

struct lua_ls;
typedef struct field_cb {
    struct lua_ls *u;
    int ref;          /* the Lua function, or LUA_NOREF */
    double divide_by; /* a scale: the value over the component's own */
    int with_t;       /* f(x, y, t): called every step */
    const char *name;
    int judged;       /* its values were put to the plausibility table */
} field_cb;

typedef struct lua_ls {
    dfle_landscape *ls;
    DFLE_LUA_IN_USE;
    lua_State *L;     /* the thread of the call running now (callbacks) */
    int ref_combine;
    field_cb cb[F_COUNT];
    double x0, y0;    /* north-west corner [m] */
    size_t nx, ny;    /* the grid, for callbacks (also while it is built) */
    double dx, dy;
    const double *zmask; /* elevations whose NaN mark NoData */
    char *crs;        /* WKT (a string held as user value UV_CRS) or NULL */
    char cb_err[512]; /* a callback's failure */
} lua_ls;

/* A run's NetCDF time series (lua_landscape_files.c). */
typedef struct lua_ls_series {
    lua_ls *u;
    dfle_nc *nc;          /* NULL: nothing recorded                  */
    int fields[DFLE_LS_NFIELDS];
    size_t nf;
    double *buf;          /* nf * n values (a userdata on the stack) */
    dfle_record *rec;     /* provenance (a userdata on the stack)    */
    dfle_nc **box;        /* nc, held for __gc (a userdata on the stack) */
    const char *path;
} lua_ls_series;

/* dfle.landscape{...} -> a landscape (lua_landscape_new.c). */
int dfle_lua_landscape_new(lua_State *L);
/* Raise err, preferring a callback's own message (lua_landscape.c). */
int dfle_lua_ls_raise(lua_State *L, lua_ls *u, const dfle_error *err);
/* The field named at idx (raises listing the fields), and its nx * ny
 * values in a scratch userdata left on the stack (lua_landscape.c). */
int dfle_lua_ls_field_id(lua_State *L, int idx, const char *fn);
double *dfle_lua_ls_get_field(lua_State *L, int field, const char *what);

/* lua_landscape_files.c: the landscape's record (what it runs, with the
 * params of components written in Lua); a run's time series from its
 * options record =, netcdf =, fields =, float32 = at index opts (sets
 * o's record times and callback; leaves userdata on the stack); its
 * close after a run that went well (how it ended goes into the file),
 * or its abort; ls:write_geotiff and ls:set_z. */
void dfle_lua_record_landscape(lua_State *L, dfle_record *rec, int idx);
void dfle_lua_ls_series_open(lua_State *L, lua_ls *u, int opts, const char *fn,
                             dfle_landscape_run_opts *o, lua_ls_series *s);
int dfle_lua_ls_series_close(lua_State *L, lua_ls_series *s, const dfle_landscape_result *res,
                             dfle_error *err);
void dfle_lua_ls_series_abort(lua_ls_series *s);
int dfle_lua_ls_write_geotiff(lua_State *L);
int dfle_lua_ls_set_z(lua_State *L);

#endif
