/*
 * lua_bridge_field.c - fields of models and landscapes read where they
 * lie (lua_bridge.h: dfle_bridge_get_field), so a host makes one copy,
 * or none, instead of going through a Lua table of numbers: an array
 * view of the object's own memory, kept valid by holding the object;
 * and the units the files give them.
 */
#include <string.h>

#include <lauxlib.h>

#include "lua/core/dfle_lua.h"
#include "lua/objects/lua_landscape.h"

#include "dfle/landscape.h"
#include "dfle/model.h"

#include "lua/bridge/lua_bridge_internal.h"

typedef struct {
    const char *name;
    dfle_bridge_field *f;
    int known;
} field_req;

/* The names the Lua get() uses in its messages (a closed object, one
 * running already), so that both routes say the same. */
#define MODEL_GET "dfle.model:get"
#define LANDSCAPE_GET "dfle.landscape:get"

/* (object, request) -> the value that keeps f->v valid (nil or a scratch
 * copy).  Leaves req->known 0 for anything it does not read itself. */
static int field_p(lua_State *L)
{
    field_req *q = lua_touserdata(L, 2);
    dfle_bridge_field *f = q->f;
    const char *type = dfle_lua_typename(L, 1);

    lua_settop(L, 1);
    if (strcmp(type, DFLE_LUA_MODEL) == 0) {
        int id = dfle_field_lookup(q->name);
        if (id < 0)
            return 0;
        f->v = dfle_lua_model_field(L, 1, id, MODEL_GET);
        f->n = f->nx = dfle_model_size(dfle_lua_check_model(L, 1));
        f->ny = 1;
        f->ndim = 1;
        /* The state and the geometry are always current; every other
         * field is as of the model's last evaluation, which the call
         * above brought up to date, but a later run leaves behind. */
        f->live = id == DFLE_FIELD_X || id == DFLE_FIELD_A || id == DFLE_FIELD_W ||
                  id == DFLE_FIELD_Z;
        q->known = 1;
        lua_pushnil(L);
        return 1;
    }
    if (strcmp(type, DFLE_LUA_LANDSCAPE) == 0) {
        int id = dfle_landscape_field_lookup(q->name);
        lua_ls *u;
        if (id < 0)
            return 0;
        dfle_lua_check_object(L, 1, DFLE_LUA_LANDSCAPE); /* raises if closed */
        u = lua_touserdata(L, 1);
        f->nx = dfle_landscape_nx(u->ls);
        f->ny = dfle_landscape_ny(u->ls);
        f->n = f->nx * f->ny;
        f->ndim = 2;
        q->known = 1;
        if (id == DFLE_LS_Z) {
            /* The elevations are the landscape's state (NaN on NoData,
             * as get() gives them); the use check gives get()'s
             * messages for a closed or running landscape. */
            dfle_lua_begin_use(L, 1, LANDSCAPE_GET);
            dfle_lua_end_use(L, 1);
            f->v = dfle_landscape_z(u->ls);
            f->live = 1;
            lua_pushnil(L);
            return 1;
        }
        f->v = dfle_lua_ls_get_field(L, id, LANDSCAPE_GET);
        f->live = 0;
        return 1; /* the scratch userdata holding the values */
    }
    return 0;
}

int dfle_bridge_get_field(dfle_bridge *b, int idx, const char *name, dfle_bridge_field *f)
{
    lua_State *L = b->L;
    field_req q = {name, f, 0};
    idx = lua_absindex(L, idx);
    memset(f, 0, sizeof *f);
    lua_pushcfunction(L, field_p);
    lua_pushvalue(L, idx);
    lua_pushlightuserdata(L, &q);
    if (lua_pcall(L, 2, 1, 0) != LUA_OK) {
        if (lua_type(L, -1) != LUA_TSTRING) {
            lua_pop(L, 1);
            lua_pushstring(L, "dfle: reading a field failed");
        }
        return -1;
    }
    return q.known;
}

const char *dfle_bridge_known_unit(const char *name) { return dfle_lua_known_unit(name); }

static int hold_p(lua_State *L)
{
    const char *type = dfle_lua_typename(L, 1);
    /* The object types whose memory views are given (their payload
     * starts with the in-use counts). */
    if (strcmp(type, DFLE_LUA_MODEL) == 0 || strcmp(type, DFLE_LUA_LANDSCAPE) == 0) {
        if (lua_toboolean(L, 2))
            dfle_lua_hold(L, 1);
        else
            dfle_lua_unhold(L, 1);
    }
    return 0;
}

/* Holding marks the object in use by a model-like holder: __close and
 * __gc then only doom it, and the last unhold frees it. */
static int hold(dfle_bridge *b, int idx, int on)
{
    lua_State *L = b->L;
    idx = lua_absindex(L, idx);
    lua_pushcfunction(L, hold_p);
    lua_pushvalue(L, idx);
    lua_pushboolean(L, on);
    if (lua_pcall(L, 2, 0, 0) != LUA_OK) {
        lua_pop(L, 1);
        return -1;
    }
    return 0;
}

int dfle_bridge_hold(dfle_bridge *b, int idx) { return hold(b, idx, 1); }
void dfle_bridge_unhold(dfle_bridge *b, int idx) { (void)hold(b, idx, 0); }
