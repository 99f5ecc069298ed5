/*
 * dem_internal.h - the dfle_dem structure, shared by the files of
 * src/dem/.  Not installed.
 *
 * The files are layered, each calling only the ones below it, never
 * back up:
 *   dem_profile.c  profiles and networks         (uses dem_flow, dem_grid)
 *   dem_flow.c     fill and routing of the DEM   (uses dem_grid, drainage)
 *   dem_grid.c     geometry, CRS checks, access  (uses nothing of the DEM)
 *   dem.c          reading (GDAL), making and freeing the object
 * and the routing itself is src/drainage/ (drainage.h), which knows
 * nothing of DEMs.  This header declares no functions, so it carries no
 * calls between the layers.
 */
#ifndef DFLE_DEM_INTERNAL_H
#define DFLE_DEM_INTERNAL_H

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/dem.h"
#include "dfle/drainage.h"

struct dfle_dem {
    size_t nx, ny, n;       /* columns, rows, cells (n < 2^32)           */
    double x0, y0, dx, dy;  /* north-west corner, cell size [m]          */
    double *z;              /* elevations, NaN = NoData                  */
    size_t n_nodata;

    char *path;             /* as given to dfle_dem_read; NULL in memory */
    char *crs_wkt, *crs_name; /* NULL when the file has no CRS           */
    int epsg;               /* 0 when unknown                            */
    int geographic;         /* CRS in degrees                            */
    double linear_unit;     /* metres per horizontal unit; 0 = no CRS    */
    char *linear_unit_name;

    int filled;             /* dfle_dem_fill has run since z last changed */

    /* Filling and routing, made on first need (dem_flow.c).  Its results
     * describe z while `routed`; a fill that raises a cell clears it. */
    dfle_drainage *flow;
    int routed;
    uint32_t *order;        /* the stack backwards: each cell before its
                               receiver, as dfle_dem_order has always
                               listed them (n - n_nodata cells)          */
};

/* A profile or network (dem_profile.c makes them, dem_profile_out.c
 * writes them). */
struct dfle_profile {
    size_t n;
    int network;
    double *f[DFLE_PROFILE_NFIELDS];
    size_t *receiver;       /* 1-based index of the receiver, 0 = none */
    double given[2], snapped[2];
    dfle_slope_opts slope;
    /* Provenance (dfle_profile_describe): the DEM's file (NULL when it
     * was made in memory), its CRS as WKT (NULL: none) and the limits
     * asked for. */
    char *dem, *crs;
    int from_head;
    double A_min, A_max, radius;
};

/* *dst = a copy of src (NULL stays NULL); nonzero when memory ran out. */
static inline int profile_copy_text(char **dst, const char *src)
{
    *dst = NULL;
    if (src == NULL)
        return 0;
    if ((*dst = malloc(strlen(src) + 1)) == NULL)
        return 1;
    memcpy(*dst, src, strlen(src) + 1);
    return 0;
}

#endif
