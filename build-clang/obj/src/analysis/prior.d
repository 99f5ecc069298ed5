build-clang/obj/src/analysis/prior.o: src/analysis/prior.c \
  include/dfle/prior.h include/dfle/error.h include/dfle/stream.h

include/dfle/prior.h:

include/dfle/error.h:

include/dfle/stream.h:
