build-clang/obj/src/analysis/mcmc.o: src/analysis/mcmc.c \
  include/dfle/mcmc.h include/dfle/error.h include/dfle/stream.h

include/dfle/mcmc.h:

include/dfle/error.h:

include/dfle/stream.h:
