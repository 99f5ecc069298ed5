build-clang/obj/src/routers/router_process.o: \
  src/routers/router_process.c include/dfle/router_process.h \
  include/dfle/flow1d.h include/dfle/error.h include/dfle/router.h \
  include/dfle/flow.h include/dfle/network.h include/dfle/channel.h \
  include/dfle/param.h

include/dfle/router_process.h:

include/dfle/flow1d.h:

include/dfle/error.h:

include/dfle/router.h:

include/dfle/flow.h:

include/dfle/network.h:

include/dfle/channel.h:

include/dfle/param.h:
