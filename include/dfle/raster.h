/*
 * raster.h - writing grids: GeoTIFF (through GDAL) and NetCDF time
 * series (CF conventions, through the netCDF C library), and reading a
 * NetCDF record back (a restart).
 *
 * Grids are row-major, row 0 at the north, NaN = NoData, as everywhere
 * in dfle (dem.h, drainage.h, landscape.h); a grid lies where its
 * dfle_raster_geo says.  Every file is written whole or not at all
 * (file.h): to a temporary file beside the target, renamed over it once
 * complete.  GDAL and libnetcdf are not linked: the first GeoTIFF or
 * NetCDF file loads its library, and where it cannot be loaded the
 * call fails with DFLE_EEXTERNAL, saying what to install.
 */
#ifndef DFLE_RASTER_H
#define DFLE_RASTER_H

#include <stddef.h>

#include "dfle/error.h"
#include "dfle/record.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Where a grid lies: its north-west corner (E, N) [m], cell size [m],
 * and the CRS as WKT (NULL: none). */
typedef struct dfle_raster_geo {
    double x0, y0;
    double dx, dy;
    const char *crs_wkt;
} dfle_raster_geo;

/* One band of a GeoTIFF: nx * ny values, a name (the band's
 * description) and a unit in dfle's style ("m", "m^2", "m/yr", "-"),
 * written as the band's unit in UDUNITS' ("m2", "1"); NULL: none. */
typedef struct dfle_raster_band {
    const double *values;
    const char *name;
    const char *units;
} dfle_raster_band;

/* A GeoTIFF of nbands Float64 bands (deflate, tiled), NoData NaN, the
 * grid's geotransform and CRS, and the record (may be NULL) as
 * metadata items (dfle_version, history, <section>_<key>, as in NetCDF
 * files).  The name must end in .tif or .tiff (any case) and be a
 * regular file or a new one (file.h, dfle_file_begin_regular):
 * DFLE_EINVAL or DFLE_EIO naming the path otherwise, and when GDAL
 * cannot write it (its reason quoted). */
int dfle_raster_write_geotiff(const char *path, size_t nx, size_t ny, const dfle_raster_geo *geo,
                              size_t nbands, const dfle_raster_band *bands,
                              const dfle_record *rec, dfle_error *err);

/* 1 if `path` ends in one of the extensions of the NULL-terminated list
 * (".tif", ...; case ignored). */
int dfle_raster_has_extension(const char *path, const char *const *ext);

/* --- NetCDF time series ------------------------------------------------
 * CF-1.8, netCDF-4 (HDF5) with deflate.  Dimensions (time, y, x), time
 * unlimited; x and y at cell centres [m] (projection_x/y_coordinate);
 * time in model years (units "common_years since 0000-01-01 00:00:00",
 * calendar "noleap", while the last time is under 290,000 years, else
 * "common_year"); with a CRS, the grid mapping variable "crs"
 * (grid_mapping_name and its parameters where CF names the projection,
 * crs_wkt, spatial_ref) and lat, lon (degrees, on the CRS's datum) as
 * auxiliary coordinates of every field.  A field is a double (or, with
 * float32, a float) with units UDUNITS reads, long_name, standard_name
 * where CF has one, _FillValue NaN; a flag field (flag_meanings) is a
 * byte with flag_values 0, 1, ..., _FillValue -1.  Global attributes:
 * Conventions, title, source, history, date_created and the record's
 * entries (numbers as numbers).  The file is written to a temporary
 * regular file and renamed over the target at dfle_nc_close; a target
 * that is not a regular file (a device, a FIFO, a link to one) is
 * refused and left as it is. */
typedef struct dfle_nc dfle_nc;

typedef struct dfle_nc_var {
    const char *name;      /* "z", "E_df", ...                             */
    const char *units;     /* dfle's style: "m", "m^2", "m/yr", "-"; NULL: none */
    const char *long_name; /* "elevation", ...                             */
    const char *standard_name; /* CF standard name, or NULL                */
    const char *flag_meanings; /* a flag field: "hillslope channel channel_head"
                                  (values 0, 1, 2), or NULL               */
} dfle_nc_var;

typedef struct dfle_nc_opts {
    const char *title;             /* global title (NULL: "dfle")           */
    const dfle_record *provenance; /* global attributes, or NULL (then
                                      dfle_nc_annotate may give them)      */
    int float32;                   /* 1: fields as 32-bit floats (coordinates
                                      and time stay doubles)       (0)     */
    int deflate;                   /* zlib level, 0 (none) to 9          (4) */
    const double *mask;            /* grids: nx * ny values whose NaN mark
                                      NoData; the file covers the bounding box
                                      of the rest (a catchment's, not the
                                      DEM's).  NULL: the whole grid        */
} dfle_nc_opts;

void dfle_nc_opts_default(dfle_nc_opts *o);

int dfle_nc_create(const char *path, size_t nx, size_t ny, const dfle_raster_geo *geo,
                   size_t nvars, const dfle_nc_var *vars, const dfle_nc_opts *opts,
                   dfle_nc **out, dfle_error *err);
/* Append one time [yr]: values[k] holds nx * ny values of variable k
 * (the whole grid; the file keeps its window). */
int dfle_nc_append(dfle_nc *nc, double t, const double *const *values, dfle_error *err);
size_t dfle_nc_steps(const dfle_nc *nc);
/* The window of the grid the file holds: first column and row, columns
 * and rows. */
void dfle_nc_window(const dfle_nc *nc, size_t *c0, size_t *r0, size_t *nx, size_t *ny);
/* The provenance as global attributes (history and the record's
 * entries), for a record finished after the file was made (how the run
 * ended): once, and only if dfle_nc_opts.provenance was NULL
 * (DFLE_ESTATE otherwise).  A file closed without a record says when
 * and by what it was written. */
int dfle_nc_annotate(dfle_nc *nc, const dfle_record *rec, dfle_error *err);
/* Close and put the file in place (rename over the target). */
int dfle_nc_close(dfle_nc *nc, dfle_error *err);
/* Give up: remove the temporary file (nc may be NULL). */
void dfle_nc_abort(dfle_nc *nc);

/* --- Reading a record back --------------------------------------------
 * Field `var` at record `index` (0-based; or, with index (size_t)-1, at
 * the record whose time is `t` [yr] within 1e-9 relative) of a NetCDF
 * grid file dfle wrote, placed on a grid of nx x ny cells of dx x dy
 * whose north-west corner is (x0, y0): the file's x and y must be cell
 * centres of that grid (within 1e-6 of a cell), its window inside it.
 * out receives nx * ny values, NaN outside the window.  *t_found
 * receives the record's time (may be NULL).  DFLE_EINVAL or DFLE_EIO
 * naming the file and what does not match. */
int dfle_nc_read_grid(const char *path, const char *var, size_t index, double t,
                      const dfle_raster_geo *grid, size_t nx, size_t ny, double *out,
                      double *t_found, dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
