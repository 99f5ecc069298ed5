build-clang/obj/src/analysis/lsq.o: src/analysis/lsq.c include/dfle/lsq.h \
  include/dfle/error.h

include/dfle/lsq.h:

include/dfle/error.h:
