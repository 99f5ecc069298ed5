build-clang/obj/src/domain/network.o: src/domain/network.c \
  include/dfle/network.h include/dfle/channel.h include/dfle/error.h \
  include/dfle/param.h

include/dfle/network.h:

include/dfle/channel.h:

include/dfle/error.h:

include/dfle/param.h:
