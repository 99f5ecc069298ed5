build-clang/obj/src/io/plot_chi.o: src/io/plot_chi.c include/dfle/plot.h \
  include/dfle/analysis.h include/dfle/error.h src/io/plot_internal.h \
  include/dfle/file.h

include/dfle/plot.h:

include/dfle/analysis.h:

include/dfle/error.h:

src/io/plot_internal.h:

include/dfle/file.h:
