build-clang/obj/src/base/record_flat.o: src/base/record_flat.c \
  include/dfle/record.h include/dfle/error.h include/dfle/param.h

include/dfle/record.h:

include/dfle/error.h:

include/dfle/param.h:
