build-clang/obj/src/dem/dem_grid.o: src/dem/dem_grid.c \
  src/dem/dem_internal.h include/dfle/dem.h include/dfle/channel.h \
  include/dfle/error.h include/dfle/param.h include/dfle/record.h \
  include/dfle/drainage.h

src/dem/dem_internal.h:

include/dfle/dem.h:

include/dfle/channel.h:

include/dfle/error.h:

include/dfle/param.h:

include/dfle/record.h:

include/dfle/drainage.h:
