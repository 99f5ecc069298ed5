/*
 * lua_snippet.h - run a piece of Lua with the dfle module from a cmocka
 * test, for tests that check with C libraries (libnetcdf, GDAL) the
 * files the Lua API writes.
 */
#ifndef DFLE_TEST_LUA_SNIPPET_H
#define DFLE_TEST_LUA_SNIPPET_H

#include <lauxlib.h>
#include <lua.h>
#include <lualib.h>

#include "dfle_test.h"

#include "dfle/lua.h"

/* Run `code` in a fresh state; fail the test with its error. */
static inline void run_lua_snippet(const char *code)
{
    lua_State *L = luaL_newstate();
    assert_non_null(L);
    luaL_openlibs(L);
    luaL_requiref(L, "dfle", luaopen_dfle, 1);
    lua_pop(L, 1);
    if (luaL_dostring(L, code) != LUA_OK) {
        print_error("%s\n", lua_tostring(L, -1));
        lua_close(L);
        fail();
    }
    lua_close(L);
}

#endif
