/*
 * lua_bridge_record.c - what a model's or a landscape's files say about
 * it, for a host that labels its own datasets (the Python package's
 * to_xarray): the record its NetCDF files carry as global attributes,
 * under the same names, and the landscape's CRS.  The same record and
 * the same flat names (dfle_record_flat_name) as src/io/netcdf_cf.c, so
 * a dataset made in memory and the file of the same object agree;
 * and the labels (unit, long name, CF standard name) a field carries
 * there.
 */
#include <string.h>

#include <lauxlib.h>

#include "lua/core/dfle_lua.h"
#include "lua/objects/lua_landscape.h"

#include "dfle/landscape.h"
#include "dfle/model.h"
#include "dfle/record.h"

#include "lua/bridge/lua_bridge_internal.h"

typedef struct {
    lua_State *L;
    int t; /* the table of attributes */
} attrs_ctx;

/* "<section>_units": "key=unit, ..." as the files gather them. */
static void add_unit(attrs_ctx *c, const dfle_record_entry *e)
{
    lua_State *L = c->L;
    dfle_record_entry u = {.section = e->section, .key = "units"};
    char name[160], cf[128];
    dfle_record_flat_name(&u, name, sizeof name);
    lua_getfield(L, c->t, name);
    if (lua_isstring(L, -1))
        lua_pushliteral(L, ", ");
    else {
        lua_pop(L, 1);
        lua_pushliteral(L, "");
        lua_pushliteral(L, "");
    }
    lua_pushfstring(L, "%s=%s", e->key,
                    dfle_units_udunits(e->unit, cf, sizeof cf) ? cf : e->unit);
    lua_concat(L, 3);
    lua_setfield(L, c->t, name);
}

static int put_entry(void *ud, const dfle_record_entry *e)
{
    attrs_ctx *c = ud;
    lua_State *L = c->L;
    char name[160], text[4096];
    if (e->section != NULL && e->kind != NULL) {
        dfle_record_entry kind = {.section = e->section};
        dfle_record_flat_name(&kind, name, sizeof name);
        lua_pushstring(L, e->kind);
        lua_setfield(L, c->t, name);
    }
    if (e->key == NULL)
        return 0;
    dfle_record_flat_name(e, name, sizeof name);
    switch (e->type) {
    case DFLE_RECORD_NUMBER:
        lua_pushnumber(L, e->num);
        break;
    case DFLE_RECORD_BOOL: /* the files' NC_INT */
        lua_pushinteger(L, e->num != 0);
        break;
    case DFLE_RECORD_TEXT:
        lua_pushstring(L, e->text != NULL ? e->text : "");
        break;
    default:
        dfle_record_join(e->items, e->nitems, text, sizeof text);
        lua_pushstring(L, text);
        break;
    }
    lua_setfield(L, c->t, name);
    if (e->section != NULL && e->unit != NULL)
        add_unit(c, e);
    return 0;
}

/* (object) -> attributes, crs (a string or nil); nothing for other values. */
static int attrs_p(lua_State *L)
{
    const char *type = dfle_lua_typename(L, 1);
    const char *crs = NULL;
    dfle_record *rec;
    attrs_ctx c = {L, 0};
    lua_settop(L, 1);
    rec = dfle_lua_push_record(L, NULL); /* held on the stack: a raise leaks nothing */
    if (strcmp(type, DFLE_LUA_MODEL) == 0) {
        dfle_lua_record_model(L, rec, 1);
    } else if (strcmp(type, DFLE_LUA_LANDSCAPE) == 0) {
        lua_ls *u;
        dfle_lua_check_object(L, 1, DFLE_LUA_LANDSCAPE); /* raises if closed */
        u = lua_touserdata(L, 1);
        dfle_lua_record_landscape(L, rec, 1);
        crs = u->crs;
    } else {
        return 0;
    }
    lua_newtable(L);
    c.t = lua_gettop(L);
    dfle_record_each(rec, put_entry, &c);
    if (crs != NULL && crs[0] != '\0')
        lua_pushstring(L, crs);
    else
        lua_pushnil(L);
    return 2;
}

int dfle_bridge_push_attrs(dfle_bridge *b, int idx)
{
    lua_State *L = b->L;
    int top = lua_gettop(L);
    idx = lua_absindex(L, idx);
    lua_pushcfunction(L, attrs_p);
    lua_pushvalue(L, idx);
    if (lua_pcall(L, 1, LUA_MULTRET, 0) != LUA_OK) {
        if (lua_type(L, -1) != LUA_TSTRING) {
            lua_pop(L, 1);
            lua_pushstring(L, "dfle: reading an object's record failed");
        }
        return -1;
    }
    return lua_gettop(L) - top == 2 ? 1 : 0;
}

int dfle_bridge_field_label(int landscape, const char *name, const char **unit,
                            const char **long_name, const char **standard_name)
{
    int id = landscape ? dfle_landscape_field_lookup(name) : dfle_field_lookup(name);
    if (id < 0)
        return 0;
    *unit = landscape ? dfle_landscape_field_unit(id) : dfle_field_unit(id);
    *long_name = landscape ? dfle_landscape_field_long_name(id) : NULL;
    *standard_name = landscape ? dfle_landscape_field_standard_name(id) : NULL;
    return 1;
}
