/*
 * vector.h - channel profiles, networks and catchments as vector layers
 * of a GeoPackage (through GDAL/OGR), for QGIS and every GIS that reads
 * OGC GeoPackage.
 *
 * Layers, each in the DEM's CRS (none when the DEM has none):
 *  - "channels": one LineString a cell of a profile or network, from the
 *    cell's centre to its receiver's (the outlet, which has none, is the
 *    last point of its receiver's line), with the cell's attributes:
 *    cell (its 1-based row in the CSV table), receiver (0: none), x, d,
 *    z, A, S, E, N;
 *  - "cells": one Point a cell, the same attributes (the outlet too);
 *  - "catchment": the area draining to an outlet as one polygon (cells
 *    joined by edges and corners, as D8 joins them), with area [m^2],
 *    cells, and the outlet as given and as snapped.
 * The file is written whole or not at all, over a regular file only
 * (file.h, dfle_file_begin_regular); its name must end in .gpkg.  The
 * record (may be NULL) goes into the GeoPackage's metadata.  GDAL is
 * loaded by the first call (it is not linked).
 */
#ifndef DFLE_VECTOR_H
#define DFLE_VECTOR_H

#include "dfle/dem.h"
#include "dfle/error.h"
#include "dfle/record.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_vector_opts {
    const dfle_profile *channels; /* "channels" and "cells", or NULL     */
    dfle_dem *catchment_of;       /* with `outlet`: "catchment", or NULL  */
    double outlet[2];             /* (E, N) [m], snapped as dem:network    */
    double radius;                /* snapping radius [m]; < 0: default     */
    const dfle_record *provenance;
} dfle_vector_opts;

void dfle_vector_opts_default(dfle_vector_opts *o);

int dfle_vector_write_gpkg(const char *path, const dfle_vector_opts *o, dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
