build-clang/obj/src/laws/law_excess_stress.o: \
  src/laws/law_excess_stress.c include/dfle/law_excess_stress.h \
  include/dfle/law.h include/dfle/error.h include/dfle/flow.h \
  include/dfle/param.h

include/dfle/law_excess_stress.h:

include/dfle/law.h:

include/dfle/error.h:

include/dfle/flow.h:

include/dfle/param.h:
