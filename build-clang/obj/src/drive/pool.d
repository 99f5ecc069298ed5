build-clang/obj/src/drive/pool.o: src/drive/pool.c include/dfle/pool.h \
  include/dfle/error.h include/dfle/evaluator.h \
  src/drive/drive_internal.h

include/dfle/pool.h:

include/dfle/error.h:

include/dfle/evaluator.h:

src/drive/drive_internal.h:
