build-clang/obj/src/io/plot_corner.o: src/io/plot_corner.c \
  include/dfle/plot.h include/dfle/analysis.h include/dfle/error.h \
  include/dfle/mcmc_diag.h src/io/plot_internal.h include/dfle/file.h

include/dfle/plot.h:

include/dfle/analysis.h:

include/dfle/error.h:

include/dfle/mcmc_diag.h:

src/io/plot_internal.h:

include/dfle/file.h:
