/*
 * dem_tiff.h - a TIFF's GDAL_NODATA tag as written (dem_tiff.c), for the
 * reader (dem.c).  Private to src/dem/.
 */
#ifndef DFLE_DEM_TIFF_H
#define DFLE_DEM_TIFF_H

#include <stddef.h>

/* The text of the GDAL_NODATA tag (42113) of the first image of the TIFF
 * at `path` into buf: 1 if found, 0 if the file has none or is no TIFF
 * this reads (a GDAL virtual path, a damaged header: GDAL judges those). */
int dem_tiff_nodata_text(const char *path, char *buf, size_t cap);

/* 1 if the text is a number as GDAL means it (blanks around it allowed;
 * "nan", "inf" and "-inf" count), or empty (GDAL then sets none). */
int dem_tiff_nodata_valid(const char *text);

#endif
