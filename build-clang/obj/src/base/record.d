build-clang/obj/src/base/record.o: src/base/record.c \
  include/dfle/record.h include/dfle/error.h include/dfle/param.h \
  include/dfle/file.h

include/dfle/record.h:

include/dfle/error.h:

include/dfle/param.h:

include/dfle/file.h:
