build-clang/obj/src/drainage/drainage_tree.o: \
  src/drainage/drainage_tree.c src/drainage/drainage_internal.h \
  include/dfle/drainage.h include/dfle/error.h

src/drainage/drainage_internal.h:

include/dfle/drainage.h:

include/dfle/error.h:
