/*
 * drainage.h - flow routing on a plain raster grid: depression filling,
 * D8 steepest descent with flats resolved, depressions routed across,
 * receivers, donors, a stack order and drainage area.
 *
 * One routing serves both the DEM analysis (dem.h routes a real DEM
 * through it) and landscape evolution on a grid, which re-routes its
 * evolving surface every time step.  It knows nothing of files, CRSs or
 * GDAL: the input is nx * ny elevations and a cell size.  An object
 * keeps its arrays between calls, so routing changed elevations again
 * allocates nothing once the first call has sized them.
 *
 * Grid.  Cells are row-major, row 0 at the north edge, column 0 at the
 * west edge: cell (r, c) has index r * nx + c.  NaN marks a cell with no
 * data (NoData): it is outside the domain, never a receiver, donor or
 * part of the stack, and its area is NaN.
 *
 * Where water leaves the grid.  Each edge of the grid, and the border
 * of NoData, is one of three kinds (dfle_drainage_edge):
 *   OPEN        a data cell there drains off the grid when no neighbour
 *               is lower, and into the grid otherwise (the DEM rule:
 *               water may leave anywhere on the edge of the data);
 *   BASE_LEVEL  a data cell there always drains off the grid (a fixed
 *               base level: it receives but never passes water on);
 *   CLOSED      a wall: nothing leaves there.
 * A cell on two edges (a corner), or on an edge and next to NoData,
 * takes the most open of its kinds (BASE_LEVEL > OPEN > CLOSED).
 *
 * Directions (doc/dem.md has the algorithms and the reasons):
 *  - D8: a cell drains to its steepest-descent lower neighbour, drop
 *    divided by centre distance; ties go to the first neighbour in the
 *    order E, SE, S, SW, W, NW, N, NE (k = 0..7, ESRI codes 1 << k);
 *  - flats (Garbrecht and Martz 1997, as Barnes et al. 2014b): a cell
 *    with no lower neighbour on a flat that has a draining edge drains
 *    across the flat, towards lower and away from higher terrain;
 *  - depressions (dfle_drainage_depressions): left as sinks, routed over
 *    the priority-flood surface (Barnes et al. 2014a), or routed through
 *    their lowest pass by the basin graph (Cordonnier et al. 2019).
 *    The elevations given to dfle_drainage_route are never changed;
 *    dfle_drainage_fill changes elevations in place when that is wanted.
 */
#ifndef DFLE_DRAINAGE_H
#define DFLE_DRAINAGE_H

#include <stddef.h>
#include <stdint.h>

#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_drainage dfle_drainage;

/* Codes in dfle_drainage_dir(): 0..7 name the receiver among the
 * neighbours E, SE, S, SW, W, NW, N, NE; the rest have no receiver. */
enum dfle_drainage_dir_code {
    DFLE_DRAINAGE_DIR_OUT = 8,      /* drains off the grid                   */
    DFLE_DRAINAGE_DIR_SINK = 9,     /* no outflow: a pit or an undrained flat */
    DFLE_DRAINAGE_DIR_NODATA = 255  /* no elevation                          */
};

enum dfle_drainage_edge {
    DFLE_DRAINAGE_OPEN = 0,        /* drains off when nothing is lower (default) */
    DFLE_DRAINAGE_BASE_LEVEL = 1,  /* always drains off the grid                */
    DFLE_DRAINAGE_CLOSED = 2       /* nothing leaves                             */
};

/* Index into dfle_drainage_opts.edge. */
enum dfle_drainage_side {
    DFLE_DRAINAGE_NORTH = 0,  /* row 0      */
    DFLE_DRAINAGE_EAST = 1,   /* column nx-1 */
    DFLE_DRAINAGE_SOUTH = 2,  /* row ny-1   */
    DFLE_DRAINAGE_WEST = 3    /* column 0   */
};

/* What becomes of a cell with no lower neighbour and no way off the
 * grid (a pit), and of the cells draining into it. */
enum dfle_drainage_depressions {
    /* Pits stay sinks (DFLE_DRAINAGE_DIR_SINK): drainage ends there, as
     * in a real DEM that has not been filled.  The DEM's routing. */
    DFLE_DRAINAGE_KEEP = 0,
    /* Route over the filled surface: a copy of the elevations is filled
     * by priority-flood (as dfle_drainage_fill), so each depression is a
     * flat lake whose flow is resolved like any flat, converging to its
     * spill point; the same directions as filling first, without
     * changing the caller's elevations.  O(n log n). */
    DFLE_DRAINAGE_FILL = 1,
    /* Route through the basin graph (Cordonnier et al. 2019): the
     * catchment of each pit is a basin; basins are joined through their
     * lowest passes by a minimum spanning tree rooted outside the grid
     * (a basin may also spill off the grid at its lowest cell on an
     * OPEN border), and the flow path from each pass down to its
     * basin's pit is reversed (carved), so the pit drains out over its
     * pass and every receiver stays a D8 neighbour.  A region with no
     * way out keeps one sink, its lowest pit.  Linear in practice: the
     * landscape model's choice. */
    DFLE_DRAINAGE_CARVE = 2
};

/* The order of the stack; both put every cell after its receiver,
 * roots first, and give the same areas. */
enum dfle_drainage_order {
    /* Kahn's topological order read backwards (Kahn's starts with the
     * cells that have no donors, in index order, and takes a cell once
     * all its donors are out).  The fastest to build (its work is
     * independent cell to cell) and the order the DEM lists.  Default. */
    DFLE_DRAINAGE_KAHN = 0,
    /* Each root, in index order, then its tree depth-first, donors in
     * index order (Braun and Willett 2013): each tree's cells are
     * contiguous, for work done basin by basin.  Slower to build on
     * large grids (each step waits on the last). */
    DFLE_DRAINAGE_DEPTH_FIRST = 1,
    /* Cells without donors in index order, each followed down its
     * receivers by every cell it is the last donor of, read backwards.
     * Each step is the cell just done or its neighbour, so on grids
     * larger than the cache it is the fastest to build and to sweep in
     * (the landscape model's order). */
    DFLE_DRAINAGE_CHAINS = 2
};

typedef struct dfle_drainage_opts {
    size_t nx, ny;          /* columns and rows, >= 1, nx * ny < 2^32       */
    double dx, dy;          /* cell width (E-W) and height (N-S) [m], > 0   */
    enum dfle_drainage_edge edge[4]; /* by dfle_drainage_side               */
    enum dfle_drainage_edge nodata;  /* data cells next to NoData           */
    enum dfle_drainage_depressions depressions;
    enum dfle_drainage_order order;
} dfle_drainage_opts;

/* Defaults: no grid (nx = ny = 0), dx = dy = 1 m, every edge and NoData
 * OPEN (the DEM rule), pits kept, Kahn's stack. */
void dfle_drainage_opts_default(dfle_drainage_opts *o);

int dfle_drainage_new(const dfle_drainage_opts *opts, dfle_drainage **out, dfle_error *err);
void dfle_drainage_free(dfle_drainage *dr);

/* Cells that always drain off the grid, wherever they lie: fixed
 * base-level points such as a catchment's outlet in a grid whose other
 * cells are walled in by CLOSED NoData.  n cell indices, copied (NULL
 * or 0 clears them); each behaves like a cell on a BASE_LEVEL edge.
 * DFLE_EINVAL for an index off the grid. */
int dfle_drainage_set_outlets(dfle_drainage *dr, const size_t *cells, size_t n,
                              dfle_error *err);

/* Hysteresis in the choice of receivers: from the next routing on, a
 * cell keeps the receiver of the last successful routing while that
 * neighbour is still lower and its slope is at least (1 - margin) times
 * the steepest; otherwise D8 as above.  margin = 0 (the default) is
 * plain D8.  Meant for iterations that re-route a surface built from
 * its own network (the landscape's direct steady state), where exact
 * and near ties would otherwise flip from one routing to the next.
 * DFLE_EINVAL unless 0 <= margin < 1. */
int dfle_drainage_set_hysteresis(dfle_drainage *dr, double margin, dfle_error *err);
/* The directions (dfle_drainage_dir's, n values) the next routing's
 * hysteresis keeps, instead of the last routing's: for a caller that
 * routed other surfaces since (steps taken to check a state) and goes
 * back to a surface it routed with these, which the next routing then
 * gives as it did.  The other outputs are stale until that routing.
 * DFLE_ESTATE before the first routing. */
int dfle_drainage_keep_directions(dfle_drainage *dr, const unsigned char *dir, dfle_error *err);

/* Route nx * ny elevations [m] (NaN = NoData): directions, receivers,
 * donors, stack and area, replacing those of the last call.  z is read,
 * never changed, and not kept.  DFLE_EINVAL if every cell is NoData or
 * an elevation is infinite. */
int dfle_drainage_route(dfle_drainage *dr, const double *z, dfle_error *err);

typedef struct dfle_drainage_fill_stats {
    size_t raised;     /* cells whose elevation was raised  */
    double max_raise;  /* largest rise [m]                  */
    double volume;     /* sum of rises times cell area [m^3] */
} dfle_drainage_fill_stats;

/* Raise every cell of z (nx * ny, NaN = NoData) to its spill elevation,
 * in place, by priority-flood from the cells where water may leave the
 * grid (OPEN and BASE_LEVEL edges and NoData borders).  Depressions
 * become exactly flat (no epsilon gradient).  A region with no way out
 * is left as it is.  Does not touch the routing of the last route call.
 * stats may be NULL. */
int dfle_drainage_fill(dfle_drainage *dr, double *z, dfle_drainage_fill_stats *stats,
                       dfle_error *err);

/* After a successful dfle_drainage_route (NULL before, or after a
 * failed one); the arrays belong to the object and are rewritten by the
 * next route call. */

/* Receiver of each cell; a cell with none (off the grid, sink, NoData)
 * is its own receiver, so rcv[i] == i marks the roots. */
const uint32_t *dfle_drainage_receivers(const dfle_drainage *dr);
/* Direction code of each cell (enum dfle_drainage_dir_code). */
const unsigned char *dfle_drainage_dir(const dfle_drainage *dr);
/* Donors in compressed rows: the donors of cell i are
 * donors[offsets[i] .. offsets[i + 1]), in increasing index order;
 * offsets has nx * ny + 1 entries. */
const uint32_t *dfle_drainage_donors(const dfle_drainage *dr, const uint32_t **offsets);
/* The data cells, roots first, every cell after its receiver (a stack
 * in the sense of Braun and Willett 2013), in the order of the options:
 * walk it forwards to go downstream-first (implicit erosion), backwards
 * to accumulate. */
const uint32_t *dfle_drainage_stack(const dfle_drainage *dr, size_t *n_stack);
/* Drainage area [m^2], counting the cell itself: (1 + cells upstream)
 * dx dy, exact in whole cells; NaN on NoData. */
const double *dfle_drainage_area(const dfle_drainage *dr);

typedef struct dfle_drainage_counts {
    size_t data;     /* data cells (the stack's length)                    */
    size_t outlets;  /* cells draining off the grid                        */
    size_t sinks;    /* cells with no outflow at the end                   */
    size_t pits;     /* cells with no outflow after D8 and flats, before
                        depressions were handled (KEEP: = sinks)          */
    size_t flats;    /* cells routed across flats                          */
    size_t filled;   /* FILL: cells below their spill elevation            */
    size_t carved;   /* CARVE: cells whose receiver was reversed           */
    size_t basins;   /* CARVE: pit basins joined through the basin graph   */
} dfle_drainage_counts;

/* Counts of the last route call (all 0 before). */
dfle_drainage_counts dfle_drainage_get_counts(const dfle_drainage *dr);

/* The grid, as given to dfle_drainage_new. */
void dfle_drainage_get_opts(const dfle_drainage *dr, dfle_drainage_opts *o);

/* Neighbour k (0..7: E, SE, S, SW, W, NW, N, NE) of cell i, or -1 off
 * the grid; and the centre-to-centre distance to it [m]. */
long long dfle_drainage_neighbour(const dfle_drainage *dr, size_t i, int k);
double dfle_drainage_length(const dfle_drainage *dr, int k);

/* Bytes the object holds now (its arrays and workspace). */
size_t dfle_drainage_memory(const dfle_drainage *dr);

/* Free the workspace kept between calls (about 5-40 bytes a cell, more
 * where the basin graph had many links), for an object that will not
 * route again soon; the results stay valid, and the next call allocates
 * what it needs again. */
void dfle_drainage_trim(dfle_drainage *dr);

#ifdef __cplusplus
}
#endif
#endif
