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
    void *p;
    /* Every payload starts like a dfle_lua_object (dfle_lua.h). */
    if (size < sizeof(dfle_lua_object))
        size = sizeof(dfle_lua_object);
    p = lua_newuserdatauv(L, size, nuv);
    memset(p, 0, size);
    luaL_setmetatable(L, tname);
    return p;
}

/* Free the C object of the payload at idx now, and let go of what it held. */
static void free_now(lua_State *L, int idx, const dfle_lua_type *t, dfle_lua_object *o)
{
    void *p = o->ptr;
    o->ptr = NULL;
    o->doomed = 0;
    t->free(p);
    if (t->release != NULL)
        t->release(L, idx);
}

/* The type of the object at idx (its metatable's __dfle_type field). */
static const dfle_lua_type *type_of(lua_State *L, int idx)
{
    const dfle_lua_type *t = NULL;
    if (lua_getmetatable(L, idx)) {
        lua_getfield(L, -1, "__dfle_type");
        t = lua_touserdata(L, -1);
        lua_pop(L, 2);
    }
    return t;
}

/* Closed: freed, or doomed and used by nothing any more.  The second
 * kind is what a call leaves when its object was closed (or collected by
 * hand) from inside it: the call still holds pointers into the object
 * after it ends its use (a model's field values, a router's report), so
 * the memory goes only at the next __gc, the collector's once nothing
 * can reach it. */
static int is_closed(const dfle_lua_object *o)
{
    return o->ptr == NULL || (o->doomed && o->busy == 0 && o->holders == 0);
}

/* Free it if it was doomed and nothing uses it any more. */
static void free_if_unused(lua_State *L, int idx, dfle_lua_object *o)
{
    const dfle_lua_type *t;
    if (o->doomed && o->ptr != NULL && o->busy == 0 && o->holders == 0 &&
        (t = type_of(L, idx)) != NULL)
        free_now(L, idx, t, o);
}

/* __gc: upvalue 1 is the type.  Never raises (it may run as a finalizer);
 * an object still in use is only marked: its last holder frees it, or,
 * if a call was using it, its next __gc. */
static int object_gc(lua_State *L)
{
    const dfle_lua_type *t = lua_touserdata(L, lua_upvalueindex(1));
    dfle_lua_object *o = luaL_checkudata(L, 1, t->name);
    if (o->ptr == NULL)
        return 0;
    if (o->busy > 0 || o->holders > 0) {
        o->doomed = 1;
        return 0;
    }
    free_now(L, 1, t, o);
    return 0;
}

/* __close (local x <close>): as __gc, but closing an object while a call
 * on it runs is a mistake worth an error. */
static int object_close(lua_State *L)
{
    const dfle_lua_type *t = lua_touserdata(L, lua_upvalueindex(1));
    dfle_lua_object *o = luaL_checkudata(L, 1, t->name);
    if (o->ptr != NULL && o->busy > 0)
        return luaL_error(L, "%s: cannot close it while it is running (it was closed from "
                             "inside its own U(t), law or router); close it after the run",
                          t->name);
    return object_gc(L);
}

dfle_lua_object *dfle_lua_begin_use(lua_State *L, int idx, const char *what)
{
    dfle_lua_object *o = lua_touserdata(L, idx);
    const dfle_lua_type *t = type_of(L, idx);
    if (o == NULL || t == NULL)
        luaL_error(L, "dfle: %s: not a dfle object", what);
    if (is_closed(o))
        luaL_error(L, "%s: %s has been closed", what, t->name);
    if (o->busy > 0)
        luaL_error(L, "%s: the %s is running already: it cannot be used from inside its own "
                      "U(t), law or router", what, t->name + 5);
    o->busy++;
    return o;
}

void dfle_lua_end_use(lua_State *L, int idx)
{
    dfle_lua_object *o = lua_touserdata(L, idx);
    (void)L;
    if (o != NULL && o->busy > 0)
        o->busy--; /* a doomed object is now closed, freed by its next __gc */
}

void dfle_lua_hold(lua_State *L, int idx)
{
    dfle_lua_object *o = lua_touserdata(L, idx);
    if (o != NULL)
        o->holders++;
}

void dfle_lua_unhold(lua_State *L, int idx)
{
    dfle_lua_object *o = lua_touserdata(L, idx);
    if (o != NULL && o->holders > 0) {
        o->holders--;
        free_if_unused(L, idx, o);
    }
}

/* __tostring: upvalue 1 is the type. */
static int object_tostring(lua_State *L)
{
    const dfle_lua_type *t = lua_touserdata(L, lua_upvalueindex(1));
    dfle_lua_object *o = luaL_checkudata(L, 1, t->name);
    lua_settop(L, 1);
    if (is_closed(o))
        lua_pushfstring(L, "%s (closed)", t->name);
    else
        t->describe(L, o->ptr);
    return 1;
}

/* __index: methods first, then the type's read-only properties; a key
 * that is neither raises, naming the fields and methods there are (a
 * misspelt m.cfl or a dot for a colon would otherwise read as nil and
 * fail later, far from the mistake).  Upvalues: the methods table, the
 * type. */
static int object_index(lua_State *L)
{
    const dfle_lua_type *t = lua_touserdata(L, lua_upvalueindex(2));
    const char *fields;
    lua_pushvalue(L, 2);
    if (lua_rawget(L, lua_upvalueindex(1)) != LUA_TNIL)
        return 1;
    lua_pop(L, 1);
    if (lua_type(L, 2) == LUA_TSTRING) {
        size_t len;
        const char *key = lua_tolstring(L, 2, &len);
        if (strlen(key) != len) /* "time\0x" must not read as time */
            return luaL_error(L, "%s: no field '%s' (a NUL byte in the name)", t->name,
                              dfle_lua_shown(L, key, len));
        if (t->property != NULL) {
            int top = lua_gettop(L), r = t->property(L);
            if (r > 0)
                return r;
            lua_settop(L, top);
        }
    }
    if (t->fields != NULL) {
        fields = t->fields;
    } else if (lua_getfield(L, lua_upvalueindex(1), "params") == LUA_TFUNCTION) {
        /* The object's parameters are its fields (the method itself, read
         * from the methods table: indexing the object would come back here). */
        /* Protected: called by hand with no live object (debug.getmetatable
         * hands scripts this function), params would raise from here, a C
         * frame, without the script's position that the error below gives. */
        lua_pushvalue(L, 1);
        if (lua_pcall(L, 1, 1, 0) == LUA_OK && lua_istable(L, -1))
            fields = lua_pushfstring(L, "name, %s", dfle_lua_push_sorted_keys(L, -1));
        else
            fields = lua_pushfstring(L, "none readable (not a live %s)", t->name);
    } else {
        fields = "none";
    }
    return luaL_error(L, "%s has no field '%s' (fields: %s; methods: %s)", t->name,
                      lua_type(L, 2) == LUA_TSTRING ? dfle_lua_shown(L, lua_tostring(L, 2),
                                                                     lua_rawlen(L, 2))
                                                    : luaL_tolstring(L, 2, NULL),
                      fields, dfle_lua_push_sorted_keys(L, lua_upvalueindex(1)));
}

/* __newindex: every field is read-only. */
static int object_newindex(lua_State *L)
{
    const dfle_lua_type *t = lua_touserdata(L, lua_upvalueindex(1));
    const char *key = lua_type(L, 2) == LUA_TSTRING ? lua_tostring(L, 2) : "?";
    if (t->setters != NULL)
        return luaL_error(L, "%s: field '%s' is read-only (to change: %s)", t->name, key,
                          t->setters);
    return luaL_error(L, "%s: field '%s' is read-only (make a new %s to change it)", t->name, key,
                      t->name);
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
    lua_setfield(L, -2, "__dfle_type");
    lua_pushlightuserdata(L, (void *)t);
    lua_pushcclosure(L, object_gc, 1);
    lua_setfield(L, -2, "__gc");
    if (t->closable) {
        lua_pushlightuserdata(L, (void *)t);
        lua_pushcclosure(L, object_close, 1);
        lua_setfield(L, -2, "__close");
    }
    lua_pushlightuserdata(L, (void *)t);
    lua_pushcclosure(L, object_tostring, 1);
    lua_setfield(L, -2, "__tostring");
    lua_newtable(L);
    if (t->methods != NULL)
        luaL_setfuncs(L, t->methods, 0);
    lua_pushlightuserdata(L, (void *)t);
    lua_pushcclosure(L, object_index, 2);
    lua_setfield(L, -2, "__index");
    lua_pushlightuserdata(L, (void *)t);
    lua_pushcclosure(L, object_newindex, 1);
    lua_setfield(L, -2, "__newindex");
    /* Scripts must not reach __gc: freeing a component a model still
     * uses would leave the model reading freed memory. */
    lua_pushliteral(L, "dfle objects do not share their metatable");
    lua_setfield(L, -2, "__metatable");
    lua_pop(L, 1);
}

/* A method of type tname called with a dot (m.run()) gets no object as
 * its first argument: say so, rather than "dfle.model expected". */
static void check_colon(lua_State *L, int arg, const char *tname)
{
    lua_Debug ar;
    /* What was passed, named before anything is pushed (index 1 may be
     * empty); dfle_lua_typename leaves its name on the stack. */
    const char *got = lua_isnone(L, 1) ? "no value" : dfle_lua_typename(L, 1);
    if (arg != 1 || luaL_testudata(L, 1, tname) != NULL || !lua_getstack(L, 0, &ar) ||
        !lua_getinfo(L, "n", &ar) || ar.name == NULL)
        return;
    if (luaL_getmetatable(L, tname) == LUA_TTABLE && lua_getfield(L, -1, "__index") != LUA_TNIL &&
        lua_getupvalue(L, -1, 1) != NULL && lua_getfield(L, -1, ar.name) == LUA_TFUNCTION)
        luaL_error(L, "%s:%s: call it with a colon, obj:%s(...), not a dot (the object is its "
                      "first argument; got %s)", tname, ar.name, ar.name, got);
}

void *dfle_lua_check_object(lua_State *L, int arg, const char *tname)
{
    dfle_lua_object *o;
    int top = lua_gettop(L);
    if (arg < 0) {
        /* A field read onto the stack is no argument: luaL_checkudata and
         * luaL_argerror would say "bad argument #-1 to 'invert'". */
        o = luaL_testudata(L, arg, tname);
        if (o == NULL)
            luaL_error(L, "%s expected, got %s", tname, dfle_lua_typename(L, arg));
        if (is_closed(o))
            luaL_error(L, "%s has been closed", tname);
        return o->ptr;
    }
    check_colon(L, arg, tname);
    lua_settop(L, top);
    o = luaL_checkudata(L, arg, tname);
    if (is_closed(o))
        luaL_argerror(L, arg, lua_pushfstring(L, "%s has been closed", tname));
    return o->ptr;
}

void *dfle_lua_object_ptr(lua_State *L, int idx)
{
    dfle_lua_object *o = lua_touserdata(L, idx);
    return o == NULL || is_closed(o) ? NULL : o->ptr;
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

const double *dfle_lua_model_field(lua_State *L, int idx, int field, const char *what)
{
    dfle_lua_model *u;
    const double *v;
    dfle_error err;
    idx = lua_absindex(L, idx);
    dfle_lua_check_model(L, idx);
    u = (dfle_lua_model *)dfle_lua_begin_use(L, idx, what);
    v = dfle_model_field(u->m, field, &err);
    dfle_lua_end_use(L, idx);
    if (v == NULL)
        dfle_lua_raise(L, &err);
    return v;
}
