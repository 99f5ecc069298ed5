build-clang/obj/src/lua/ensemble/lua_ensemble_result.o: \
  src/lua/ensemble/lua_ensemble_result.c \
  src/lua/ensemble/lua_ensemble_internal.h include/dfle/ensemble.h \
  include/dfle/error.h include/dfle/ensemble_run.h \
  include/dfle/evaluator.h include/dfle/pool.h include/dfle/record.h \
  include/dfle/param.h include/dfle/sampling.h src/lua/core/dfle_lua.h \
  /usr/include/lua5.4/lauxlib.h /usr/include/lua5.4/luaconf.h \
  /usr/include/lua5.4/lua.h include/dfle/channel.h \
  include/dfle/fluvial.h include/dfle/law.h include/dfle/flow.h \
  include/dfle/model.h include/dfle/network.h include/dfle/router.h \
  include/dfle/plot.h include/dfle/analysis.h include/dfle/solver.h \
  src/lua/drive/lua_parallel.h src/lua/drive/lua_drive.h \
  src/lua/ensemble/lua_ensemble.h

src/lua/ensemble/lua_ensemble_internal.h:

include/dfle/ensemble.h:

include/dfle/error.h:

include/dfle/ensemble_run.h:

include/dfle/evaluator.h:

include/dfle/pool.h:

include/dfle/record.h:

include/dfle/param.h:

include/dfle/sampling.h:

src/lua/core/dfle_lua.h:

/usr/include/lua5.4/lauxlib.h:

/usr/include/lua5.4/luaconf.h:

/usr/include/lua5.4/lua.h:

include/dfle/channel.h:

include/dfle/fluvial.h:

include/dfle/law.h:

include/dfle/flow.h:

include/dfle/model.h:

include/dfle/network.h:

include/dfle/router.h:

include/dfle/plot.h:

include/dfle/analysis.h:

include/dfle/solver.h:

src/lua/drive/lua_parallel.h:

src/lua/drive/lua_drive.h:

src/lua/ensemble/lua_ensemble.h:
