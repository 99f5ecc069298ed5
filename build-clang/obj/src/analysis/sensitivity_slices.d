build-clang/obj/src/analysis/sensitivity_slices.o: \
  src/analysis/sensitivity_slices.c src/analysis/sensitivity_internal.h \
  include/dfle/sensitivity.h include/dfle/error.h

src/analysis/sensitivity_internal.h:

include/dfle/sensitivity.h:

include/dfle/error.h:
