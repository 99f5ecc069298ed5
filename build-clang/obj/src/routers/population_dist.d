build-clang/obj/src/routers/population_dist.o: \
  src/routers/population_dist.c include/dfle/router_population.h \
  include/dfle/router.h include/dfle/error.h include/dfle/flow.h \
  include/dfle/network.h include/dfle/channel.h include/dfle/param.h

include/dfle/router_population.h:

include/dfle/router.h:

include/dfle/error.h:

include/dfle/flow.h:

include/dfle/network.h:

include/dfle/channel.h:

include/dfle/param.h:
