build-clang/obj/src/drainage/drainage.o: src/drainage/drainage.c \
  src/drainage/drainage_internal.h include/dfle/drainage.h \
  include/dfle/error.h

src/drainage/drainage_internal.h:

include/dfle/drainage.h:

include/dfle/error.h:
