build-clang/obj/src/cli/progress.o: src/cli/progress.c src/cli/progress.h \
  include/dfle/solver.h include/dfle/error.h include/dfle/model.h \
  include/dfle/channel.h include/dfle/param.h include/dfle/fluvial.h \
  include/dfle/law.h include/dfle/flow.h include/dfle/network.h \
  include/dfle/record.h include/dfle/router.h

src/cli/progress.h:

include/dfle/solver.h:

include/dfle/error.h:

include/dfle/model.h:

include/dfle/channel.h:

include/dfle/param.h:

include/dfle/fluvial.h:

include/dfle/law.h:

include/dfle/flow.h:

include/dfle/network.h:

include/dfle/record.h:

include/dfle/router.h:
