build-clang/obj/src/model/model_rates.o: src/model/model_rates.c \
  src/model/model_internal.h include/dfle/flow.h include/dfle/error.h \
  include/dfle/model.h include/dfle/channel.h include/dfle/param.h \
  include/dfle/fluvial.h include/dfle/law.h include/dfle/network.h \
  include/dfle/record.h include/dfle/router.h

src/model/model_internal.h:

include/dfle/flow.h:

include/dfle/error.h:

include/dfle/model.h:

include/dfle/channel.h:

include/dfle/param.h:

include/dfle/fluvial.h:

include/dfle/law.h:

include/dfle/network.h:

include/dfle/record.h:

include/dfle/router.h:
