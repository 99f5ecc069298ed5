build-clang/obj/src/base/param.o: src/base/param.c include/dfle/param.h

include/dfle/param.h:
