build-clang/obj/src/base/file.o: src/base/file.c include/dfle/file.h \
  include/dfle/error.h

include/dfle/file.h:

include/dfle/error.h:
