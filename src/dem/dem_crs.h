/*
 * dem_crs.h - a CRS already in GDAL's hands, described (dem_crs.c), for
 * the reader (dem.c): the file's own definition, not its WKT read again
 * (a WKT 1 of a geographic CRS gains axes in the export that an EPSG
 * match then scores lower).  Private to src/dem/.
 */
#ifndef DFLE_DEM_CRS_H
#define DFLE_DEM_CRS_H

#include "base/gdal_lib.h"
#include "dfle/crs.h"

void dem_crs_describe(OGRSpatialReferenceH srs, dfle_crs_info *info);

#endif
