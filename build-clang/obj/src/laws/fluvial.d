build-clang/obj/src/laws/fluvial.o: src/laws/fluvial.c \
  include/dfle/fluvial.h include/dfle/error.h include/dfle/param.h

include/dfle/fluvial.h:

include/dfle/error.h:

include/dfle/param.h:
