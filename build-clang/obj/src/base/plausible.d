build-clang/obj/src/base/plausible.o: src/base/plausible.c \
  include/dfle/plausible.h

include/dfle/plausible.h:
