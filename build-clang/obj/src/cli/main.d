build-clang/obj/src/cli/main.o: src/cli/main.c \
  /usr/include/lua5.4/lauxlib.h /usr/include/lua5.4/luaconf.h \
  /usr/include/lua5.4/lua.h /usr/include/lua5.4/lualib.h \
  include/dfle/lua.h src/lua/core/dfle_lua.h include/dfle/channel.h \
  include/dfle/error.h include/dfle/param.h include/dfle/fluvial.h \
  include/dfle/law.h include/dfle/flow.h include/dfle/model.h \
  include/dfle/network.h include/dfle/record.h include/dfle/router.h \
  include/dfle/plot.h include/dfle/analysis.h include/dfle/solver.h \
  src/lua/drive/lua_drive.h include/dfle/evaluator.h include/dfle/pool.h \
  src/cli/progress.h

/usr/include/lua5.4/lauxlib.h:

/usr/include/lua5.4/luaconf.h:

/usr/include/lua5.4/lua.h:

/usr/include/lua5.4/lualib.h:

include/dfle/lua.h:

src/lua/core/dfle_lua.h:

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

src/lua/drive/lua_drive.h:

include/dfle/evaluator.h:

include/dfle/pool.h:

src/cli/progress.h:
