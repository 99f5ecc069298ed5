/*
 * lua_params.c - a router's or law's parameters as Lua sees them:
 * x:params(), x.<param> and tostring(x), for any kind of component.
 *
 * They come from the component's params op (param.h), so the binding
 * never asks which kind it holds; a component written in Lua has no such
 * op and keeps its own table instead (user value 2 of its object,
 * lua_shell.h), which is read the same way.
 */
#include "lua/core/dfle_lua.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The component's parameter list in a scratch userdata left on the
 * stack; NULL, with nothing pushed, when it has no params op. */
static const dfle_param *param_list(lua_State *L, dfle_lua_params_fn fn, const void *comp,
                                    size_t *n)
{
    size_t count = fn(comp, NULL, 0);
    dfle_param *p;
    if (count == (size_t)-1)
        return NULL;
    p = lua_newuserdatauv(L, (count ? count : 1) * sizeof *p, 0);
    fn(comp, p, count);
    *n = count;
    return p;
}

void dfle_lua_push_params(lua_State *L, int obj, dfle_lua_params_fn fn, const void *comp)
{
    size_t n = 0;
    const dfle_param *p;

    obj = lua_absindex(L, obj);
    lua_newtable(L);
    if ((p = param_list(L, fn, comp, &n)) == NULL) {
        if (lua_getiuservalue(L, obj, 2) == LUA_TTABLE)
            dfle_lua_copy_table(L, -1, -2);
        lua_pop(L, 1);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        if (p[i].is_switch)
            lua_pushboolean(L, p[i].value != 0);
        else
            lua_pushnumber(L, p[i].value);
        lua_setfield(L, -3, p[i].name);
    }
    lua_pop(L, 1); /* the list */
}

int dfle_lua_push_param_field(lua_State *L, const char *name, dfle_lua_params_fn fn,
                              const void *comp)
{
    const char *key = lua_tostring(L, 2);
    if (strcmp(key, "name") == 0) {
        lua_pushstring(L, name);
        return 1;
    }
    dfle_lua_push_params(L, 1, fn, comp);
    if (lua_getfield(L, -1, key) == LUA_TNIL)
        return 0; /* not a parameter: __index says so */
    return 1;
}

/* A number as tostring(x) shows parameters: short, like the C library's
 * messages. */
static void format_number(char *buf, size_t len, double v)
{
    snprintf(buf, len, "%g", v);
}

static int by_text(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

/* Push "k = v" for every entry of the table at t, sorted, as an array of
 * strings (a table has no order of its own; a description must not
 * change from one run to the next). */
static void push_table_items(lua_State *L, int t)
{
    const char **item;
    size_t n = 0, i = 0;
    int items;

    t = lua_absindex(L, t);
    lua_pushnil(L);
    while (lua_next(L, t) != 0) {
        lua_pop(L, 1);
        n++;
    }
    item = lua_newuserdatauv(L, (n ? n : 1) * sizeof *item, 0);
    lua_createtable(L, (int)n, 0);
    items = lua_gettop(L);
    lua_pushnil(L);
    while (lua_next(L, t) != 0) {
        char num[32];
        /* luaL_tolstring pushes a copy: the key lua_next needs stays. */
        const char *k = luaL_tolstring(L, -2, NULL);
        if (lua_type(L, -2) == LUA_TNUMBER) {
            format_number(num, sizeof num, lua_tonumber(L, -2));
            lua_pushfstring(L, "%s = %s", k, num);
        } else {
            lua_pushfstring(L, "%s = %s", k, luaL_tolstring(L, -2, NULL));
            lua_remove(L, -2);
        }
        item[i] = lua_tostring(L, -1);
        lua_rawseti(L, items, (lua_Integer)++i); /* keeps the string alive */
        lua_pop(L, 2); /* the key's text, the value */
    }
    qsort(item, n, sizeof *item, by_text);
    /* A new array: every string stays anchored in the old one while the
     * sorted copy is made. */
    lua_createtable(L, (int)n, 0);
    for (i = 0; i < n; i++) {
        lua_pushstring(L, item[i]);
        lua_rawseti(L, -2, (lua_Integer)i + 1);
    }
    lua_replace(L, items - 1);
    lua_settop(L, items - 1);
}

void dfle_lua_push_described(lua_State *L, int obj, const char *prefix, const char *name,
                             dfle_lua_params_fn fn, const void *comp)
{
    luaL_Buffer b;
    size_t n = 0;
    const dfle_param *p;
    int items = 0;
    const int top = lua_gettop(L);

    obj = lua_absindex(L, obj);
    p = param_list(L, fn, comp, &n);
    if (p == NULL) {
        if (lua_getiuservalue(L, obj, 2) != LUA_TTABLE)
            lua_newtable(L);
        push_table_items(L, -1);
        items = lua_gettop(L);
        n = lua_rawlen(L, items);
    }
    luaL_buffinit(L, &b);
    luaL_addstring(&b, prefix);
    luaL_addchar(&b, '.');
    luaL_addstring(&b, name);
    luaL_addchar(&b, '(');
    for (size_t i = 0; i < n; i++) {
        if (i > 0)
            luaL_addstring(&b, ", ");
        if (p == NULL) {
            lua_rawgeti(L, items, (lua_Integer)i + 1);
            luaL_addvalue(&b);
            continue;
        }
        luaL_addstring(&b, p[i].name);
        luaL_addstring(&b, " = ");
        if (p[i].is_switch) {
            luaL_addstring(&b, p[i].value != 0 ? "true" : "false");
        } else {
            char num[32];
            format_number(num, sizeof num, p[i].value);
            luaL_addstring(&b, num);
        }
        if (p[i].unit != NULL && p[i].unit[0] != '\0') {
            luaL_addchar(&b, ' ');
            luaL_addstring(&b, p[i].unit);
        }
    }
    luaL_addchar(&b, ')');
    luaL_pushresult(&b);
    lua_replace(L, top + 1); /* only the description stays */
    lua_settop(L, top + 1);
}
