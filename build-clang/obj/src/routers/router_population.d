build-clang/obj/src/routers/router_population.o: \
  src/routers/router_population.c include/dfle/router_population.h \
  include/dfle/router.h include/dfle/error.h include/dfle/flow.h \
  include/dfle/network.h include/dfle/channel.h include/dfle/param.h \
  include/dfle/router_empirical.h

include/dfle/router_population.h:

include/dfle/router.h:

include/dfle/error.h:

include/dfle/flow.h:

include/dfle/network.h:

include/dfle/channel.h:

include/dfle/param.h:

include/dfle/router_empirical.h:
