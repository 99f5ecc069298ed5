build-clang/obj/src/lua/trace/lua_trace_release.o: \
  src/lua/trace/lua_trace_release.c src/lua/trace/lua_trace.h \
  /usr/include/lua5.4/lua.h /usr/include/lua5.4/luaconf.h

src/lua/trace/lua_trace.h:

/usr/include/lua5.4/lua.h:

/usr/include/lua5.4/luaconf.h:
