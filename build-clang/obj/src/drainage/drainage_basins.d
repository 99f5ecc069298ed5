build-clang/obj/src/drainage/drainage_basins.o: \
  src/drainage/drainage_basins.c src/drainage/drainage_internal.h \
  include/dfle/drainage.h include/dfle/error.h

src/drainage/drainage_internal.h:

include/dfle/drainage.h:

include/dfle/error.h:
