build-clang/obj/src/lua/core/lua_type.o: src/lua/core/lua_type.c \
  src/lua/core/dfle_lua.h /usr/include/lua5.4/lauxlib.h \
  /usr/include/lua5.4/luaconf.h /usr/include/lua5.4/lua.h \
  include/dfle/channel.h include/dfle/error.h include/dfle/param.h \
  include/dfle/fluvial.h include/dfle/law.h include/dfle/flow.h \
  include/dfle/model.h include/dfle/network.h include/dfle/record.h \
  include/dfle/router.h include/dfle/plot.h include/dfle/analysis.h \
  include/dfle/solver.h

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
