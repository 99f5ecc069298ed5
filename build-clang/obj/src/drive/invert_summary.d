build-clang/obj/src/drive/invert_summary.o: src/drive/invert_summary.c \
  src/drive/invert_internal.h include/dfle/ensemble.h \
  include/dfle/error.h include/dfle/invert_run.h \
  include/dfle/evaluator.h include/dfle/mcmc_diag.h include/dfle/prior.h \
  include/dfle/stream.h src/drive/drive_internal.h

src/drive/invert_internal.h:

include/dfle/ensemble.h:

include/dfle/error.h:

include/dfle/invert_run.h:

include/dfle/evaluator.h:

include/dfle/mcmc_diag.h:

include/dfle/prior.h:

include/dfle/stream.h:

src/drive/drive_internal.h:
