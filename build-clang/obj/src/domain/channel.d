build-clang/obj/src/domain/channel.o: src/domain/channel.c \
  include/dfle/channel.h include/dfle/error.h include/dfle/param.h

include/dfle/channel.h:

include/dfle/error.h:

include/dfle/param.h:
