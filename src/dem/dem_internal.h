/*
 * dem_internal.h - the dfle_dem structure and the neighbour table,
 * shared by dem.c (reading, geometry), dem_flow.c (filling, routing)
 * and dem_profile.c (profiles, networks).  Not installed.
 */
#ifndef DFLE_DEM_INTERNAL_H
#define DFLE_DEM_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "dfle/dem.h"

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

    /* Routing, valid while `routed`; freed when z changes. */
    int routed;
    unsigned char *dir;     /* enum dfle_dem_dir_code per cell           */
    double *area;           /* [m^2], NaN on NoData                      */
    uint32_t *order;        /* data cells, each before its receiver      */
    size_t n_order;
    size_t n_sinks, n_flat;
};

/* The eight neighbours in D8 preference order E, SE, S, SW, W, NW, N,
 * NE (ESRI codes 1 << k); rows grow southwards. */
extern const int dfle_dem_nb_dr[8];
extern const int dfle_dem_nb_dc[8];

/* Index of neighbour k of cell (r, c), or -1 if it is off the grid. */
static inline long long dfle_dem_nb(const struct dfle_dem *d, size_t r, size_t c, int k)
{
    long long rr = (long long)r + dfle_dem_nb_dr[k];
    long long cc = (long long)c + dfle_dem_nb_dc[k];
    if (rr < 0 || cc < 0 || rr >= (long long)d->ny || cc >= (long long)d->nx)
        return -1;
    return rr * (long long)d->nx + cc;
}

/* Centre-to-centre distance to neighbour k [m]. */
double dfle_dem_nb_dist(const struct dfle_dem *d, int k);

/* Drop the routing (after the elevations changed). */
void dfle_dem_unroute(struct dfle_dem *d);

#endif
