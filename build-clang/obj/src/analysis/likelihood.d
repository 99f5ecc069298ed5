build-clang/obj/src/analysis/likelihood.o: src/analysis/likelihood.c \
  include/dfle/likelihood.h include/dfle/error.h

include/dfle/likelihood.h:

include/dfle/error.h:
