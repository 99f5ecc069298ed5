build-clang/obj/src/lua/define/lua_law_define.o: \
  src/lua/define/lua_law_define.c src/lua/define/lua_law_compiled.h \
  src/lua/define/lua_law_sweep.h src/lua/core/lua_shell.h \
  src/lua/core/dfle_lua.h /usr/include/lua5.4/lauxlib.h \
  /usr/include/lua5.4/luaconf.h /usr/include/lua5.4/lua.h \
  include/dfle/channel.h include/dfle/error.h include/dfle/param.h \
  include/dfle/fluvial.h include/dfle/law.h include/dfle/flow.h \
  include/dfle/model.h include/dfle/network.h include/dfle/record.h \
  include/dfle/router.h include/dfle/plot.h include/dfle/analysis.h \
  include/dfle/solver.h src/lua/trace/lua_trace.h

src/lua/define/lua_law_compiled.h:

src/lua/define/lua_law_sweep.h:

src/lua/core/lua_shell.h:

src/lua/core/dfle_lua.h:

/usr/include/lua5.4/lauxlib.h:

/usr/include/lua5.4/luaconf.h:

/usr/include/lua5.4/lua.h:

include/dfle/channel.h:

include/dfle/error.h:

include/dfle/param.h:

include/dfle/fluvial.h:

include/dfle/law.h:

include/dfle/flow.h:

include/dfle/model.h:

include/dfle/network.h:

include/dfle/record.h:

include/dfle/router.h:

include/dfle/plot.h:

include/dfle/analysis.h:

include/dfle/solver.h:

src/lua/trace/lua_trace.h:
