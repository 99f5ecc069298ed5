/*
 * dem_gdal.h - a DEM to and from an in-memory GDAL dataset (dem.c), for
 * the operations GDAL does on grids (dem_warp.c: resampling, cropping).
 * Private to src/dem/; include after base/gdal_lib.h.
 */
#ifndef DFLE_DEM_GDAL_H
#define DFLE_DEM_GDAL_H

#include "base/gdal_lib.h"
#include "dfle/dem.h"

/* The DEM as a one-band Float64 dataset of GDAL's MEM driver: its
 * geotransform, CRS, and NoData NaN.  NULL with err set. */
GDALDatasetH dem_to_gdal(const dfle_dem *d, dfle_error *err);

/* A DEM from band 1 of a dataset, with every check of dfle_dem_read
 * (`what` names it in messages); it has no file (path NULL). */
int dem_from_gdal(GDALDatasetH ds, const char *what, dfle_dem **out, dfle_error *err);

#endif
