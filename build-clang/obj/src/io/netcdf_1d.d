build-clang/obj/src/io/netcdf_1d.o: src/io/netcdf_1d.c \
  include/dfle/netcdf.h include/dfle/error.h include/dfle/raster.h \
  include/dfle/record.h include/dfle/param.h include/dfle/file.h \
  src/io/netcdf_internal.h src/base/netcdf_lib.h

include/dfle/netcdf.h:

include/dfle/error.h:

include/dfle/raster.h:

include/dfle/record.h:

include/dfle/param.h:

include/dfle/file.h:

src/io/netcdf_internal.h:

src/base/netcdf_lib.h:
