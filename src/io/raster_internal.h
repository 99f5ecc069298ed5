/*
 * raster_internal.h - what the GDAL writers of src/io/ share: a record
 * (record.h) as GDAL metadata items (raster.c), for GeoTIFFs and
 * GeoPackages (vector.c) alike.  Not installed.
 */
#ifndef DFLE_IO_RASTER_INTERNAL_H
#define DFLE_IO_RASTER_INTERNAL_H

#include "base/gdal_lib.h"
#include "dfle/record.h"

/* dfle_version, history and every entry of rec (may be NULL) as the
 * metadata items <name> = <text> of a dataset or layer: names as in
 * NetCDF files (dfle_record_flat_name), numbers as their shortest exact
 * text and their unit. */
void raster_put_record(GDALMajorObjectH obj, const dfle_record *rec);

#endif
