/* Written by scripts/extlib-names.sh for this build; do not edit. */
#ifndef DFLE_GDAL_SONAME
#define DFLE_GDAL_SONAME "libgdal.so.32"
#endif
#ifndef DFLE_GDAL_PACKAGE
#define DFLE_GDAL_PACKAGE "libgdal32"
#endif
#ifndef DFLE_NETCDF_SONAME
#define DFLE_NETCDF_SONAME "libnetcdf.so.19"
#endif
#ifndef DFLE_NETCDF_PACKAGE
#define DFLE_NETCDF_PACKAGE "libnetcdf19"
#endif
