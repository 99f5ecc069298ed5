/*
 * lua_type.c - the one mechanism behind every dfle object type in Lua
 * (dfle.channel, dfle.model, dfle.dem, ...).
 *
 * An object is a full userdata holding one pointer, NULL until the C
 * constructor succeeds, so it is valid (empty) before anything can fail.
 * A type is described once (dfle_lua_type) and registered by one call;
 * its __gc (and __close, where scripts may close it early) is generic:
 * it frees the pointer through the type's free function and clears it,
 * so it is idempotent, and every object says "<type> (closed)" once
 * closed.  The binding files only supply what differs: the free
 * function, the description, the methods and the read-only fields.
 */
#include "lua/core/dfle_lua.h"

#include <string.h>

void *dfle_lua_newobject(lua_State *L, size_t size, const char *tname, int nuv)
{
    void *p = lua_newuserdatauv(L, size, nuv);
    memset(p, 0, size);
    luaL_setmetatable(L, tname);
    return p;
}

/* __gc and __close: upvalue 1 is the type. */
static int object_gc(lua_State *L)
{
    const dfle_lua_type *t = lua_touserdata(L, lua_upvalueindex(1));
    void **p = luaL_checkudata(L, 1, t->name);
    if (*p != NULL) {
        t->free(*p);
        *p = NULL;
    }
    return 0;
}

/* __tostring: upvalue 1 is the type. */
static int object_tostring(lua_State *L)
{
    const dfle_lua_type *t = lua_touserdata(L, lua_upvalueindex(1));
    void **p = luaL_checkudata(L, 1, t->name);
    lua_settop(L, 1);
    if (*p == NULL)
        lua_pushfstring(L, "%s (closed)", t->name);
    else
        t->describe(L, *p);
    return 1;
}

/* __index: methods first, then the type's read-only properties.
 * Upvalues: the methods table, the type. */
static int object_index(lua_State *L)
{
    const dfle_lua_type *t = lua_touserdata(L, lua_upvalueindex(2));
    lua_pushvalue(L, 2);
    if (lua_rawget(L, lua_upvalueindex(1)) != LUA_TNIL)
        return 1;
    lua_pop(L, 1);
    if (t->property != NULL && lua_type(L, 2) == LUA_TSTRING)
        return t->property(L);
    return 0;
}

void dfle_lua_register(lua_State *L, const dfle_lua_type *t)
{
    if (!luaL_newmetatable(L, t->name)) {
        lua_pop(L, 1);
        return;
    }
    if (t->meta != NULL)
        luaL_setfuncs(L, t->meta, 0);
    lua_pushlightuserdata(L, (void *)t);
    lua_pushcclosure(L, object_gc, 1);
    if (t->closable) {
        lua_pushvalue(L, -1);
        lua_setfield(L, -3, "__close");
    }
    lua_setfield(L, -2, "__gc");
    lua_pushlightuserdata(L, (void *)t);
    lua_pushcclosure(L, object_tostring, 1);
    lua_setfield(L, -2, "__tostring");
    lua_newtable(L);
    if (t->methods != NULL)
        luaL_setfuncs(L, t->methods, 0);
    lua_pushlightuserdata(L, (void *)t);
    lua_pushcclosure(L, object_index, 2);
    lua_setfield(L, -2, "__index");
    /* Scripts must not reach __gc: freeing a component a model still
     * uses would leave the model reading freed memory. */
    lua_pushliteral(L, "dfle objects do not share their metatable");
    lua_setfield(L, -2, "__metatable");
    lua_pop(L, 1);
}

void *dfle_lua_check_object(lua_State *L, int arg, const char *tname)
{
    void **p = luaL_checkudata(L, arg, tname);
    if (*p == NULL)
        luaL_argerror(L, arg, lua_pushfstring(L, "%s has been closed", tname));
    return *p;
}

dfle_channel *dfle_lua_check_channel(lua_State *L, int arg)
{
    return dfle_lua_check_object(L, arg, DFLE_LUA_CHANNEL);
}
dfle_fluvial *dfle_lua_check_fluvial(lua_State *L, int arg)
{
    return dfle_lua_check_object(L, arg, DFLE_LUA_FLUVIAL);
}
dfle_router *dfle_lua_check_router(lua_State *L, int arg)
{
    return dfle_lua_check_object(L, arg, DFLE_LUA_ROUTER);
}
dfle_law *dfle_lua_check_law(lua_State *L, int arg)
{
    return dfle_lua_check_object(L, arg, DFLE_LUA_LAW);
}
dfle_model *dfle_lua_check_model(lua_State *L, int arg)
{
    dfle_lua_touch(L); /* the script may have changed what a compiled law read */
    return dfle_lua_check_object(L, arg, DFLE_LUA_MODEL);
}

const char *dfle_lua_typename(lua_State *L, int idx)
{
    if (luaL_getmetafield(L, idx, "__name") == LUA_TSTRING)
        return lua_tostring(L, -1); /* left on the stack, so it stays valid */
    return luaL_typename(L, idx);
}
