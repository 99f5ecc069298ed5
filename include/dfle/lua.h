/*
 * lua.h - the Lua 5.4 binding of dfle: `require "dfle"`.
 *
 * Embedders (the dfle CLI among them) call luaL_requiref(L, "dfle",
 * luaopen_dfle, 1) or put luaopen_dfle in package.preload.  The same
 * function is the entry point of the loadable module dfle.so.
 */
#ifndef DFLE_LUA_H
#define DFLE_LUA_H

#ifdef __cplusplus
extern "C" {
#endif

struct lua_State;
int luaopen_dfle(struct lua_State *L);

#ifdef __cplusplus
}
#endif
#endif
