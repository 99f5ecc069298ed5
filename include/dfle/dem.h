/*
 * dem.h - digital elevation models: reading (GDAL), depression filling,
 * D8 flow routing, drainage area, channel profiles and networks with
 * their slope-area data.
 *
 * This is the observational side of McGuire et al. (2023): Fig. 1 fits
 * Eq. (2) to slope-area data extracted from real DEMs.  The functions
 * here turn a raster into (x, z, A, S) along a channel, which the
 * analysis (analysis.h) and the model (channel.h) take as they take a
 * modelled profile.
 *
 * Grid conventions.  Cells are stored row-major, row 0 at the north
 * edge, column 0 at the west edge: cell (r, c) has index r * nx + c and
 * its centre at E = x0 + (c + 0.5) dx, N = y0 - (r + 0.5) dy, where
 * (x0, y0) is the north-west corner of the grid.  Cells without data
 * (the file's NoData value, NaN) hold NaN in dfle_dem_z(); every
 * algorithm treats them as outside the grid, so a NaN never enters an
 * area, a slope or a fit.  Horizontal units are the CRS's (metres are
 * required for anything that measures distance or area); elevations
 * are taken to be in metres.
 *
 * Algorithms (details and reasons in doc/dem.md), all of them the
 * routing module's (drainage.h) with every edge and NoData border open:
 *  - filling: priority-flood (Barnes et al. 2014) seeded from the grid
 *    edge and the cells next to NoData, to the exact spill elevation
 *    (no epsilon gradient: flats stay flat and are resolved below);
 *  - D8: each cell drains to its steepest-descent lower neighbour
 *    (drop / centre distance); ties go to the first neighbour in the
 *    order E, SE, S, SW, W, NW, N, NE (the ESRI direction codes 1, 2,
 *    4, ..., 128); a boundary cell with no lower neighbour drains off
 *    the grid;
 *  - flats: Garbrecht and Martz (1997) as formulated by Barnes et al.
 *    (2014): towards lower terrain and away from higher terrain;
 *  - drainage area: planimetric, in m^2, counting the cell itself,
 *    accumulated in topological order (no recursion).
 */
#ifndef DFLE_DEM_H
#define DFLE_DEM_H

#include <stddef.h>
#include <stdint.h>

#include "dfle/channel.h"
#include "dfle/error.h"
#include "dfle/record.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_dem dfle_dem;

/* Flow-direction codes in dfle_dem_dir(): 0..7 name the receiver among
 * the neighbours E, SE, S, SW, W, NW, N, NE; the rest have none. */
enum dfle_dem_dir_code {
    DFLE_DEM_DIR_OUT = 8,      /* boundary outlet: drains off the grid    */
    DFLE_DEM_DIR_SINK = 9,     /* interior pit or undrained flat          */
    DFLE_DEM_DIR_NODATA = 255  /* no elevation                            */
};

typedef struct dfle_dem_read_opts {
    int band;          /* 1-based raster band; 0 = 1                      */
    int set_nodata;    /* 1: `nodata` marks NoData, replacing the file's  */
    double nodata;     /* elevation value that means "no data"            */
    const char *crs;   /* CRS to assign (EPSG:32611, WKT, PROJ string...)
                          replacing the file's; NULL = the file's         */
} dfle_dem_read_opts;

/* Read band `band` of any raster GDAL opens (GeoTIFF, ESRI ASCII, ...).
 * opts may be NULL.  Fails with DFLE_EIO (missing file, a format GDAL
 * does not read, read error) or DFLE_EINVAL (no georeferencing, a
 * rotated or south-up grid, a band that does not exist, no data at
 * all), the message naming the path.  A geographic (degree) grid is
 * read; routing and profiles then refuse it (dfle_dem_check_metric).
 * GDAL is loaded by the first call (it is not linked); DFLE_EEXTERNAL,
 * saying what to install, where it cannot be. */
int dfle_dem_read(const char *path, const dfle_dem_read_opts *opts, dfle_dem **out,
                  dfle_error *err);

/* Where an in-memory grid lies. */
typedef struct dfle_dem_geo {
    double x0, y0;  /* north-west corner of the grid (E, N) [m]   */
    double dx, dy;  /* cell width (E-W) and height (N-S) [m], > 0 */
} dfle_dem_geo;

/* A DEM from nx * ny elevations [m] (row-major, row 0 at the north;
 * NaN = NoData), copied.  No CRS: horizontal units are taken as m. */
int dfle_dem_new(size_t nx, size_t ny, const double *z, const dfle_dem_geo *geo,
                 dfle_dem **out, dfle_error *err);

void dfle_dem_free(dfle_dem *dem);

/* Give the DEM a CRS (any text GDAL reads: "EPSG:32611", WKT, PROJ),
 * replacing its own; DFLE_EINVAL when GDAL does not understand it.
 * Loads GDAL (crs.h). */
int dfle_dem_set_crs(dfle_dem *dem, const char *crs, dfle_error *err);

size_t dfle_dem_nx(const dfle_dem *dem);
size_t dfle_dem_ny(const dfle_dem *dem);
double dfle_dem_dx(const dfle_dem *dem);   /* cell width [m]   */
double dfle_dem_dy(const dfle_dem *dem);   /* cell height [m]  */
/* ext = {E_min, E_max, N_min, N_max} of the grid's outer edges [m]. */
void dfle_dem_extent(const dfle_dem *dem, double ext[4]);
const double *dfle_dem_z(const dfle_dem *dem);   /* nx * ny, NaN = NoData */
size_t dfle_dem_nodata_count(const dfle_dem *dem);
const char *dfle_dem_path(const dfle_dem *dem);    /* NULL if in memory  */
const char *dfle_dem_crs_name(const dfle_dem *dem); /* NULL if unknown   */
const char *dfle_dem_crs_wkt(const dfle_dem *dem);  /* NULL if unknown   */
int dfle_dem_epsg(const dfle_dem *dem);             /* 0 if unknown      */
int dfle_dem_is_geographic(const dfle_dem *dem);    /* 1: degrees        */

/* Where the DEM comes from, into a record (record.h): section "dem" with
 * its file (if read from one), cells, cell size [m], CRS (name, EPSG
 * code), and whether it was filled. */
void dfle_dem_describe(const dfle_dem *dem, dfle_record *rec);

/* DFLE_OK if horizontal units are metres (a projected CRS in metres, or
 * no CRS and a grid that does not look like degrees); otherwise
 * DFLE_EINVAL with a message saying that `what` needs metres and how to
 * reproject. */
int dfle_dem_check_metric(const dfle_dem *dem, const char *what, dfle_error *err);

/* Elevations that read but are almost surely wrong: cells holding a
 * common NoData marker (-9999, -32768, ...) the file did not declare, or
 * a range beyond any on land.  Writes one sentence with the fix into msg
 * and returns 1; 0 if nothing looks wrong.  Callers warn; the values
 * are kept as read. */
int dfle_dem_check_plausible(const dfle_dem *dem, char *msg, size_t cap);

/* Index of the cell containing map point (E, N) [m].  DFLE_EINVAL,
 * naming `what` and the grid's extent, when the point is outside. */
int dfle_dem_cell_at(const dfle_dem *dem, double E, double N, const char *what,
                     size_t *index, dfle_error *err);
/* Centre of cell `index` [m]. */
void dfle_dem_cell_centre(const dfle_dem *dem, size_t index, double *E, double *N);

/* --- dem_warp.c: resampling and cropping through GDAL ----------------- */

/* A new DEM of cells dx x dy [m] (dy 0: = dx) over the same extent from
 * the same north-west corner (the last column and row reach past the
 * old edge when the extent is not a whole number of new cells), by
 * GDAL's warper with `method`: "nearest", "bilinear", "cubic",
 * "cubicspline", "lanczos", "average", "min", "max", "median", "mode";
 * NULL: "average" for coarser cells, "bilinear" for finer.  NoData is
 * left out of every method.  The CRS is kept; the new DEM has no file
 * and is neither filled nor routed. */
int dfle_dem_resample(const dfle_dem *dem, double dx, double dy, const char *method,
                      dfle_dem **out, dfle_error *err);

/* A new DEM of the cells that overlap box = {E_min, E_max, N_min, N_max}
 * [m] (whole cells, no resampling; through GDAL's translate); the box
 * may reach past the grid, whose edge then bounds it.  DFLE_EINVAL when
 * it does not overlap the grid. */
int dfle_dem_crop(const dfle_dem *dem, const double box[4], dfle_dem **out, dfle_error *err);

/* The outer edges of the cells with data, box = {E_min, E_max, N_min,
 * N_max} [m]; 0 when every cell is NoData. */
int dfle_dem_data_extent(const dfle_dem *dem, double box[4]);

/* --- dem_flow.c ------------------------------------------------------ */

typedef struct dfle_dem_fill_stats {
    size_t raised;     /* cells whose elevation was raised        */
    double max_raise;  /* largest rise [m]                        */
    double volume;     /* sum of rises times cell area [m^3]      */
} dfle_dem_fill_stats;

/* Fill every depression to its spill elevation, in place
 * (priority-flood).  Invalidates any routing.  stats may be NULL. */
int dfle_dem_fill(dfle_dem *dem, dfle_dem_fill_stats *stats, dfle_error *err);
int dfle_dem_is_filled(const dfle_dem *dem);

/* D8 directions with flats resolved, and drainage area.  Cached until
 * the elevations change (dfle_dem_fill).  Needs metres.  On an unfilled
 * DEM, pits are sinks (DFLE_DEM_DIR_SINK) where drainage ends. */
int dfle_dem_route(dfle_dem *dem, dfle_error *err);
int dfle_dem_is_routed(const dfle_dem *dem);
/* After routing (NULL before): codes (enum above) and area [m^2] (NaN
 * on NoData) per cell, and the data cells in topological order, every
 * cell before its receiver (n_order of them). */
const unsigned char *dfle_dem_dir(const dfle_dem *dem);
const double *dfle_dem_area(const dfle_dem *dem);
const uint32_t *dfle_dem_order(const dfle_dem *dem, size_t *n_order);
/* Receiver of cell i, or -1 (outlet, sink, NoData, not routed). */
long long dfle_dem_receiver(const dfle_dem *dem, size_t i);
size_t dfle_dem_sink_count(const dfle_dem *dem);  /* interior pits        */
size_t dfle_dem_flat_count(const dfle_dem *dem);  /* cells routed on flats */

/* --- dem_profile.c --------------------------------------------------- */

typedef struct dfle_profile dfle_profile;

/* How slope is measured along flow paths (doc/dem.md): over a fixed
 * horizontal distance `ds` [m] centred on each cell (the default), or
 * over a fixed drop `dz` [m] centred on each cell's elevation.  The
 * window runs upstream along the largest-area donor (along the profile
 * itself for a profile) and downstream along D8 receivers, with z
 * interpolated linearly in flow distance; it is cut short at a divide
 * or at the grid's edge. */
typedef struct dfle_slope_opts {
    double ds;  /* horizontal interval [m]; 0 = 3 cell widths unless dz */
    double dz;  /* vertical interval [m]; 0 = use ds                    */
} dfle_slope_opts;

typedef struct dfle_profile_opts {
    int from_head;     /* 0: upstream from an outlet; 1: down from a head   */
    double E, N;       /* outlet or head [m, map coordinates]               */
    double radius;     /* outlet snapping radius [m]; < 0 = default (2
                          cell diagonals); the outlet moves to the cell of
                          largest drainage area within it                  */
    double A_min;      /* from an outlet: stop upstream where the largest
                          donor's area < A_min [m^2]; 0 = go to the divide */
    double A_max;      /* from a head: stop at the first cell with area
                          >= A_max [m^2]; 0 = go to the grid's edge        */
    dfle_slope_opts slope;
} dfle_profile_opts;

/* Defaults: outlet mode, radius -1, no A_min/A_max, slope defaults. */
void dfle_profile_opts_default(dfle_profile_opts *o);

/* Extract a profile (routes the DEM first if needed).  Fails with
 * DFLE_EINVAL for a point outside the grid or on NoData, a DEM that
 * still has pits (fill it first), or a non-metric grid. */
int dfle_dem_profile(dfle_dem *dem, const dfle_profile_opts *o, dfle_profile **out,
                     dfle_error *err);

typedef struct dfle_network_opts {
    double A_min;      /* channel cells: area >= A_min [m^2], > 0           */
    int has_outlet;    /* 1: only the catchment above (E, N)                */
    double E, N;       /* outlet [m]                                        */
    double radius;     /* snapping radius as for profiles                   */
    dfle_slope_opts slope;
} dfle_network_opts;

void dfle_network_opts_default(dfle_network_opts *o);

/* All cells with area >= A_min (in one catchment or the whole grid), in
 * topological order (each cell before its receiver). */
int dfle_dem_network(dfle_dem *dem, const dfle_network_opts *o, dfle_profile **out,
                     dfle_error *err);

void dfle_profile_free(dfle_profile *p);

enum dfle_profile_field {
    DFLE_PROFILE_E,  /* cell centre, easting [m]                        */
    DFLE_PROFILE_N,  /* cell centre, northing [m]                       */
    DFLE_PROFILE_X,  /* profile: flow distance from the head [m];
                        network: as D                                   */
    DFLE_PROFILE_D,  /* flow distance to the outlet (last cell) [m]     */
    DFLE_PROFILE_Z,  /* elevation [m]                                   */
    DFLE_PROFILE_A,  /* drainage area [m^2]                             */
    DFLE_PROFILE_S,  /* slope [-], see dfle_slope_opts                  */
    DFLE_PROFILE_NFIELDS
};

size_t dfle_profile_size(const dfle_profile *p);
int dfle_profile_is_network(const dfle_profile *p);
const double *dfle_profile_field(const dfle_profile *p, enum dfle_profile_field f);
/* 1-based index of each cell's receiver in the arrays, 0 if it is not
 * among them (the outlet). */
const size_t *dfle_profile_receiver(const dfle_profile *p);
/* The outlet or head as given and as snapped (cell centre) [m], and the
 * slope interval used (exactly one of ds, dz is non-zero). */
void dfle_profile_point(const dfle_profile *p, double given[2], double snapped[2]);
dfle_slope_opts dfle_profile_slope(const dfle_profile *p);

/* The main stem of a network as a profile: from its outlet (the cell
 * without a receiver of largest area) upstream along the donor of
 * largest area (ties: the first in the network's order) to a cell without
 * donors, stored head first with x from the head, d to the outlet and
 * each cell's z, A and S as in the network.  For a profile, a copy.
 * This is the channel a model of the network's catchment runs on. */
int dfle_profile_main_stem(const dfle_profile *p, dfle_profile **out, dfle_error *err);

/* The CRS of the DEM the profile comes from, as WKT; NULL: none. */
const char *dfle_profile_crs_wkt(const dfle_profile *p);

/* CSV (dfle_table_write): `rec` as comment lines (may be NULL), the
 * units line, then E, N, x, d, z, A, S, receiver and, where the DEM has
 * a CRS, lon and lat (degrees on the CRS's datum, crs.h), one row per
 * cell, numbers with 10 significant digits. */
int dfle_profile_write_csv(const dfle_profile *p, const char *path, const dfle_record *rec,
                           dfle_error *err);

/* Where the profile comes from, into a record (record.h): at the top
 * level the CRS (crs: its name and EPSG code, lon_lat: the datum of lon
 * and lat, crs_wkt) where there is one; section
 * "profile" (kind "profile" or "network") with the DEM's file, the
 * direction traced, the point given and snapped [m], the radius, A_min
 * or A_max [m^2], the slope interval ds or dz [m], the cells and the
 * longest flow distance [m]. */
void dfle_profile_describe(const dfle_profile *p, dfle_record *rec);

/* A model channel on the profile's geometry: nodes every dx [m] from
 * the head (x = 0) to the last whole dx before the outlet's x, A [m^2]
 * interpolated linearly in x between cell centres, width w = k_w A^b.
 * Profiles only (a network has no single x). */
int dfle_profile_channel(const dfle_profile *p, double dx, double k_w, double b,
                         dfle_channel **out, dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
