build-clang/obj/src/analysis/analysis.o: src/analysis/analysis.c \
  include/dfle/analysis.h include/dfle/error.h

include/dfle/analysis.h:

include/dfle/error.h:
