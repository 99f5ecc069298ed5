build-clang/obj/src/lua/invert/lua_invert.o: src/lua/invert/lua_invert.c \
  src/lua/invert/lua_invert_internal.h include/dfle/csv.h \
  include/dfle/error.h include/dfle/invert_run.h \
  include/dfle/evaluator.h include/dfle/mcmc_diag.h include/dfle/prior.h \
  include/dfle/stream.h src/lua/core/dfle_lua.h \
  /usr/include/lua5.4/lauxlib.h /usr/include/lua5.4/luaconf.h \
  /usr/include/lua5.4/lua.h include/dfle/channel.h include/dfle/param.h \
  include/dfle/fluvial.h include/dfle/law.h include/dfle/flow.h \
  include/dfle/model.h include/dfle/network.h include/dfle/record.h \
  include/dfle/router.h include/dfle/plot.h include/dfle/analysis.h \
  include/dfle/solver.h src/lua/drive/lua_parallel.h \
  src/lua/drive/lua_drive.h include/dfle/pool.h

src/lua/invert/lua_invert_internal.h:

include/dfle/csv.h:

include/dfle/error.h:

include/dfle/invert_run.h:

include/dfle/evaluator.h:

include/dfle/mcmc_diag.h:

include/dfle/prior.h:

include/dfle/stream.h:

src/lua/core/dfle_lua.h:

/usr/include/lua5.4/lauxlib.h:

/usr/include/lua5.4/luaconf.h:

/usr/include/lua5.4/lua.h:

include/dfle/channel.h:

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

src/lua/drive/lua_parallel.h:

src/lua/drive/lua_drive.h:

include/dfle/pool.h:
