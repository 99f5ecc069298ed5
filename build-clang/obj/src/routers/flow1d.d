build-clang/obj/src/routers/flow1d.o: src/routers/flow1d.c \
  include/dfle/flow1d.h include/dfle/error.h

include/dfle/flow1d.h:

include/dfle/error.h:
