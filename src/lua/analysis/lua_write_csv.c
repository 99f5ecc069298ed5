/*
 * lua_write_csv.c - dfle.write_csv: a script's own table written as dfle
 * writes its files (record.h): the provenance as comment lines, a units
 * line, plain column names, the JSON record beside it.
 *
 *   dfle.write_csv("sweep.csv", { columns = { "U", "A_df" }, rows = rows,
 *                                 units = { U = "m/yr", A_df = "m^2" } })
 *
 * Cells are read into C arrays first (numbers, or texts anchored in a
 * Lua table), so nothing malloc'd is held while Lua code may raise.
 */
#include "lua/core/dfle_lua.h"

#include <math.h>
#include <string.h>


/* The cell at v as text (NULL for nil), kept alive in the table at
 * `texts`: numbers as they read back, anything else as tostring. */
static const char *cell_text(lua_State *L, int v, int texts)
{
    char buf[32];
    const char *s;
    if (lua_isnil(L, v))
        return NULL;
    if (lua_type(L, v) == LUA_TNUMBER && !lua_isinteger(L, v))
        lua_pushstring(L, dfle_number_text(lua_tonumber(L, v), buf));
    else
        luaL_tolstring(L, v, NULL);
    s = lua_tostring(L, -1);
    lua_rawseti(L, texts, (lua_Integer)lua_rawlen(L, texts) + 1); /* anchors s */
    return s;
}

/* Push cell (row r, column name at `name`) of the table at t: rows[r][name]
 * or data[name][r]. */
static void push_cell(lua_State *L, int t, int by_rows, int name, lua_Integer r)
{
    if (by_rows) {
        lua_rawgeti(L, t, r);
        if (lua_istable(L, -1)) {
            lua_pushvalue(L, name);
            lua_gettable(L, -2);
            lua_remove(L, -2);
        } else {
            lua_pop(L, 1);
            lua_pushnil(L);
        }
    } else {
        lua_pushvalue(L, name);
        lua_gettable(L, t);
        if (lua_istable(L, -1)) {
            lua_rawgeti(L, -1, r);
            lua_remove(L, -2);
        } else {
            lua_pop(L, 1);
            lua_pushnil(L);
        }
    }
}

/* The provenance `params` at p: models as the model (first), tables
 * into a section of their own, plain values into section "params". */
static void record_params(lua_State *L, dfle_record *rec, int p, const char *fn)
{
    const char *keys = dfle_lua_push_sorted_keys(L, p);
    int klist = lua_gettop(L);
    for (int pass = 0; pass < 2; pass++) {
        const char *k = keys;
        while (*k != '\0') {
            const char *end = strstr(k, ", ");
            size_t len = end != NULL ? (size_t)(end - k) : strlen(k);
            int v, model;
            lua_pushlstring(L, k, len);
            lua_pushvalue(L, -1);
            lua_rawget(L, p);
            v = lua_gettop(L);
            model = luaL_testudata(L, v, DFLE_LUA_MODEL) != NULL;
            if (pass == 0 && model) {
                dfle_lua_record_model(L, rec, v);
            } else if (pass == 1 && !model && lua_istable(L, v)) {
                /* A section of its own, never mixed with a model's. */
                if (dfle_record_has_section(rec, lua_tostring(L, v - 1)))
                    luaL_error(L, "dfle.%s: params.%s would mix with the model's section of "
                                  "that name; call it something else", fn, lua_tostring(L, v - 1));
                dfle_record_section(rec, lua_tostring(L, v - 1), NULL);
                dfle_lua_record_table(L, rec, v, 1);
            } else if (pass == 1 && !model) {
                dfle_record_section(rec, "params", NULL);
                dfle_lua_record_value(L, rec, lua_tostring(L, v - 1), v, 1);
            }
            lua_settop(L, klist);
            k += len + (end != NULL ? 2 : 0);
        }
    }
    lua_pop(L, 1);
}

/* dfle.write_csv(path, { columns =, rows = | data =, units =, about =,
 *                        params =, record = }) */
static int l_write_csv(lua_State *L)
{
    static const char *const fn = "write_csv";
    static const char *const keys[] = {"columns", "rows", "data", "units", "about", "params",
                                       "record", NULL};
    const char *path = dfle_lua_check_string(L, 1, fn, "the path"), *jpath;
    int cols_t, data_t, units_t, texts, by_rows;
    lua_Integer ncols, nrows = 0;
    dfle_column *cols;
    dfle_record *rec;
    dfle_error err;

    luaL_checktype(L, 2, LUA_TTABLE);
    lua_settop(L, 2);
    dfle_lua_read_params(L, 2, fn, NULL, 0, keys);
    if (lua_getfield(L, 2, "columns") != LUA_TTABLE || lua_rawlen(L, -1) == 0)
        luaL_error(L, "dfle.%s: parameter 'columns' must be a non-empty array of column names "
                      "(the order of the columns)", fn);
    cols_t = lua_gettop(L);
    ncols = (lua_Integer)lua_rawlen(L, cols_t);
    lua_getfield(L, 2, "rows");
    lua_getfield(L, 2, "data");
    if (lua_istable(L, -2) == lua_istable(L, -1))
        luaL_error(L, "dfle.%s: give either 'rows' (an array of tables keyed by column name) "
                      "or 'data' (a table of columns, each an array)", fn);
    by_rows = lua_istable(L, -2);
    lua_remove(L, by_rows ? -1 : -2);
    data_t = lua_gettop(L);
    if (lua_getfield(L, 2, "units") != LUA_TNIL && !lua_istable(L, -1))
        luaL_error(L, "dfle.%s: parameter 'units' must be a table {column = \"unit\"}", fn);
    units_t = lua_gettop(L);
    lua_newtable(L);
    texts = lua_gettop(L);
    cols = lua_newuserdatauv(L, (size_t)ncols * sizeof *cols, 0);
    /* Column names, units, and the number of rows. */
    for (lua_Integer j = 1; j <= ncols; j++) {
        dfle_column *c = &cols[j - 1];
        if (lua_rawgeti(L, cols_t, j) != LUA_TSTRING)
            luaL_error(L, "dfle.%s: columns[%d] must be a name, got %s", fn, (int)j,
                       luaL_typename(L, -1));
        c->name = dfle_lua_check_string(L, -1, fn, "a column name");
        for (lua_Integer k = 1; k < j; k++)
            if (strcmp(cols[k - 1].name, c->name) == 0)
                luaL_error(L, "dfle.%s: column '%s' is listed twice", fn, c->name);
        c->unit = NULL;
        if (lua_istable(L, units_t) && lua_getfield(L, units_t, c->name) != LUA_TNIL) {
            if (lua_type(L, -1) != LUA_TSTRING)
                luaL_error(L, "dfle.%s: units.%s must be a string (\"m^2\", \"-\" for a "
                              "dimensionless number)", fn, c->name);
            c->unit = lua_tostring(L, -1); /* anchored in units */
        }
        lua_settop(L, texts + 1);
        if (!by_rows) {
            lua_Integer len;
            if (lua_getfield(L, data_t, c->name) != LUA_TTABLE)
                luaL_error(L, "dfle.%s: data.%s must be an array, got %s", fn, c->name,
                           luaL_typename(L, -1));
            len = (lua_Integer)lua_rawlen(L, -1);
            if (j > 1 && len != nrows)
                luaL_error(L, "dfle.%s: data.%s has %d values, data.%s %d", fn, c->name,
                           (int)len, cols[0].name, (int)nrows);
            nrows = len;
            lua_pop(L, 1);
        }
    }
    if (lua_istable(L, units_t)) {
        lua_pushnil(L);
        while (lua_next(L, units_t) != 0) {
            int known = 0;
            lua_pop(L, 1);
            for (lua_Integer j = 0; j < ncols && !known; j++)
                known = lua_type(L, -1) == LUA_TSTRING && strcmp(lua_tostring(L, -1),
                                                                 cols[j].name) == 0;
            if (!known)
                luaL_error(L, "dfle.%s: units names '%s', which is not a column", fn,
                           luaL_tolstring(L, -1, NULL));
        }
    }
    if (by_rows)
        nrows = (lua_Integer)lua_rawlen(L, data_t);
    /* Cells: a column of numbers (or nil) stays numbers; any other text. */
    for (lua_Integer j = 1; j <= ncols; j++) {
        dfle_column *c = &cols[j - 1];
        int numeric = 1;
        lua_rawgeti(L, cols_t, j);
        for (lua_Integer r = 1; r <= nrows && numeric; r++) {
            push_cell(L, data_t, by_rows, lua_gettop(L), r);
            numeric = lua_isnil(L, -1) || lua_type(L, -1) == LUA_TNUMBER;
            lua_pop(L, 1);
        }
        if (numeric) {
            double *v = lua_newuserdatauv(L, (size_t)(nrows > 0 ? nrows : 1) * sizeof *v, 0);
            lua_rawseti(L, texts, (lua_Integer)lua_rawlen(L, texts) + 1); /* anchored */
            for (lua_Integer r = 1; r <= nrows; r++) {
                push_cell(L, data_t, by_rows, lua_gettop(L), r);
                v[r - 1] = lua_isnil(L, -1) ? NAN : lua_tonumber(L, -1);
                lua_pop(L, 1);
            }
            c->num = v;
            c->text = NULL;
        } else {
            const char **t = lua_newuserdatauv(L, (size_t)(nrows > 0 ? nrows : 1) * sizeof *t, 0);
            lua_rawseti(L, texts, (lua_Integer)lua_rawlen(L, texts) + 1);
            for (lua_Integer r = 1; r <= nrows; r++) {
                push_cell(L, data_t, by_rows, lua_gettop(L), r);
                t[r - 1] = cell_text(L, lua_gettop(L), texts);
                lua_pop(L, 1);
            }
            c->num = NULL;
            c->text = t;
        }
        lua_pop(L, 1);
    }
    lua_getfield(L, 2, "about");
    if (!lua_isnil(L, -1) && lua_type(L, -1) != LUA_TSTRING)
        luaL_error(L, "dfle.%s: parameter 'about' must be a string", fn);
    rec = dfle_lua_push_record(L, lua_tostring(L, -1));
    if (lua_getfield(L, 2, "params") != LUA_TNIL) {
        if (!lua_istable(L, -1))
            luaL_error(L, "dfle.%s: parameter 'params' must be a table", fn);
        record_params(L, rec, lua_gettop(L), fn);
    }
    lua_pop(L, 1);
    jpath = dfle_lua_record_path(L, rec, 2, path, fn);
    if (dfle_table_write(path, "write_csv", rec, cols, (size_t)ncols, (size_t)nrows, 0, &err) !=
        DFLE_OK)
        return dfle_lua_raise(L, &err);
    dfle_lua_record_done(L, rec, path, jpath);
    return 0;
}

void dfle_lua_open_write_csv(lua_State *L)
{
    lua_pushcfunction(L, l_write_csv);
    lua_setfield(L, -2, "write_csv");
}
