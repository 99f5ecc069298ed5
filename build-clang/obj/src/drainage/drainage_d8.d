build-clang/obj/src/drainage/drainage_d8.o: src/drainage/drainage_d8.c \
  src/drainage/drainage_internal.h include/dfle/drainage.h \
  include/dfle/error.h

src/drainage/drainage_internal.h:

include/dfle/drainage.h:

include/dfle/error.h:
