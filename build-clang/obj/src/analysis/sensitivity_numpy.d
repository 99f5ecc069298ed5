build-clang/obj/src/analysis/sensitivity_numpy.o: \
  src/analysis/sensitivity_numpy.c src/analysis/sensitivity_internal.h \
  include/dfle/sensitivity.h include/dfle/error.h

src/analysis/sensitivity_internal.h:

include/dfle/sensitivity.h:

include/dfle/error.h:
