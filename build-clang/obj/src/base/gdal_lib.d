build-clang/obj/src/base/gdal_lib.o: src/base/gdal_lib.c \
  src/base/gdal_lib.h /usr/include/gdal/cpl_conv.h \
  /usr/include/gdal/cpl_port.h /usr/include/gdal/cpl_config.h \
  /usr/include/gdal/cpl_vsi.h /usr/include/gdal/cpl_progress.h \
  /usr/include/gdal/cpl_error.h /usr/include/gdal/gdal.h \
  /usr/include/gdal/gdal_version.h /usr/include/gdal/cpl_virtualmem.h \
  /usr/include/gdal/cpl_minixml.h /usr/include/gdal/ogr_api.h \
  /usr/include/gdal/ogr_core.h /usr/include/gdal/gdal_alg.h \
  /usr/include/gdal/gdal_utils.h /usr/include/gdal/ogr_srs_api.h \
  include/dfle/error.h src/base/extlib.h build-clang/gen/extlib_names.h

src/base/gdal_lib.h:

/usr/include/gdal/cpl_conv.h:

/usr/include/gdal/cpl_port.h:

/usr/include/gdal/cpl_config.h:

/usr/include/gdal/cpl_vsi.h:

/usr/include/gdal/cpl_progress.h:

/usr/include/gdal/cpl_error.h:

/usr/include/gdal/gdal.h:

/usr/include/gdal/gdal_version.h:

/usr/include/gdal/cpl_virtualmem.h:

/usr/include/gdal/cpl_minixml.h:

/usr/include/gdal/ogr_api.h:

/usr/include/gdal/ogr_core.h:

/usr/include/gdal/gdal_alg.h:

/usr/include/gdal/gdal_utils.h:

/usr/include/gdal/ogr_srs_api.h:

include/dfle/error.h:

src/base/extlib.h:

build-clang/gen/extlib_names.h:
