build-clang/obj/src/analysis/sensitivity_bootstrap.o: \
  src/analysis/sensitivity_bootstrap.c \
  src/analysis/sensitivity_internal.h include/dfle/sensitivity.h \
  include/dfle/error.h include/dfle/sampling.h

src/analysis/sensitivity_internal.h:

include/dfle/sensitivity.h:

include/dfle/error.h:

include/dfle/sampling.h:
