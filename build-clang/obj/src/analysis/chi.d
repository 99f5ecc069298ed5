build-clang/obj/src/analysis/chi.o: src/analysis/chi.c include/dfle/chi.h \
  include/dfle/error.h include/dfle/analysis.h

include/dfle/chi.h:

include/dfle/error.h:

include/dfle/analysis.h:
