build-clang/obj/src/analysis/analytical.o: src/analysis/analytical.c \
  include/dfle/analytical.h include/dfle/error.h

include/dfle/analytical.h:

include/dfle/error.h:
