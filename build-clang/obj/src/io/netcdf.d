build-clang/obj/src/io/netcdf.o: src/io/netcdf.c include/dfle/raster.h \
  include/dfle/error.h include/dfle/record.h include/dfle/param.h \
  include/dfle/crs.h include/dfle/file.h src/io/netcdf_internal.h \
  src/base/netcdf_lib.h include/dfle/netcdf.h

include/dfle/raster.h:

include/dfle/error.h:

include/dfle/record.h:

include/dfle/param.h:

include/dfle/crs.h:

include/dfle/file.h:

src/io/netcdf_internal.h:

src/base/netcdf_lib.h:

include/dfle/netcdf.h:
