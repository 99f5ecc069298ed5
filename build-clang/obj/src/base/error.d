build-clang/obj/src/base/error.o: src/base/error.c include/dfle/error.h

include/dfle/error.h:
