build-clang/obj/src/landscape/landscape_memory.o: \
  src/landscape/landscape_memory.c src/landscape/landscape_internal.h \
  include/dfle/landscape.h include/dfle/drainage.h include/dfle/error.h \
  include/dfle/fluvial.h include/dfle/param.h include/dfle/law.h \
  include/dfle/flow.h include/dfle/model.h include/dfle/channel.h \
  include/dfle/network.h include/dfle/record.h include/dfle/router.h \
  include/dfle/solver.h

src/landscape/landscape_internal.h:

include/dfle/landscape.h:

include/dfle/drainage.h:

include/dfle/error.h:

include/dfle/fluvial.h:

include/dfle/param.h:

include/dfle/law.h:

include/dfle/flow.h:

include/dfle/model.h:

include/dfle/channel.h:

include/dfle/network.h:

include/dfle/record.h:

include/dfle/router.h:

include/dfle/solver.h:
