build-clang/obj/src/solvers/solver_events.o: src/solvers/solver_events.c \
  include/dfle/model_events.h include/dfle/model.h \
  include/dfle/channel.h include/dfle/error.h include/dfle/param.h \
  include/dfle/fluvial.h include/dfle/law.h include/dfle/flow.h \
  include/dfle/network.h include/dfle/record.h include/dfle/router.h \
  include/dfle/router_population.h include/dfle/solver.h

include/dfle/model_events.h:

include/dfle/model.h:

include/dfle/channel.h:

include/dfle/error.h:

include/dfle/param.h:

include/dfle/fluvial.h:

include/dfle/law.h:

include/dfle/flow.h:

include/dfle/network.h:

include/dfle/record.h:

include/dfle/router.h:

include/dfle/router_population.h:

include/dfle/solver.h:
