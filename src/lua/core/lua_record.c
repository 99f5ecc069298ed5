/*
 * lua_record.c - records of what produced an output (record.h), as the
 * Lua binding makes them: stamped with the version, the date, the
 * command line, the script and the working directory; components
 * written in Lua listed from their own params; the files the script has
 * written so far; and the JSON record written beside a CSV file.
 *
 * A record is held by a userdata whose __gc frees it, so an error raised
 * while it is being built (a law's params that cannot be read, a file
 * that cannot be written) leaks nothing.
 */
#include "lua/core/dfle_lua.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define RECORD_BOX "dfle.record_box"

/* Registry keys: their addresses are the keys. */
static const char command_key = 'c';
static const char files_key = 'f';

typedef struct record_box {
    dfle_record *rec;
} record_box;

static int box_gc(lua_State *L)
{
    record_box *b = luaL_checkudata(L, 1, RECORD_BOX);
    dfle_record_free(b->rec);
    b->rec = NULL;
    return 0;
}

void dfle_lua_set_command(lua_State *L, char **argv, int argc, int script)
{
    lua_createtable(L, argc, 1);
    for (int i = 0; i < argc; i++) {
        lua_pushstring(L, argv[i]);
        lua_rawseti(L, -2, i + 1);
    }
    if (script >= 0 && script < argc) {
        lua_pushstring(L, argv[script]);
        lua_setfield(L, -2, "script");
    }
    lua_rawsetp(L, LUA_REGISTRYINDEX, &command_key);
}

/* The command as an array (and its script) on the stack: the host's, or
 * else built from the global `arg` as the lua interpreter sets it
 * (arg[0] the script, negative indices the interpreter and options). */
static void push_command(lua_State *L)
{
    lua_Integer lo = 0, k = 0;
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &command_key) == LUA_TTABLE)
        return;
    lua_pop(L, 1);
    lua_newtable(L);
    if (lua_getglobal(L, "arg") != LUA_TTABLE) {
        lua_pop(L, 1);
        return;
    }
    while (lua_rawgeti(L, -1, lo - 1) == LUA_TSTRING)
        lua_pop(L, 1), lo--;
    lua_pop(L, 1);
    for (lua_Integer i = lo; lua_rawgeti(L, -1, i) == LUA_TSTRING; i++)
        lua_rawseti(L, -3, ++k);
    lua_pop(L, 1);
    if (lua_rawgeti(L, -1, 0) == LUA_TSTRING)
        lua_setfield(L, -3, "script");
    else
        lua_pop(L, 1);
    lua_pop(L, 1);
}

/* The strings of the array at the top of the stack as list `key` of the
 * record's current section; pops the array. */
static void record_list(lua_State *L, dfle_record *rec, const char *key)
{
    lua_Integer n = (lua_Integer)lua_rawlen(L, -1);
    const char **items = lua_newuserdatauv(L, (size_t)(n > 0 ? n : 1) * sizeof *items, 0);
    for (lua_Integer i = 1; i <= n; i++) {
        lua_rawgeti(L, -2, i);
        items[i - 1] = lua_tostring(L, -1); /* anchored in the array */
        lua_pop(L, 1);
    }
    if (n > 0)
        dfle_record_list(rec, key, items, (size_t)n);
    lua_pop(L, 2);
}

dfle_record *dfle_lua_push_empty_record(lua_State *L)
{
    record_box *b = lua_newuserdatauv(L, sizeof *b, 0);
    dfle_error err;

    b->rec = NULL;
    if (luaL_newmetatable(L, RECORD_BOX)) {
        lua_pushcfunction(L, box_gc);
        lua_setfield(L, -2, "__gc");
    }
    lua_setmetatable(L, -2);
    if (dfle_record_new(&b->rec, &err) != DFLE_OK)
        dfle_lua_raise(L, &err);
    return b->rec;
}

dfle_record *dfle_lua_push_record(lua_State *L, const char *about)
{
    dfle_record *rec = dfle_lua_push_empty_record(L);
    record_box *b = lua_touserdata(L, -1);
    char cwd[PATH_MAX];

    dfle_record_stamp(rec);
    if (about != NULL)
        dfle_record_text(b->rec, "about", about);
    push_command(L);
    lua_getfield(L, -1, "script");
    lua_insert(L, -2);
    record_list(L, b->rec, "command");
    if (lua_type(L, -1) == LUA_TSTRING)
        dfle_record_text(b->rec, "script", lua_tostring(L, -1));
    lua_pop(L, 1);
    if (getcwd(cwd, sizeof cwd) != NULL)
        dfle_record_text(b->rec, "cwd", cwd);
    return b->rec;
}

void dfle_lua_record_value(lua_State *L, dfle_record *rec, const char *key, int v, int params)
{
    switch (lua_type(L, v)) {
    case LUA_TNUMBER:
        (params ? dfle_record_param_number : dfle_record_number)(rec, key, lua_tonumber(L, v),
                                                                 NULL);
        break;
    case LUA_TBOOLEAN:
        (params ? dfle_record_param_bool : dfle_record_bool)(rec, key, lua_toboolean(L, v));
        break;
    case LUA_TSTRING:
        (params ? dfle_record_param_text : dfle_record_text)(rec, key, lua_tostring(L, v));
        break;
    default: /* a function, a table: what it is, not what it holds */
        (params ? dfle_record_param_text : dfle_record_text)(rec, key, luaL_typename(L, v));
    }
}

void dfle_lua_record_table(lua_State *L, dfle_record *rec, int t, int params)
{
    const char *keys;
    t = lua_absindex(L, t);
    /* Sorted, so the record is the same from one run to the next. */
    keys = dfle_lua_push_sorted_keys(L, t);
    while (keys != NULL && *keys != '\0') {
        const char *end = strstr(keys, ", ");
        size_t len = end != NULL ? (size_t)(end - keys) : strlen(keys);
        lua_pushlstring(L, keys, len);
        lua_pushvalue(L, -1);
        lua_rawget(L, t);
        dfle_lua_record_value(L, rec, lua_tostring(L, -2), lua_gettop(L), params);
        lua_pop(L, 2);
        keys += len + (end != NULL ? 2 : 0);
    }
    lua_pop(L, 1);
}

void dfle_lua_record_own_params(lua_State *L, dfle_record *rec, int obj)
{
    if (lua_getiuservalue(L, obj, 2) == LUA_TTABLE)
        dfle_lua_record_table(L, rec, -1, 1);
    lua_pop(L, 1);
}

void dfle_lua_record_lua_parts(lua_State *L, dfle_record *rec, int obj, int uv_router,
                               int uv_law)
{
    int top = lua_gettop(L);
    obj = lua_absindex(L, obj);
    for (int k = 0; k < 2; k++) {
        if (lua_getiuservalue(L, obj, k == 0 ? uv_router : uv_law) == LUA_TUSERDATA) {
            dfle_lua_object *o = lua_touserdata(L, -1);
            size_t n = k == 0 ? dfle_router_params(o->ptr, NULL, 0)
                              : dfle_law_params(o->ptr, NULL, 0);
            if (n == (size_t)-1) {
                dfle_record_section(rec, k == 0 ? "router" : "law", NULL);
                dfle_lua_record_own_params(L, rec, lua_gettop(L));
            }
        }
        lua_settop(L, top);
    }
}

void dfle_lua_note_file(lua_State *L, const char *path)
{
    lua_Integer n;
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &files_key) != LUA_TTABLE) {
        lua_pop(L, 1);
        lua_newtable(L);
        lua_pushvalue(L, -1);
        lua_rawsetp(L, LUA_REGISTRYINDEX, &files_key);
    }
    n = (lua_Integer)lua_rawlen(L, -1);
    for (lua_Integer i = 1; i <= n; i++) {
        int same = lua_rawgeti(L, -1, i) == LUA_TSTRING && strcmp(lua_tostring(L, -1), path) == 0;
        lua_pop(L, 1);
        if (same) {
            lua_pop(L, 1);
            return; /* written again: listed once */
        }
    }
    lua_pushstring(L, path);
    lua_rawseti(L, -2, n + 1);
    lua_pop(L, 1);
}

/* The longest file name (one path component) of Linux file systems. */
#ifdef NAME_MAX
#define RECORD_NAME_MAX NAME_MAX
#else
#define RECORD_NAME_MAX 255
#endif

const char *dfle_lua_record_path(lua_State *L, dfle_record *rec, int opts, const char *path,
                                const char *fn)
{
    size_t len = strlen(path);
    struct stat sb;
    const char *jpath = NULL;
    int t;

    opts = lua_absindex(L, opts);
    t = lua_istable(L, opts) ? lua_getfield(L, opts, "record") : (lua_pushnil(L), LUA_TNIL);
    if (t == LUA_TSTRING) {
        jpath = dfle_lua_check_string(L, -1, fn, "record");
        if (strcmp(jpath, path) == 0)
            luaL_error(L, "dfle.%s: the record would replace the file itself ('%s'); give it "
                          "another name", fn, path);
    } else if (t != LUA_TNIL && t != LUA_TBOOLEAN) {
        luaL_error(L, "dfle.%s: parameter 'record' must be true, false or a file name for the "
                      "JSON record, got %s", fn, dfle_lua_typename(L, -1));
    } else if (t == LUA_TBOOLEAN && !lua_toboolean(L, -1)) {
        /* record = false: none */
    } else if (stat(path, &sb) == 0 && !S_ISREG(sb.st_mode)) {
        /* Beside a file only: a device or a pipe (/dev/stdout) has no
         * "beside", and a record there would only surprise. */
    } else {
        lua_pop(L, 1);
        if (len > 4 && (strcmp(path + len - 4, ".csv") == 0 || strcmp(path + len - 4, ".CSV") == 0))
            lua_pushlstring(L, path, len - 4);
        else
            lua_pushstring(L, path);
        lua_pushliteral(L, ".json");
        lua_concat(L, 2);
        jpath = lua_tostring(L, -1);
    }
    if (jpath == NULL) {
        lua_pop(L, 1);
        lua_pushnil(L);
        return NULL;
    }
    {
        /* Checked before the output is written: a name of 252-255 bytes
         * is legal, its record's (".json" in place of ".csv", or added)
         * may not be, and the output must not be left without the
         * record its comment lines name. */
        const char *base = strrchr(jpath, '/');
        size_t blen = strlen(base != NULL ? base + 1 : jpath);
        if (blen > RECORD_NAME_MAX)
            luaL_error(L, "dfle.%s: the JSON record beside '%s' would have a name of %d bytes, "
                          "more than a file name can hold (%d); give a shorter name, record = "
                          "'other.json', or record = false",
                       fn, path, (int)blen, RECORD_NAME_MAX);
    }
    dfle_record_section(rec, NULL, NULL);
    dfle_record_text(rec, "record", jpath);
    return jpath;
}

void dfle_lua_record_done(lua_State *L, dfle_record *rec, const char *output, const char *jpath)
{
    if (jpath != NULL)
        dfle_lua_write_record(L, rec, output, jpath);
    else
        dfle_lua_note_file(L, output);
}

void dfle_lua_write_record(lua_State *L, dfle_record *rec, const char *output,
                           const char *jpath)
{
    dfle_error err;

    dfle_record_section(rec, NULL, NULL);
    dfle_record_text(rec, "record", NULL); /* that is this file */
    if (output != NULL) {
        dfle_lua_note_file(L, output);
        dfle_record_text(rec, "output", output);
    }
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &files_key) != LUA_TTABLE) {
        lua_pop(L, 1);
        lua_newtable(L);
    }
    record_list(L, rec, "files");
    if (dfle_record_write_json(rec, jpath, &err) != DFLE_OK)
        dfle_lua_raise(L, &err);
    dfle_lua_note_file(L, jpath);
    /* The record may describe another output next (a fit's table and
     * its bins): what named this one goes. */
    dfle_record_section(rec, NULL, NULL);
    dfle_record_text(rec, "output", NULL);
    dfle_record_text(rec, "files", NULL);
}

