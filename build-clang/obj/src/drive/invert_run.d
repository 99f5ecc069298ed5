build-clang/obj/src/drive/invert_run.o: src/drive/invert_run.c \
  src/drive/invert_internal.h include/dfle/ensemble.h \
  include/dfle/error.h include/dfle/invert_run.h \
  include/dfle/evaluator.h include/dfle/mcmc_diag.h include/dfle/prior.h \
  include/dfle/stream.h src/drive/drive_internal.h include/dfle/mcmc.h \
  include/dfle/pool.h

src/drive/invert_internal.h:

include/dfle/ensemble.h:

include/dfle/error.h:

include/dfle/invert_run.h:

include/dfle/evaluator.h:

include/dfle/mcmc_diag.h:

include/dfle/prior.h:

include/dfle/stream.h:

src/drive/drive_internal.h:

include/dfle/mcmc.h:

include/dfle/pool.h:
