build-clang/obj/src/base/netcdf_lib.o: src/base/netcdf_lib.c \
  src/base/netcdf_lib.h include/dfle/error.h src/base/extlib.h \
  build-clang/gen/extlib_names.h

src/base/netcdf_lib.h:

include/dfle/error.h:

src/base/extlib.h:

build-clang/gen/extlib_names.h:
