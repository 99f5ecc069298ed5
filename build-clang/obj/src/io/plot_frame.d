build-clang/obj/src/io/plot_frame.o: src/io/plot_frame.c \
  src/io/plot_internal.h include/dfle/error.h include/dfle/file.h \
  include/dfle/plot.h include/dfle/analysis.h

src/io/plot_internal.h:

include/dfle/error.h:

include/dfle/file.h:

include/dfle/plot.h:

include/dfle/analysis.h:
