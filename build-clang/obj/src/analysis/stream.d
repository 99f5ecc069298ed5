build-clang/obj/src/analysis/stream.o: src/analysis/stream.c \
  include/dfle/stream.h

include/dfle/stream.h:
