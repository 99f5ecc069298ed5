build-clang/obj/src/analysis/sampling.o: src/analysis/sampling.c \
  include/dfle/sampling.h include/dfle/error.h

include/dfle/sampling.h:

include/dfle/error.h:
