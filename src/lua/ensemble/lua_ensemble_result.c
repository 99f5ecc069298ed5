/*
 * lua_ensemble_result.c - a finished ensemble's file read back into the
 * table dfle.ensemble (and dfle.gather) returns: a column per parameter
 * and output, the status counts, what ran.
 *
 * The result is always read from the file, never kept from the run, so
 * that a resumed, sharded or gathered ensemble gives the same table as
 * one run at once.  Numbers come back as Lua read them (integers stay
 * integers); quoted fields, the status and the reason stay text.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lua/ensemble/lua_ensemble_internal.h"

/* Split one CSV line; push each of its first maxpush fields (strings)
 * and return the count of all.  quoted[k] says whether field k was
 * quoted (up to maxq fields).  Fields past maxpush are only counted: a
 * damaged line of a million commas ran the stack out ("stack overflow
 * (too many columns)") instead of saying it has too many fields. */
static int push_fields(lua_State *L, const char *s, unsigned char *quoted, int maxq,
                       int maxpush)
{
    int n = 0;
    for (;;) {
        luaL_Buffer b;
        int q = 0;
        if (n >= maxpush) {
            int inq = 0;
            for (; *s != '\0'; s++) {
                if (*s == '"')
                    inq = !inq;
                else if (*s == ',' && !inq)
                    n++;
            }
            return n + 1;
        }
        luaL_checkstack(L, 2, "too many columns");
        luaL_buffinit(L, &b);
        if (*s == '"') {
            q = 1;
            s++;
            while (*s != '\0') {
                if (*s == '"' && s[1] == '"') {
                    luaL_addchar(&b, '"');
                    s += 2;
                } else if (*s == '"') {
                    s++;
                    break;
                } else {
                    luaL_addchar(&b, *s++);
                }
            }
            while (*s != '\0' && *s != ',')
                s++;
        } else {
            const char *e = strchr(s, ',');
            size_t len = e ? (size_t)(e - s) : strlen(s);
            luaL_addlstring(&b, s, len);
            s += len;
        }
        luaL_pushresult(&b);
        if (n < maxq)
            quoted[n] = (unsigned char)q;
        n++;
        if (*s != ',')
            return n;
        s++;
    }
}

/* The number in field string f (integers stay integers; "nan", "inf"
 * and an empty field as floats); text stays text. */
static void push_field_number(lua_State *L, int f)
{
    const char *s = lua_tostring(L, f);
    char *end;
    double v;
    if (lua_stringtonumber(L, s) != 0)
        return;
    v = strtod(s, &end);
    if (*s == '\0')
        lua_pushnumber(L, NAN);
    else if (*end == '\0')
        lua_pushnumber(L, v);
    else
        lua_pushvalue(L, f);
}

/* Value of token `key=` in the meta line, pushed (or nil). */
static void push_meta_token(lua_State *L, const char *meta, const char *key)
{
    size_t kl = strlen(key);
    const char *p = meta;
    while ((p = strstr(p, key)) != NULL) {
        if ((p == meta || p[-1] == ' ') && p[kl] == '=') {
            const char *v = p + kl + 1, *e = strchr(v, ' ');
            lua_pushlstring(L, v, e ? (size_t)(e - v) : strlen(v));
            return;
        }
        p += kl;
    }
    lua_pushnil(L);
}

/* Push a Lua array of the comma-separated names in the string at top. */
static void split_names(lua_State *L)
{
    const char *s = lua_tostring(L, -1);
    int k = 0;
    lua_newtable(L);
    while (s != NULL && *s != '\0') {
        const char *e = strchr(s, ',');
        size_t len = e ? (size_t)(e - s) : strlen(s);
        lua_pushlstring(L, s, len);
        lua_rawseti(L, -2, ++k);
        s += len + (e ? 1 : 0);
    }
    lua_remove(L, -2);
}

/* Push the result table of the ensemble file at `path`. */
void dfle_lua_ens_push_result(lua_State *L, const char *fn, const char *path, size_t shard_i,
                        size_t shard_n, lua_Integer ran)
{
    run_box *box = dfle_lua_ens_new_box(L);
    dfle_error err;
    dfle_ens_table *t;
    int res, data, inputs, outputs, header, counts;
    lua_Integer n = 0, nin, nout, ncols, ok = 0;
    unsigned char quoted[4096];

    if (dfle_ens_table_read(path, &box->table, &err) != DFLE_OK)
        luaL_error(L, "dfle.%s: %s", fn, err.msg);
    t = box->table;
    lua_newtable(L);
    res = lua_gettop(L);
    luaL_setmetatable(L, RESULT_MT);
    push_meta_token(L, t->meta, "n");
    n = lua_isnil(L, -1) ? 0 : (lua_Integer)lua_tointeger(L, -1);
    if (strncmp(t->meta, "# dfle.ensemble ", 16) != 0 || n < 1)
        luaL_error(L, "dfle.%s: %s: not a dfle.ensemble file (first line '%s')", fn, path, t->meta);
    lua_pop(L, 1);
    push_meta_token(L, t->meta, "inputs");
    split_names(L);
    inputs = lua_gettop(L);
    push_meta_token(L, t->meta, "outputs");
    split_names(L);
    outputs = lua_gettop(L);
    nin = (lua_Integer)lua_rawlen(L, inputs);
    nout = (lua_Integer)lua_rawlen(L, outputs);
    lua_pushstring(L, t->header);
    split_names(L);
    header = lua_gettop(L);
    ncols = (lua_Integer)lua_rawlen(L, header);
    if (ncols != nin + nout + 3)
        luaL_error(L, "dfle.%s: %s: header and first line disagree", fn, path);
    lua_newtable(L);
    data = lua_gettop(L);
    for (lua_Integer c = 1; c <= ncols; c++) {
        lua_geti(L, header, c);
        lua_createtable(L, (int)t->nrows, 0);
        lua_settable(L, data);
    }
    lua_newtable(L);
    counts = lua_gettop(L);
    luaL_checkstack(L, (int)ncols + 8, "too many columns");
    for (size_t r = 0; r < t->nrows; r++) {
        int base = lua_gettop(L);
        int nf = push_fields(L, t->rows[r], quoted, (int)sizeof quoted, (int)ncols + 1);
        if (nf != ncols)
            luaL_error(L, "dfle.%s: %s: sample %d has %d fields, the header %d", fn, path,
                       (int)t->index[r], nf, (int)ncols);
        for (lua_Integer c = 1; c <= ncols; c++) {
            int f = base + (int)c;
            lua_geti(L, header, c);
            lua_gettable(L, data);
            if (c == 1)
                lua_pushinteger(L, (lua_Integer)t->index[r]);
            else if (c >= ncols - 1 || (c - 1 < (lua_Integer)sizeof quoted && quoted[c - 1]))
                lua_pushvalue(L, f); /* status, reason, text parameters */
            else
                push_field_number(L, f);
            lua_rawseti(L, -2, (lua_Integer)r + 1);
            lua_pop(L, 1);
        }
        /* status count */
        lua_pushvalue(L, base + (int)ncols - 1);
        lua_pushvalue(L, -1);
        lua_gettable(L, counts);
        lua_pushinteger(L, lua_tointeger(L, -1) + 1);
        lua_remove(L, -2);
        lua_settable(L, counts);
        if (strcmp(lua_tostring(L, base + (int)ncols - 1), "ok") == 0)
            ok++;
        lua_settop(L, base);
    }
    lua_pushvalue(L, data), lua_setfield(L, res, "data");
    lua_pushvalue(L, inputs), lua_setfield(L, res, "inputs");
    lua_pushvalue(L, outputs), lua_setfield(L, res, "outputs");
    lua_pushvalue(L, counts), lua_setfield(L, res, "status");
    lua_pushinteger(L, n), lua_setfield(L, res, "n");
    lua_pushinteger(L, (lua_Integer)t->nrows), lua_setfield(L, res, "count");
    lua_pushinteger(L, ok), lua_setfield(L, res, "ok");
    lua_pushinteger(L, (lua_Integer)t->nrows - ok), lua_setfield(L, res, "failed");
    lua_pushinteger(L, ran), lua_setfield(L, res, "ran");
    lua_pushboolean(L, (lua_Integer)t->nrows == n), lua_setfield(L, res, "complete");
    lua_pushstring(L, path), lua_setfield(L, res, "file");
    if (shard_n > 1) {
        lua_createtable(L, 2, 0);
        lua_pushinteger(L, (lua_Integer)shard_i), lua_rawseti(L, -2, 1);
        lua_pushinteger(L, (lua_Integer)shard_n), lua_rawseti(L, -2, 2);
        lua_setfield(L, res, "shard");
    }
    lua_pushvalue(L, res);
    dfle_ens_table_free(box->table);
    box->table = NULL;
}

