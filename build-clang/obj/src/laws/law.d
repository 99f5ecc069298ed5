build-clang/obj/src/laws/law.o: src/laws/law.c include/dfle/law.h \
  include/dfle/error.h include/dfle/flow.h include/dfle/param.h

include/dfle/law.h:

include/dfle/error.h:

include/dfle/flow.h:

include/dfle/param.h:
