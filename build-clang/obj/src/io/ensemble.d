build-clang/obj/src/io/ensemble.o: src/io/ensemble.c \
  include/dfle/ensemble.h include/dfle/error.h include/dfle/file.h

include/dfle/ensemble.h:

include/dfle/error.h:

include/dfle/file.h:
