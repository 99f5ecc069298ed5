build-clang/obj/src/routers/router.o: src/routers/router.c \
  include/dfle/router.h include/dfle/error.h include/dfle/flow.h \
  include/dfle/network.h include/dfle/channel.h include/dfle/param.h

include/dfle/router.h:

include/dfle/error.h:

include/dfle/flow.h:

include/dfle/network.h:

include/dfle/channel.h:

include/dfle/param.h:
