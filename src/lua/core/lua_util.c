/*
 * lua_util.c - the pieces every binding file uses: checked option
 * tables, error raising, numbers as text, tables and arrays, slope-area
 * data.
 */
#include "lua/core/dfle_lua.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Format the list of known keys into the message buffer for an
 * "unknown parameter" error, so the user sees what was meant. */
static void push_known_keys(lua_State *L, const dfle_lua_param *params, size_t np,
                            const char *const *other)
{
    luaL_Buffer b;
    int first = 1;

    luaL_buffinit(L, &b);
    for (size_t i = 0; i < np; i++) {
        if (!first)
            luaL_addstring(&b, ", ");
        luaL_addstring(&b, params[i].name);
        first = 0;
    }
    for (size_t i = 0; other != NULL && other[i] != NULL; i++) {
        if (!first)
            luaL_addstring(&b, ", ");
        luaL_addstring(&b, other[i]);
        first = 0;
    }
    luaL_pushresult(&b);
}

static int is_known(const char *key, const dfle_lua_param *params, size_t np,
                    const char *const *other)
{
    for (size_t i = 0; i < np; i++)
        if (strcmp(key, params[i].name) == 0)
            return 1;
    for (size_t i = 0; other != NULL && other[i] != NULL; i++)
        if (strcmp(key, other[i]) == 0)
            return 1;
    return 0;
}

const char *dfle_lua_shown(lua_State *L, const char *s, size_t len)
{
    luaL_Buffer b;
    size_t k;
    luaL_buffinit(L, &b);
    for (k = 0; k < len && k < 60; k++) {
        unsigned char c = (unsigned char)s[k];
        if (c < 0x20 || c == 0x7f) {
            char esc[8];
            snprintf(esc, sizeof esc, "\\%03u", c);
            luaL_addstring(&b, esc);
        } else {
            luaL_addchar(&b, (char)c);
        }
    }
    if (k < len) {
        char more[48];
        snprintf(more, sizeof more, "... (%zu characters)", len);
        luaL_addstring(&b, more);
    }
    luaL_pushresult(&b);
    return lua_tostring(L, -1);
}

const char *dfle_lua_check_string(lua_State *L, int idx, const char *fn, const char *what)
{
    size_t len;
    const char *s = luaL_checklstring(L, idx, &len);
    if (strlen(s) != len)
        luaL_error(L, "dfle.%s: %s contains a NUL byte ('%s')", fn, what,
                   dfle_lua_shown(L, s, len));
    return s;
}

void dfle_lua_read_params(lua_State *L, int idx, const char *fn,
                          const dfle_lua_param *params, size_t np,
                          const char *const *other)
{
    idx = lua_absindex(L, idx);
    if (lua_isnoneornil(L, idx))
        return;
    if (!lua_istable(L, idx))
        luaL_error(L, "dfle.%s: expected a table of named parameters, got %s", fn,
                   luaL_typename(L, idx));
    lua_pushnil(L);
    while (lua_next(L, idx) != 0) {
        const char *key;
        if (lua_type(L, -2) != LUA_TSTRING)
            luaL_error(L, "dfle.%s: parameters are named (key = value); got a %s key", fn,
                       luaL_typename(L, -2));
        size_t klen;
        key = lua_tolstring(L, -2, &klen);
        /* A NUL ends the key for strcmp: "U\0x" would pass for U. */
        if (strlen(key) != klen || !is_known(key, params, np, other)) {
            const char *shown = dfle_lua_shown(L, key, klen);
            push_known_keys(L, params, np, other);
            luaL_error(L, "dfle.%s: unknown parameter '%s' (known: %s)", fn, shown,
                       lua_tostring(L, -1));
        }
        lua_pop(L, 1);
    }
    for (size_t i = 0; i < np; i++) {
        int t = lua_getfield(L, idx, params[i].name);
        if (t != LUA_TNIL) {
            double v;
            if (t != LUA_TNUMBER)
                luaL_error(L, "dfle.%s: parameter '%s' must be a number, got %s", fn,
                           params[i].name, dfle_lua_typename(L, -1));
            v = lua_tonumber(L, -1);
            if (!isfinite(v))
                luaL_error(L, "dfle.%s: parameter '%s' must be a finite number, got %s", fn,
                           params[i].name, dfle_lua_number_text(L, v));
            *params[i].dst = v;
        }
        lua_pop(L, 1);
    }
}

int dfle_lua_raise(lua_State *L, const dfle_error *err)
{
    return luaL_error(L, "dfle.%s", err->msg);
}

void dfle_lua_copy_table(lua_State *L, int src, int dst)
{
    src = lua_absindex(L, src);
    dst = lua_absindex(L, dst);
    lua_pushnil(L);
    while (lua_next(L, src) != 0) {
        lua_pushvalue(L, -2);
        lua_insert(L, -2);
        lua_rawset(L, dst);
    }
}

void dfle_lua_push_array(lua_State *L, const double *v, size_t n)
{
    lua_createtable(L, (int)n, 0);
    for (size_t i = 0; i < n; i++) {
        lua_pushnumber(L, v[i]);
        lua_rawseti(L, -2, (lua_Integer)i + 1);
    }
}

double *dfle_lua_check_array(lua_State *L, int idx, const char *what, size_t *n)
{
    double *v;
    lua_Unsigned len;

    idx = lua_absindex(L, idx);
    if (!lua_istable(L, idx))
        luaL_error(L, "dfle.%s must be an array of numbers, got %s", what,
                   luaL_typename(L, idx));
    len = lua_rawlen(L, idx);
    v = lua_newuserdatauv(L, (len ? len : 1) * sizeof *v, 0);
    for (lua_Unsigned i = 0; i < len; i++) {
        if (lua_rawgeti(L, idx, (lua_Integer)i + 1) != LUA_TNUMBER)
            luaL_error(L, "dfle.%s[%d] must be a number, got %s", what, (int)i + 1,
                       luaL_typename(L, -1));
        v[i] = lua_tonumber(L, -1);
        lua_pop(L, 1);
    }
    *n = (size_t)len;
    return v;
}

const char *dfle_lua_number_text(lua_State *L, double v)
{
    if (isnan(v))
        return lua_pushliteral(L, "NaN");
    if (isinf(v))
        return lua_pushstring(L, v > 0 ? "inf" : "-inf");
    return lua_pushfstring(L, "%f", v);
}

lua_Integer dfle_lua_check_whole(lua_State *L, double v, const char *fn, const char *name,
                                 double lo, double hi)
{
    if (!(v >= lo && v <= hi && v == floor(v)))
        luaL_error(L, "dfle.%s: %s must be a whole number in [%s, %s] (got %s)", fn, name,
                   dfle_lua_number_text(L, lo), dfle_lua_number_text(L, hi),
                   dfle_lua_number_text(L, v));
    return (lua_Integer)v;
}

size_t dfle_lua_slope_area(lua_State *L, int arg, const char *fn, const double **A,
                           const double **S)
{
    size_t n, nS;
    char what[80];

    arg = lua_absindex(L, arg);
    if (luaL_testudata(L, arg, DFLE_LUA_MODEL) != NULL) {
        dfle_model *m = dfle_lua_check_model(L, arg);
        char caller[96];
        snprintf(caller, sizeof caller, "dfle.%s", fn);
        *A = dfle_lua_model_field(L, arg, DFLE_FIELD_A, caller);
        *S = dfle_lua_model_field(L, arg, DFLE_FIELD_S, caller);
        /* The outlet is held at base level; its slope only repeats its
         * neighbour's, so it is not a data point. */
        return dfle_model_size(m) - 1;
    }
    /* --- dfle.profile (lua_dem.c): a DEM profile or network gives its
     * own pairs through p:slope_area(), a table read like a user's. --- */
    if (luaL_testudata(L, arg, "dfle.profile") != NULL) {
        /* Closed, it would fail inside the call below, which has no
         * position of the script's to give. */
        dfle_lua_check_object(L, arg, "dfle.profile");
        lua_getfield(L, arg, "slope_area");
        lua_pushvalue(L, arg);
        lua_call(L, 1, 1);
        arg = lua_gettop(L);
    }
    /* --- end dfle.profile --- */
    if (!lua_istable(L, arg))
        luaL_error(L, "dfle.%s: expected a dfle.model, a dfle.profile or a table "
                   "{A = {...}, S = {...}}, got %s", fn, dfle_lua_typename(L, arg));
    lua_getfield(L, arg, "A");
    snprintf(what, sizeof what, "%s: A", fn);
    *A = dfle_lua_check_array(L, -1, what, &n);
    lua_getfield(L, arg, "S");
    snprintf(what, sizeof what, "%s: S", fn);
    *S = dfle_lua_check_array(L, -1, what, &nS);
    if (n != nS)
        luaL_error(L, "dfle.%s: A has %d values but S has %d", fn, (int)n, (int)nS);
    return n;
}
