build-clang/obj/src/laws/law_inertial.o: src/laws/law_inertial.c \
  include/dfle/law_inertial.h include/dfle/law.h include/dfle/error.h \
  include/dfle/flow.h include/dfle/param.h

include/dfle/law_inertial.h:

include/dfle/law.h:

include/dfle/error.h:

include/dfle/flow.h:

include/dfle/param.h:
