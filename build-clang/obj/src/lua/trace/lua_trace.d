build-clang/obj/src/lua/trace/lua_trace.o: src/lua/trace/lua_trace.c \
  src/lua/trace/lua_trace_internal.h src/lua/trace/lua_trace.h \
  /usr/include/lua5.4/lua.h /usr/include/lua5.4/luaconf.h \
  /usr/include/lua5.4/lauxlib.h

src/lua/trace/lua_trace_internal.h:

src/lua/trace/lua_trace.h:

/usr/include/lua5.4/lua.h:

/usr/include/lua5.4/luaconf.h:

/usr/include/lua5.4/lauxlib.h:
