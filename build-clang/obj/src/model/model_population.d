build-clang/obj/src/model/model_population.o: \
  src/model/model_population.c include/dfle/model_events.h \
  include/dfle/model.h include/dfle/channel.h include/dfle/error.h \
  include/dfle/param.h include/dfle/fluvial.h include/dfle/law.h \
  include/dfle/flow.h include/dfle/network.h include/dfle/record.h \
  include/dfle/router.h include/dfle/router_population.h \
  src/model/model_internal.h

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

src/model/model_internal.h:
