build-clang/obj/src/analysis/sensitivity.o: src/analysis/sensitivity.c \
  src/analysis/sensitivity_internal.h include/dfle/sensitivity.h \
  include/dfle/error.h include/dfle/sampling.h

src/analysis/sensitivity_internal.h:

include/dfle/sensitivity.h:

include/dfle/error.h:

include/dfle/sampling.h:
