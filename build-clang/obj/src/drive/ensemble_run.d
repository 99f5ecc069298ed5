build-clang/obj/src/drive/ensemble_run.o: src/drive/ensemble_run.c \
  include/dfle/ensemble_run.h include/dfle/error.h \
  include/dfle/evaluator.h include/dfle/pool.h include/dfle/record.h \
  include/dfle/param.h include/dfle/sampling.h include/dfle/ensemble.h \
  src/drive/drive_internal.h

include/dfle/ensemble_run.h:

include/dfle/error.h:

include/dfle/evaluator.h:

include/dfle/pool.h:

include/dfle/record.h:

include/dfle/param.h:

include/dfle/sampling.h:

include/dfle/ensemble.h:

src/drive/drive_internal.h:
