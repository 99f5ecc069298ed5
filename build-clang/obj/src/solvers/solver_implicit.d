build-clang/obj/src/solvers/solver_implicit.o: \
  src/solvers/solver_implicit.c src/solvers/solver_internal.h \
  include/dfle/model.h include/dfle/channel.h include/dfle/error.h \
  include/dfle/param.h include/dfle/fluvial.h include/dfle/law.h \
  include/dfle/flow.h include/dfle/network.h include/dfle/record.h \
  include/dfle/router.h include/dfle/solver.h

src/solvers/solver_internal.h:

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

include/dfle/solver.h:
