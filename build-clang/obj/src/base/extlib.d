build-clang/obj/src/base/extlib.o: src/base/extlib.c src/base/extlib.h \
  include/dfle/error.h

src/base/extlib.h:

include/dfle/error.h:
