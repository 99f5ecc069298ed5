build-clang/obj/src/lua/trace/lua_trace_outside.o: \
  src/lua/trace/lua_trace_outside.c src/lua/trace/lua_trace_internal.h \
  src/lua/trace/lua_trace.h /usr/include/lua5.4/lua.h \
  /usr/include/lua5.4/luaconf.h /usr/include/lua5.4/lauxlib.h \
  /usr/include/lua5.4/lualib.h

src/lua/trace/lua_trace_internal.h:

src/lua/trace/lua_trace.h:

/usr/include/lua5.4/lua.h:

/usr/include/lua5.4/luaconf.h:

/usr/include/lua5.4/lauxlib.h:

/usr/include/lua5.4/lualib.h:
