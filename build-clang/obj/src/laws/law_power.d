build-clang/obj/src/laws/law_power.o: src/laws/law_power.c \
  include/dfle/law_power.h include/dfle/law.h include/dfle/error.h \
  include/dfle/flow.h include/dfle/param.h

include/dfle/law_power.h:

include/dfle/law.h:

include/dfle/error.h:

include/dfle/flow.h:

include/dfle/param.h:
