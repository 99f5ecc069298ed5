build-clang/obj/src/routers/flow.o: src/routers/flow.c \
  include/dfle/flow.h include/dfle/error.h

include/dfle/flow.h:

include/dfle/error.h:
