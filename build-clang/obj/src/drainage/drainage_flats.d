build-clang/obj/src/drainage/drainage_flats.o: \
  src/drainage/drainage_flats.c src/drainage/drainage_internal.h \
  include/dfle/drainage.h include/dfle/error.h

src/drainage/drainage_internal.h:

include/dfle/drainage.h:

include/dfle/error.h:
