build-clang/obj/src/io/netcdf_read.o: src/io/netcdf_read.c \
  include/dfle/raster.h include/dfle/error.h include/dfle/record.h \
  include/dfle/param.h src/base/netcdf_lib.h include/dfle/crs.h

include/dfle/raster.h:

include/dfle/error.h:

include/dfle/record.h:

include/dfle/param.h:

src/base/netcdf_lib.h:

include/dfle/crs.h:
