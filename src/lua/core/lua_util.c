/*
 * lua_util.c - the pieces every binding file uses: checked option
 * tables, error raising, numbers as text, tables and arrays, text built
 * from pieces, slope-area data.
 */
#include "lua/core/dfle_lua.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include "dfle/plausible.h"

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
    const char *s;
    /* A field read onto the stack is no argument: luaL_checklstring would
     * say "bad argument #-2 to 'run'". */
    if (idx < 0 && lua_type(L, idx) != LUA_TSTRING && lua_type(L, idx) != LUA_TNUMBER)
        luaL_error(L, "dfle.%s: %s must be a string, got %s", fn, what, luaL_typename(L, idx));
    s = luaL_checklstring(L, idx, &len);
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
            dfle_lua_warn_implausible(L, fn, params[i].name, v);
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
    if (luaL_testudata(L, arg, "dfle.profile") != NULL ||
        luaL_testudata(L, arg, "dfle.landscape") != NULL) { /* lua_landscape.c: channel cells */
        /* Closed, it would fail inside the call below, which has no
         * position of the script's to give. */
        dfle_lua_check_object(L, arg, luaL_testudata(L, arg, "dfle.profile") != NULL
                                          ? "dfle.profile" : "dfle.landscape");
        /* A landscape that has not run is its start (noise, z or a DEM):
         * fitted, it gave Eq. (2) of random slopes without a word. */
        if (luaL_testudata(L, arg, "dfle.landscape") != NULL &&
            lua_getfield(L, arg, "has_run") == LUA_TBOOLEAN && !lua_toboolean(L, -1))
            luaL_error(L, "dfle.%s: the landscape has not run: its surface is the start it was "
                          "built with (noise, z or a DEM), not a landscape of the model; run it "
                          "first (ls:run_to_steady{}), or measure a DEM with dem:network{}", fn);
        lua_getfield(L, arg, "slope_area");
        lua_pushvalue(L, arg);
        lua_call(L, 1, 1);
        arg = lua_gettop(L);
    }
    /* --- end dfle.profile --- */
    if (!lua_istable(L, arg))
        luaL_error(L, "dfle.%s: expected a dfle.model, a dfle.profile, a dfle.landscape or a table "
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

/* Push, as one string, the keys of the table at idx, sorted. */
const char *dfle_lua_push_sorted_keys(lua_State *L, int idx)
{
    luaL_Buffer b;
    int n = 0, list;
    idx = lua_absindex(L, idx);
    lua_newtable(L);
    list = lua_gettop(L);
    lua_pushnil(L);
    while (lua_next(L, idx) != 0) {
        lua_pop(L, 1);
        if (lua_type(L, -1) == LUA_TSTRING) {
            lua_pushvalue(L, -1);
            lua_rawseti(L, list, ++n);
        }
    }
    lua_getglobal(L, "table");
    if (lua_getfield(L, -1, "sort") == LUA_TFUNCTION) {
        lua_pushvalue(L, list);
        lua_call(L, 1, 0);
    } else {
        lua_pop(L, 1);
    }
    lua_pop(L, 1);
    luaL_buffinit(L, &b);
    for (int k = 1; k <= n; k++) {
        lua_rawgeti(L, list, k);
        if (k > 1)
            luaL_addstring(&b, ", ");
        luaL_addvalue(&b);
    }
    luaL_pushresult(&b);
    return lua_tostring(L, -1);
}

/* __index of a strict table: upvalue 1 names it. */
static int strict_index(lua_State *L)
{
    const char *keys = dfle_lua_push_sorted_keys(L, 1);
    return luaL_error(L, "%s has no field '%s' (fields: %s)", lua_tostring(L, lua_upvalueindex(1)),
                      lua_type(L, 2) == LUA_TSTRING ? dfle_lua_shown(L, lua_tostring(L, 2),
                                                                     lua_rawlen(L, 2))
                                                    : luaL_typename(L, 2),
                      keys);
}

void dfle_lua_strict_table(lua_State *L, int idx, const char *what)
{
    idx = lua_absindex(L, idx);
    lua_createtable(L, 0, 1);
    lua_pushstring(L, what);
    lua_pushcclosure(L, strict_index, 1);
    lua_setfield(L, -2, "__index");
    lua_setmetatable(L, idx);
}

/* Warnings go through Lua's own channel (lua_warning): the dfle command
 * prints them on stderr, a host embedding the module decides for itself,
 * and a script may say warn("@off").  Each (function, parameter) warns
 * once per state, so an ensemble or a loop over models does not repeat
 * the same sentence a thousand times. */
void dfle_lua_warn_implausible(lua_State *L, const char *fn, const char *name, double v)
{
    static const char warned_key = 'w';
    char msg[400];
    if (!dfle_plausible_check(name, v, msg, sizeof msg))
        return;
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &warned_key) != LUA_TTABLE) {
        lua_pop(L, 1);
        lua_newtable(L);
        lua_pushvalue(L, -1);
        lua_rawsetp(L, LUA_REGISTRYINDEX, &warned_key);
    }
    lua_pushfstring(L, "%s.%s", fn, name);
    if (lua_rawget(L, -2) != LUA_TNIL) {
        lua_pop(L, 2);
        return;
    }
    lua_pop(L, 1);
    lua_pushfstring(L, "%s.%s", fn, name);
    lua_pushboolean(L, 1);
    lua_rawset(L, -3);
    lua_pop(L, 1);
    dfle_lua_warn(L, fn, msg);
}

void dfle_lua_warn(lua_State *L, const char *fn, const char *msg)
{
    luaL_where(L, 1);
    lua_pushfstring(L, "%sdfle.%s: %s", lua_tostring(L, -1), fn, msg);
    lua_warning(L, lua_tostring(L, -1), 0);
    lua_pop(L, 2);
}

const char *dfle_lua_push_history(lua_State *L)
{
    char when[32];
    time_t now = time(NULL);
    struct tm utc;
    luaL_Buffer b;
    lua_Integer lo = 0, hi;

    if (gmtime_r(&now, &utc) == NULL || strftime(when, sizeof when, "%Y-%m-%dT%H:%M:%SZ", &utc) == 0)
        snprintf(when, sizeof when, "(unknown time)");
    int a;
    lua_getglobal(L, "arg");
    a = lua_gettop(L);
    if (lua_istable(L, a)) {
        while (lo > -64 && lua_rawgeti(L, a, lo - 1) == LUA_TSTRING) {
            lua_pop(L, 1);
            lo--;
        }
        lua_pop(L, 1);
    }
    luaL_buffinit(L, &b);
    luaL_addstring(&b, when);
    luaL_addstring(&b, ":");
    if (lua_istable(L, a)) {
        hi = (lua_Integer)lua_rawlen(L, a);
        for (lua_Integer i = lo; i <= hi && i - lo < 256; i++) {
            if (lua_rawgeti(L, a, i) == LUA_TSTRING) {
                luaL_addchar(&b, ' ');
                luaL_addvalue(&b);
            } else {
                lua_pop(L, 1);
            }
        }
    } else {
        luaL_addstring(&b, " dfle (embedded)");
    }
    luaL_pushresult(&b);
    lua_remove(L, -2);
    return lua_tostring(L, -1);
}

void dfle_lua_text_init(lua_State *L, dfle_lua_text *p)
{
    lua_newtable(L);
    p->t = lua_gettop(L);
    p->k = 0;
}

void dfle_lua_text_add(lua_State *L, dfle_lua_text *p)
{
    lua_rawseti(L, p->t, ++p->k);
}

void dfle_lua_text_str(lua_State *L, dfle_lua_text *p, const char *s)
{
    lua_pushstring(L, s);
    dfle_lua_text_add(L, p);
}

void dfle_lua_text_finish(lua_State *L, dfle_lua_text *p)
{
    luaL_Buffer b;
    lua_settop(L, p->t);
    luaL_buffinit(L, &b);
    for (lua_Integer k = 1; k <= p->k; k++) {
        lua_rawgeti(L, p->t, k);
        luaL_addvalue(&b);
    }
    luaL_pushresult(&b);
    lua_replace(L, p->t);
}

const char *dfle_lua_opt_string(lua_State *L, int idx, const char *key, const char *fn)
{
    const char *s = NULL;
    if (lua_istable(L, idx)) {
        int t = lua_getfield(L, idx, key);
        if (t != LUA_TNIL && t != LUA_TSTRING)
            luaL_error(L, "dfle.%s: parameter '%s' must be a string, got %s", fn, key,
                       luaL_typename(L, -1));
        s = t == LUA_TNIL ? NULL : dfle_lua_check_string(L, -1, fn, key); /* the table holds it */
        lua_pop(L, 1);
    }
    return s;
}

int dfle_lua_check_method(lua_State *L, int idx, const char *fn)
{
    const char *names[DFLE_METHOD_AUTO + 2];
    for (int k = 0; k <= DFLE_METHOD_AUTO; k++)
        names[k] = dfle_method_name(k);
    names[DFLE_METHOD_AUTO + 1] = NULL;
    /* dfle_method_lookup is the one place the names are looked up;
     * the list only makes the message */
    {
        int m = dfle_method_lookup(dfle_lua_check_string(L, idx, fn, "method"));
        if (m >= 0)
            return m;
    }
    return dfle_lua_check_option(L, idx, fn, "method", names);
}

int dfle_lua_check_option(lua_State *L, int idx, const char *fn, const char *what,
                          const char *const *choices)
{
    const char *name = dfle_lua_check_string(L, idx, fn, what);
    luaL_Buffer b;
    int k;

    for (k = 0; choices[k] != NULL; k++)
        if (strcmp(choices[k], name) == 0)
            return k;
    luaL_buffinit(L, &b);
    for (k = 0; choices[k] != NULL; k++) {
        if (k > 0)
            luaL_addstring(&b, choices[k + 1] == NULL ? " or " : ", ");
        lua_pushfstring(L, "'%s'", choices[k]);
        luaL_addvalue(&b);
    }
    luaL_pushresult(&b);
    {
        const char *list = lua_tostring(L, -1);
        const char *shown = dfle_lua_shown(L, name, strlen(name));
        return luaL_error(L, "dfle.%s: %s must be %s (got '%s')", fn, what, list, shown);
    }
}

const char *dfle_lua_known_unit(const char *name)
{
    static const char *const units[][2] = {
        {"U", "m/yr"}, {"M0", "m^(3-2 gamma)"}, {"tau_y", "Pa"}, {"mu", "Pa s"},
        {"rho_b", "kg/m^3"}, {"k_e", "m^2.5 s^2 kg^-1.5"}, {"S_df", "-"}, {"A_df", "m^2"},
        {"S_max", "-"}, {"S_ch", "-"}, {"S_max_minus_S_ch", "-"}, {"r2", "-"},
        {"runout_A", "m^2"}, {"runout_x", "m"}, {"time", "yr"}, {"steps", "-"}, {"gamma", "-"},
        {"alpha", "-"}, {"beta", "-"}, {"sigma", "-"}};
    for (size_t k = 0; k < sizeof units / sizeof units[0]; k++)
        if (strcmp(name, units[k][0]) == 0)
            return units[k][1];
    return NULL;
}
