build-clang/obj/src/model/model.o: src/model/model.c include/dfle/model.h \
  include/dfle/channel.h include/dfle/error.h include/dfle/param.h \
  include/dfle/fluvial.h include/dfle/law.h include/dfle/flow.h \
  include/dfle/network.h include/dfle/record.h include/dfle/router.h \
  include/dfle/file.h src/model/model_internal.h

include/dfle/model.h:

include/dfle/channel.h:

include/dfle/error.h:

include/dfle/param.h:

include/dfle/fluvial.h:

include/dfle/law.h:

include/dfle/flow.h:

include/dfle/network.h:

include/dfle/record.h:

include/dfle/router.h:

include/dfle/file.h:

src/model/model_internal.h:
