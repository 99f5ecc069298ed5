build-clang/obj/src/analysis/mcmc_diag.o: src/analysis/mcmc_diag.c \
  include/dfle/mcmc_diag.h include/dfle/error.h

include/dfle/mcmc_diag.h:

include/dfle/error.h:
