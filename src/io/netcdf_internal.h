/*
 * netcdf_internal.h - what the NetCDF writers of src/io/ share
 * (netcdf_cf.c): CF-1.8 attributes in one place, so the grids of a
 * landscape (netcdf.c), the records of a profile and the tables of an
 * ensemble (netcdf_1d.c) say units, time, provenance and the CRS alike.
 * Not installed.
 *
 * Every function takes an open netCDF id in define mode and returns a
 * netCDF status (NC_NOERR), except where it says DFLE_OK.
 */
#ifndef DFLE_IO_NETCDF_INTERNAL_H
#define DFLE_IO_NETCDF_INTERNAL_H

#include <stddef.h>

#include "base/netcdf_lib.h"
#include "dfle/netcdf.h"
#include "dfle/raster.h"
#include "dfle/record.h"

/* Model time decodes as a date (CF "since") while the largest time is
 * below this [yr]: cftime, which xarray decodes with, counts in 64-bit
 * microseconds, 292,471 years at most. */
#define NC_CF_SINCE_MAX_YEARS 2.9e5

/* The `units` attribute of var from a dfle unit (NULL: none), or, when
 * UDUNITS cannot say it, the text as `dfle_units`. */
int nc_cf_put_units(int ncid, int var, const char *unit);

int nc_cf_put_text(int ncid, int var, const char *name, const char *text);

/* A time coordinate's attributes: standard_name, long_name, axis,
 * calendar "noleap" and units "common_years since 0000-01-01 00:00:00"
 * (model years, year 0 the start) when t_max < NC_CF_SINCE_MAX_YEARS,
 * else units "common_year" (a duration, which every reader takes as a
 * number). */
int nc_cf_put_time(int ncid, int var, double t_max);

/* Conventions, title, source, dfle_version and, with rec (may be NULL),
 * its provenance (nc_cf_put_provenance). */
int nc_cf_put_globals(int ncid, const char *title, const dfle_record *rec);

/* history ("<date>: <command>" from rec, or when and what wrote the
 * file when rec is NULL or names no command) and, with rec, every entry
 * as a global attribute (nc_cf_put_record).  Written once a file: HDF5
 * replaces an attribute through paths valgrind finds reading
 * uninitialised memory of its own. */
int nc_cf_put_provenance(int ncid, const dfle_record *rec);

/* The record as global attributes: top-level entries as dfle_<key>,
 * each section's kind as <section> and its entries as <section>_<key>
 * (numbers as doubles, true/false as 0/1 ints, texts and lists as text),
 * its units as <section>_units, "key=unit, ...". */
int nc_cf_put_record(int ncid, const dfle_record *rec);

/* The grid mapping variable "crs" for a CRS in WKT (a scalar int):
 * grid_mapping_name and its parameters where CF names the projection
 * (transverse_mercator, lambert_conformal_conic, albers_conical_equal_
 * area, lambert_azimuthal_equal_area, polar_stereographic, mercator,
 * latitude_longitude), the ellipsoid, the CRS's names, crs_wkt and
 * spatial_ref (GDAL's).  *var receives its id.  DFLE_OK or a dfle
 * status with err set (GDAL cannot be loaded, a netCDF error). */
int nc_cf_def_crs(int ncid, const char *wkt, int *var, const char *path, dfle_error *err);

/* Deflate (shuffle and zlib at `level`, 0 = none) on var. */
int nc_cf_deflate(int ncid, int var, int level);

/* "netcdf: cannot write '<path>' (<what>): <netCDF's reason>" */
int nc_cf_fail(const char *path, int status, const char *what, dfle_error *err);

#endif
