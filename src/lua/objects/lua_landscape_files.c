/*
 * lua_landscape_files.c - a landscape's files: its NetCDF time series
 * (ls:run{ record =, netcdf =, fields =, float32 = }), GeoTIFF
 * (ls:write_geotiff), the record of what it runs, and restarts from its
 * own output (ls:set_z from a dfle.dem or a NetCDF record).
 *
 * Every file carries the landscape's record (dfle_landscape_describe,
 * plus the parameters of components written in Lua, which keep them in
 * Lua), so a file alone says how to make it again.  A record is held by
 * a userdata on the stack (dfle_lua_push_record), so a raise between
 * here and the write leaks nothing.
 */
#include "lua/core/dfle_lua.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/dem.h"
#include "dfle/raster.h"

#include "lua/objects/lua_landscape.h"

static lua_ls *check_ls(lua_State *L, int arg)
{
    dfle_lua_check_object(L, arg, DFLE_LUA_LANDSCAPE);
    return lua_touserdata(L, arg);
}

static void geo_of(const lua_ls *u, dfle_raster_geo *g)
{
    g->x0 = u->x0;
    g->y0 = u->y0;
    g->dx = dfle_landscape_dx(u->ls);
    g->dy = dfle_landscape_dy(u->ls);
    g->crs_wkt = u->crs;
}

void dfle_lua_record_landscape(lua_State *L, dfle_record *rec, int idx)
{
    lua_ls *u = check_ls(L, idx);
    idx = lua_absindex(L, idx);
    dfle_landscape_describe(u->ls, rec);
    dfle_record_section(rec, "landscape", NULL);
    dfle_record_number(rec, "x0", u->x0, "m");
    dfle_record_number(rec, "y0", u->y0, "m");
    /* Components written in Lua keep their params in Lua. */
    dfle_lua_record_lua_parts(L, rec, idx, UV_ROUTER, UV_LAW);
}

/* ---------------------------------------------------------------- */
/* NetCDF time series                                               */
/* ---------------------------------------------------------------- */

static int record_nc(void *ud, dfle_landscape *ls, size_t k, double t)
{
    lua_ls_series *s = ud;
    const size_t n = dfle_landscape_nx(ls) * dfle_landscape_ny(ls);
    const double *vals[DFLE_LS_NFIELDS];
    dfle_error err;
    (void)k;
    for (size_t j = 0; j < s->nf; j++) {
        if (dfle_landscape_get(ls, s->fields[j], s->buf + j * n, &err) != DFLE_OK) {
            snprintf(s->u->cb_err, sizeof s->u->cb_err, "%s", err.msg);
            return 1;
        }
        vals[j] = s->buf + j * n;
    }
    if (dfle_nc_append(s->nc, t, vals, &err) != DFLE_OK) {
        snprintf(s->u->cb_err, sizeof s->u->cb_err, "%s", err.msg);
        return 1;
    }
    return 0;
}

/* The open file is held by a userdata on the stack too: a raise between
 * the file's creation and the end of the run (the landscape busy, an
 * interrupt) collects it, and its __gc removes the temporary file. */
#define SERIES_BOX "dfle.landscape_series"

static int box_gc(lua_State *L)
{
    dfle_nc **box = luaL_checkudata(L, 1, SERIES_BOX);
    dfle_nc_abort(*box);
    *box = NULL;
    return 0;
}

static dfle_nc **push_box(lua_State *L)
{
    dfle_nc **box = lua_newuserdatauv(L, sizeof *box, 0);
    *box = NULL;
    if (luaL_newmetatable(L, SERIES_BOX)) {
        lua_pushcfunction(L, box_gc);
        lua_setfield(L, -2, "__gc");
    }
    lua_setmetatable(L, -2);
    return box;
}

/* The run asked, into the record's section "run". */
static void record_run_opts(dfle_record *rec, const char *fn, const dfle_landscape_run_opts *o)
{
    static const char *const methods[] = {"explicit", "implicit", "direct", "auto"};
    int steady = strstr(fn, "steady") != NULL;
    dfle_record_section(rec, "run", steady ? "run_to_steady" : "run");
    dfle_record_param_text(rec, "method_asked", (int)o->method >= 0 && (int)o->method < 4
                                                    ? methods[o->method] : "?");
    if (steady) {
        dfle_record_param_number(rec, "tol", o->tol, "");
        dfle_record_param_number(rec, "channel_quantile", o->channel_quantile, "");
        dfle_record_param_number(rec, "hillslope_quantile", o->hillslope_quantile, "");
        dfle_record_param_number(rec, "stable_steps", (double)o->stable_steps, "");
        dfle_record_param_number(rec, "rcv_tol", o->rcv_tol, "");
        dfle_record_param_number(rec, "rcv_tol_cycle", o->rcv_tol_cycle, "");
        dfle_record_param_number(rec, "verify_steps", (double)o->verify_steps, "");
        dfle_record_param_number(rec, "verify_dt", o->verify_dt, "yr");
        dfle_record_param_number(rec, "max_time", o->max_time, "yr");
    } else {
        dfle_record_param_number(rec, "years", o->years, "yr");
    }
    dfle_record_param_number(rec, "dt", o->dt, "yr");
    dfle_record_param_number(rec, "max_steps", (double)o->max_steps, "");
}

void dfle_lua_ls_series_open(lua_State *L, lua_ls *u, int opts, const char *fn,
                             dfle_landscape_run_opts *o, lua_ls_series *s)
{
    size_t k;
    double *times;
    const char *path;
    dfle_nc_var vars[DFLE_LS_NFIELDS];
    dfle_nc_opts no;
    dfle_raster_geo g;
    dfle_error err;
    const size_t n = dfle_landscape_nx(u->ls) * dfle_landscape_ny(u->ls);
    int top;

    memset(s, 0, sizeof *s);
    s->u = u;
    opts = lua_absindex(L, opts);
    if (!lua_istable(L, opts))
        return;
    if (lua_getfield(L, opts, "record") == LUA_TNIL) {
        /* netcdf, fields and float32 without record would be ignored. */
        for (const char *const *key = (const char *const[]){"netcdf", "fields", "float32", NULL};
             *key != NULL; key++) {
            if (lua_getfield(L, opts, *key) != LUA_TNIL)
                luaL_error(L, "dfle.%s: '%s' goes with 'record', the times to record", fn, *key);
            lua_pop(L, 1);
        }
        lua_pop(L, 1);
        return;
    }
    /* Everything below stays on the stack (the caller's scratch). */
    times = dfle_lua_check_array(L, -1, "landscape:run: record", &k);
    o->n_record = k;
    o->record_times = times;
    if (lua_getfield(L, opts, "netcdf") != LUA_TSTRING)
        luaL_error(L, "dfle.%s: 'record' needs 'netcdf', the path of the time series", fn);
    path = dfle_lua_check_string(L, -1, fn, "netcdf");
    if (lua_getfield(L, opts, "fields") == LUA_TNIL) {
        s->fields[0] = DFLE_LS_Z;
        s->nf = 1;
    } else {
        if (!lua_istable(L, -1))
            luaL_error(L, "dfle.%s: 'fields' must list 1 to %d field names, got %s", fn,
                       DFLE_LS_NFIELDS, luaL_typename(L, -1));
        s->nf = lua_rawlen(L, -1);
        if (s->nf == 0 || s->nf > DFLE_LS_NFIELDS)
            luaL_error(L, "dfle.%s: 'fields' must list 1 to %d field names", fn, DFLE_LS_NFIELDS);
        for (size_t j = 0; j < s->nf; j++) {
            lua_rawgeti(L, -1, (lua_Integer)j + 1);
            s->fields[j] = dfle_lua_ls_field_id(L, -1, fn);
            lua_pop(L, 1);
            for (size_t i = 0; i < j; i++)
                if (s->fields[i] == s->fields[j])
                    luaL_error(L, "dfle.%s: field '%s' is listed twice in 'fields' (entries %d "
                               "and %d)", fn, dfle_landscape_field_name(s->fields[j]), (int)i + 1,
                               (int)j + 1);
        }
    }
    dfle_nc_opts_default(&no);
    top = lua_getfield(L, opts, "float32");
    if (top != LUA_TNIL && top != LUA_TBOOLEAN)
        luaL_error(L, "dfle.%s: 'float32' must be true or false, got %s", fn,
                   luaL_typename(L, -1));
    no.float32 = lua_toboolean(L, -1);
    for (size_t j = 0; j < s->nf; j++) {
        int f = s->fields[j];
        vars[j].name = dfle_landscape_field_name(f);
        vars[j].units = dfle_landscape_field_unit(f);
        vars[j].long_name = dfle_landscape_field_long_name(f);
        vars[j].standard_name = dfle_landscape_field_standard_name(f);
        vars[j].flag_meanings = f == DFLE_LS_CHANNEL ? "hillslope channel channel_head"
                                : f == DFLE_LS_BASE  ? "not_base_level base_level"
                                                     : NULL;
        if (vars[j].flag_meanings != NULL)
            vars[j].units = NULL; /* flags have none (CF) */
    }
    s->buf = lua_newuserdatauv(L, s->nf * n * sizeof(double), 0);
    s->rec = dfle_lua_push_record(L, "landscape time series: the recorded fields at each "
                                     "record time");
    dfle_lua_record_landscape(L, s->rec, 1);
    record_run_opts(s->rec, fn, o);
    s->box = push_box(L);
    geo_of(u, &g);
    no.title = "dfle landscape";
    no.provenance = NULL; /* at the close, with how the run ended */
    no.mask = dfle_landscape_z(u->ls); /* NaN = NoData: crop to the data */
    if (dfle_nc_create(path, dfle_landscape_nx(u->ls), dfle_landscape_ny(u->ls), &g, s->nf, vars,
                       &no, &s->nc, &err) != DFLE_OK)
        dfle_lua_raise(L, &err);
    *s->box = s->nc;
    s->path = path;
    o->on_record = record_nc;
    o->on_record_ud = s;
}

void dfle_lua_ls_series_abort(lua_ls_series *s)
{
    if (s->box != NULL)
        *s->box = NULL;
    dfle_nc_abort(s->nc);
    s->nc = NULL;
}

int dfle_lua_ls_series_close(lua_State *L, lua_ls_series *s, const dfle_landscape_result *res,
                             dfle_error *err)
{
    dfle_nc *nc = s->nc;
    s->nc = NULL;
    if (s->box != NULL)
        *s->box = NULL; /* ours from here: closed or aborted below */
    if (nc == NULL)
        return DFLE_OK;
    dfle_record_section(s->rec, "run", NULL);
    dfle_record_bool(s->rec, "converged", res->converged);
    dfle_record_text(s->rec, "reason", dfle_stop_reason_name(res->reason));
    dfle_record_text(s->rec, "method", dfle_method_name(res->method));
    dfle_record_number(s->rec, "steps", (double)res->last.steps, NULL);
    dfle_record_number(s->rec, "time", res->last.time, "yr");
    dfle_record_number(s->rec, "recorded", (double)res->n_recorded, NULL);
    dfle_record_text(s->rec, "note", res->note);
    /* what "steady" rested on: the channel cells and the volume balance */
    dfle_record_number(s->rec, "channel_max_ratio", res->last.channel_max_ratio, NULL);
    dfle_record_number(s->rec, "channel_frac_above", res->last.channel_frac_above, NULL);
    dfle_record_number(s->rec, "volume_balance", res->last.volume_balance, NULL);
    dfle_record_bool(s->rec, "verified", res->verified);
    if (dfle_nc_annotate(nc, s->rec, err) != DFLE_OK) {
        dfle_nc_abort(nc);
        return err->code;
    }
    if (dfle_nc_close(nc, err) != DFLE_OK)
        return err->code;
    dfle_lua_note_file(L, s->path);
    return DFLE_OK;
}

/* ---------------------------------------------------------------- */
/* GeoTIFF                                                          */
/* ---------------------------------------------------------------- */

