build-clang/obj/src/io/plot.o: src/io/plot.c include/dfle/plot.h \
  include/dfle/analysis.h include/dfle/error.h src/io/plot_internal.h \
  include/dfle/file.h

include/dfle/plot.h:

include/dfle/analysis.h:

include/dfle/error.h:

src/io/plot_internal.h:

include/dfle/file.h:
