/*
 * lua_ensemble_netcdf.c - ens:write_netcdf(path): an ensemble's rows as a
 * CF NetCDF table (netcdf.h), for xarray and friends.
 *
 * One variable per column along the dimension "sample": the sample index,
 * every input and output (NaN where a failed sample has none), and the
 * status and reason as text.  The file's first line (the ensemble's
 * design: n, seed, ranges) goes in a global attribute, so the NetCDF file
 * says what the CSV says.
 */
#include "lua/ensemble/lua_ensemble_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dfle/netcdf.h"

/* The design line of the ensemble file (without its "# "), or NULL. */
static const char *push_design(lua_State *L, const char *file)
{
    char line[4096];
    FILE *f = file != NULL ? fopen(file, "r") : NULL;
    const char *s = NULL;
    if (f != NULL) {
        if (fgets(line, sizeof line, f) != NULL && strncmp(line, "# ", 2) == 0) {
            line[strcspn(line, "\r\n")] = '\0';
            s = lua_pushstring(L, line + 2);
        }
        fclose(f);
    }
    if (s == NULL)
        lua_pushnil(L);
    return s;
}

/* The number column `name` of ens.data (at index data), nrows values. */
static void read_column(lua_State *L, int data, const char *name, size_t nrows, double *out)
{
    if (lua_getfield(L, data, name) != LUA_TTABLE)
        luaL_error(L, "dfle.ensemble:write_netcdf: the result has no column '%s'", name);
    for (size_t r = 0; r < nrows; r++) {
        int t = lua_rawgeti(L, -1, (lua_Integer)r + 1);
        out[r] = t == LUA_TNUMBER ? lua_tonumber(L, -1) : NAN;
        lua_pop(L, 1);
    }
    lua_pop(L, 1);
}

static int l_write_netcdf(lua_State *L)
{
    static const char *const fn = "ensemble:write_netcdf";
    const char *path, *design, *names[2] = {"status", "reason"};
    size_t nrows, nin, nout, ncols;
    dfle_nc_var *cols;
    double *values;
    const double **colp;
    const char **text[2];
    dfle_nc_text tcols[2];
    dfle_nc_attr attrs[4];
    size_t nattrs = 0;
    dfle_error err;
    int data;

    luaL_checktype(L, 1, LUA_TTABLE);
    path = dfle_lua_check_string(L, 2, fn, "the path");
    lua_settop(L, 2);
    if (lua_getfield(L, 1, "data") != LUA_TTABLE)
        return luaL_error(L, "dfle.%s: expected the result of dfle.ensemble or dfle.gather", fn);
    data = lua_gettop(L);
    lua_getfield(L, 1, "inputs");
    lua_getfield(L, 1, "outputs");
    lua_getfield(L, 1, "count");
    if (!lua_istable(L, data + 1) || !lua_istable(L, data + 2) || !lua_isinteger(L, data + 3))
        return luaL_error(L, "dfle.%s: expected the result of dfle.ensemble or dfle.gather", fn);
    nrows = (size_t)lua_tointeger(L, data + 3);
    if (nrows == 0)
        return luaL_error(L, "dfle.%s: the ensemble has no rows yet; nothing to write", fn);
    /* A script may change the table: a count its columns do not hold
     * would size the buffers below (a huge one raised Lua's bare "block
     * too big"). */
    if (lua_getfield(L, data, "index") != LUA_TTABLE ||
        (size_t)lua_rawlen(L, -1) != nrows || lua_tointeger(L, data + 3) < 0)
        return luaL_error(L, "dfle.%s: the result's count (%I) is not the number of rows in "
                             "data.index (%I): was the table changed?", fn,
                          lua_tointeger(L, data + 3),
                          (lua_Integer)(lua_istable(L, -1) ? lua_rawlen(L, -1) : 0));
    lua_pop(L, 1);
    nin = (size_t)lua_rawlen(L, data + 1);
    nout = (size_t)lua_rawlen(L, data + 2);
    ncols = 1 + nin + nout;
    /* Everything in userdata: a raise anywhere below leaks nothing. */
    cols = lua_newuserdatauv(L, ncols * sizeof *cols, 0);
    colp = lua_newuserdatauv(L, ncols * sizeof *colp, 0);
    values = lua_newuserdatauv(L, ncols * nrows * sizeof *values, 0);
    for (size_t k = 0; k < ncols; k++) {
        const char *name = "index";
        if (k > 0) {
            lua_rawgeti(L, k <= nin ? data + 1 : data + 2, (lua_Integer)(k <= nin ? k : k - nin));
            name = lua_tostring(L, -1); /* anchored by the inputs/outputs tables */
            lua_pop(L, 1);
            if (name == NULL)
                return luaL_error(L, "dfle.%s: column names must be strings", fn);
        }
        cols[k] = (dfle_nc_var){name, k == 0 ? "1" : dfle_lua_known_unit(name), k == 0 ? "sample index (row of the design, from 1)"
                                           : k <= nin ? "input parameter" : "output", NULL, NULL};
        read_column(L, data, name, nrows, values + k * nrows);
        colp[k] = values + k * nrows;
    }
    for (int j = 0; j < 2; j++) {
        text[j] = lua_newuserdatauv(L, nrows * sizeof *text[j], 0);
        if (lua_getfield(L, data, names[j]) != LUA_TTABLE)
            return luaL_error(L, "dfle.%s: the result has no column '%s'", fn, names[j]);
        for (size_t r = 0; r < nrows; r++) {
            lua_rawgeti(L, -1, (lua_Integer)r + 1);
            text[j][r] = lua_tostring(L, -1); /* anchored by the column table */
            lua_pop(L, 1);
        }
        tcols[j] = (dfle_nc_text){names[j], j == 0 ? "ok or failed" : "why a sample failed",
                                  text[j]};
    }
    attrs[nattrs++] = (dfle_nc_attr){"title", "dfle ensemble: one steady-state model per sample"};
    attrs[nattrs++] = (dfle_nc_attr){"history", dfle_lua_push_history(L)};
    lua_getfield(L, 1, "file");
    if ((design = push_design(L, lua_tostring(L, -1))) != NULL)
        attrs[nattrs++] = (dfle_nc_attr){"dfle_design", design};
    if (lua_isstring(L, -2))
        attrs[nattrs++] = (dfle_nc_attr){"dfle_rows_file", lua_tostring(L, -2)};
    if (dfle_nc_write_table(path, "sample", nrows, ncols, cols, colp, 2, tcols, nattrs, attrs,
                            &err) != DFLE_OK)
        return luaL_error(L, "dfle.%s: %s", fn, err.msg);
    dfle_lua_note(L, DFLE_LUA_DETAIL, "wrote %s (%zu samples)", path, nrows);
    lua_settop(L, 1);
    return 1;
}

void dfle_lua_ens_result_methods(lua_State *L)
{
    static const luaL_Reg methods[] = {{"write_netcdf", l_write_netcdf}, {NULL, NULL}};
    luaL_newlib(L, methods);
    lua_setfield(L, -2, "__index");
}