/* ls:write_geotiff(path [, fields]) : one band per field (default z). */
int dfle_lua_ls_write_geotiff(lua_State *L)
{
    static const char *const fn = "landscape:write_geotiff";
    lua_ls *u = check_ls(L, 1);
    const char *path = dfle_lua_check_string(L, 2, fn, "the path");
    int fields[DFLE_LS_NFIELDS];
    dfle_raster_band bands[DFLE_LS_NFIELDS];
    size_t nf = 0;
    dfle_raster_geo g;
    dfle_record *rec;
    dfle_error err;

    lua_settop(L, 3);
    if (lua_isnil(L, 3)) {
        fields[nf++] = DFLE_LS_Z;
    } else if (lua_type(L, 3) == LUA_TSTRING) {
        fields[nf++] = dfle_lua_ls_field_id(L, 3, fn);
    } else {
        luaL_checktype(L, 3, LUA_TTABLE);
        if (lua_rawlen(L, 3) > DFLE_LS_NFIELDS)
            luaL_error(L, "dfle.%s: at most %d fields, each once (got %d)", fn,
                       DFLE_LS_NFIELDS, (int)lua_rawlen(L, 3));
        for (size_t k = 1; k <= lua_rawlen(L, 3); k++) {
            lua_rawgeti(L, 3, (lua_Integer)k);
            fields[nf] = dfle_lua_ls_field_id(L, -1, fn);
            lua_pop(L, 1);
            /* a name twice would be two bands of one name */
            for (size_t j = 0; j < nf; j++)
                if (fields[j] == fields[nf])
                    luaL_error(L, "dfle.%s: field '%s' is listed twice in the fields "
                               "(entries %d and %d)", fn, dfle_landscape_field_name(fields[nf]),
                               (int)j + 1, (int)nf + 1);
            nf++;
        }
        if (nf == 0)
            luaL_error(L, "dfle.%s: no fields to write", fn);
    }
    for (size_t k = 0; k < nf; k++) {
        bands[k].values = dfle_lua_ls_get_field(L, fields[k], "dfle.landscape:write_geotiff");
        bands[k].name = dfle_landscape_field_name(fields[k]);
        bands[k].units = fields[k] == DFLE_LS_CHANNEL || fields[k] == DFLE_LS_BASE
                             ? NULL
                             : dfle_landscape_field_unit(fields[k]);
    }
    geo_of(u, &g);
    rec = dfle_lua_push_record(L, "landscape fields, one band each");
    dfle_lua_record_landscape(L, rec, 1);
    if (dfle_raster_write_geotiff(path, dfle_landscape_nx(u->ls), dfle_landscape_ny(u->ls), &g,
                                  nf, bands, rec, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, path);
    lua_settop(L, 1);
    return 1;
}

/* ---------------------------------------------------------------- */
/* Restarts                                                         */
/* ---------------------------------------------------------------- */

/* NoData where the landscape has it, data where it has data: a surface
 * from elsewhere must agree (NoData stays NoData, and a restart that
 * left a data cell without an elevation would be no restart). */
static void check_mask(lua_State *L, lua_ls *u, const double *z, const char *from)
{
    const double *now = dfle_landscape_z(u->ls);
    const size_t nx = dfle_landscape_nx(u->ls), n = nx * dfle_landscape_ny(u->ls);
    for (size_t c = 0; c < n; c++)
        if (isnan(now[c]) != isnan(z[c]))
            luaL_error(L, "dfle.landscape:set_z: %s has %s at row %d, column %d, where the "
                          "landscape has %s", from, isnan(z[c]) ? "no elevation" : "an elevation",
                       (int)(c / nx) + 1, (int)(c % nx) + 1, isnan(now[c]) ? "NoData" : "data");
}

/* ls:set_z(z) | ls:set_z(dem) | ls:set_z{ netcdf = path, record = k | time = t } */
int dfle_lua_ls_set_z(lua_State *L)
{
    static const char *const fn = "landscape:set_z";
    lua_ls *u = check_ls(L, 1);
    const size_t nx = dfle_landscape_nx(u->ls), ny = dfle_landscape_ny(u->ls), n = nx * ny;
    double *z = NULL;
    dfle_error err;

    lua_settop(L, 2);
    if (luaL_testudata(L, 2, "dfle.dem") != NULL) {
        dfle_dem *d = dfle_lua_check_object(L, 2, "dfle.dem");
        double e[4];
        dfle_dem_extent(d, e);
        if (dfle_dem_nx(d) != nx || dfle_dem_ny(d) != ny)
            return luaL_error(L, "dfle.%s: the DEM has %d x %d cells, the landscape %d x %d", fn,
                              (int)dfle_dem_nx(d), (int)dfle_dem_ny(d), (int)nx, (int)ny);
        if (fabs(dfle_dem_dx(d) - dfle_landscape_dx(u->ls)) > 1e-9 * dfle_landscape_dx(u->ls) ||
            fabs(dfle_dem_dy(d) - dfle_landscape_dy(u->ls)) > 1e-9 * dfle_landscape_dy(u->ls) ||
            fabs(e[0] - u->x0) > 1e-6 * dfle_landscape_dx(u->ls) ||
            fabs(e[3] - u->y0) > 1e-6 * dfle_landscape_dy(u->ls))
            return luaL_error(L, "dfle.%s: the DEM's grid (cells of %f x %f m, north-west corner "
                                 "%f E, %f N) is not the landscape's (%f x %f m, %f E, %f N)",
                              fn, dfle_dem_dx(d), dfle_dem_dy(d), e[0], e[3],
                              dfle_landscape_dx(u->ls), dfle_landscape_dy(u->ls), u->x0, u->y0);
        z = lua_newuserdatauv(L, n * sizeof *z, 0);
        memcpy(z, dfle_dem_z(d), n * sizeof *z);
        check_mask(L, u, z, "the DEM");
    } else if (lua_istable(L, 2) && lua_getfield(L, 2, "netcdf") != LUA_TNIL) {
        static const char *const keys[] = {"netcdf", "record", "time", "field", NULL};
        double record = NAN, t = NAN;
        const dfle_lua_param params[] = {{"record", &record}, {"time", &t}};
        const char *path = dfle_lua_check_string(L, -1, fn, "netcdf");
        const char *field = "z";
        dfle_raster_geo g;
        size_t index = (size_t)-1;
        dfle_lua_read_params(L, 2, fn, params, 2, keys);
        if (isnan(record) == isnan(t))
            return luaL_error(L, "dfle.%s: give 'record' (1 = the first) or 'time' [yr] of the "
                                 "NetCDF record, one of them", fn);
        if (!isnan(record))
            index = (size_t)dfle_lua_check_whole(L, record, fn, "record", 1, 1e15) - 1;
        if (lua_getfield(L, 2, "field") != LUA_TNIL)
            field = dfle_lua_check_string(L, -1, fn, "field");
        z = lua_newuserdatauv(L, n * sizeof *z, 0);
        geo_of(u, &g);
        if (dfle_nc_read_grid(path, field, index, t, &g, nx, ny, z, NULL, &err) != DFLE_OK)
            return dfle_lua_raise(L, &err);
        lua_pushfstring(L, "'%s'", path);
        check_mask(L, u, z, lua_tostring(L, -1));
    } else {
        size_t m;
        if (!lua_istable(L, 2) || lua_rawlen(L, 2) == 0)
            return luaL_error(L, "dfle.%s: give an array of %d elevations, a dfle.dem on the "
                                 "landscape's grid or { netcdf = path, record = k | time = t }, "
                                 "got %s", fn, (int)n,
                              lua_istable(L, 2) ? "a table without elevations"
                                                : dfle_lua_typename(L, 2));
        z = dfle_lua_check_array(L, 2, "landscape:set_z: z", &m);
        if (m != n)
            return luaL_error(L, "dfle.%s: z has %d values, the grid %d", fn, (int)m, (int)n);
    }
    dfle_lua_begin_use(L, 1, "dfle.landscape:set_z");
    dfle_lua_end_use(L, 1);
    if (dfle_landscape_set_z(u->ls, z, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    lua_settop(L, 1);
    return 1;
}
