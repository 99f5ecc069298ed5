/*
 * extlib.h - shared libraries the library loads on first use (GDAL,
 * netCDF), private to the library.
 *
 * GDAL and libnetcdf bring about a hundred shared libraries with them
 * (PROJ, GEOS, HDF5, curl, ...), whose loading and relocation cost tens
 * of milliseconds of CPU in every process that links them, although most
 * scripts never read a DEM or write a GeoTIFF or NetCDF file.  So the
 * library does not link them: it dlopen()s each by the soname the build
 * found (the one the linker would have recorded) the first time it is
 * needed and calls it through a table of function pointers
 * (gdal_lib.h, netcdf_lib.h).  This file is the part common to both:
 * open, resolve every name, and keep a message saying why not.
 */
#ifndef DFLE_BASE_EXTLIB_H
#define DFLE_BASE_EXTLIB_H

#include <pthread.h>
#include <stddef.h>

#include "dfle/error.h"

/* A function to resolve: its name and where its pointer goes in the
 * library's table (a struct of function pointers). */
typedef struct dfle_extlib_sym {
    const char *name;
    size_t offset;
} dfle_extlib_sym;

/* One library to load: the fields above `lock` are set by its owner
 * (gdal_lib.c, netcdf_lib.c), with `lock` = PTHREAD_MUTEX_INITIALIZER
 * and the rest zero; dfle_extlib_load fills the rest. */
typedef struct dfle_extlib {
    const char *what;             /* for messages: "GDAL"                     */
    const char *soname;           /* "libgdal.so.32", fixed by the build      */
    const char *package;          /* "libgdal32": what provides it, or ""     */
    const dfle_extlib_sym *syms;  /* the n functions to resolve               */
    size_t n;
    void *table;                  /* receives their addresses                 */
    void (*loaded)(void);         /* optional: run once, after loading        */
    pthread_mutex_t lock;
    int tried;                    /* 1 once loading was attempted             */
    int status;                   /* DFLE_OK once every name is resolved      */
    char why[DFLE_ERROR_MSG_MAX]; /* the loader's reason when status != 0     */
} dfle_extlib;

/* Load lib if no call has tried yet (thread-safe): open lib->soname,
 * resolve every function into lib->table, run lib->loaded.  Returns
 * DFLE_OK, or DFLE_EEXTERNAL with the message "<who>: <what> could not
 * be loaded: <dlerror's words>; install <package> ..." at this call and
 * every later one: there is one attempt per process, and the library
 * stays loaded for the process. */
int dfle_extlib_load(dfle_extlib *lib, const char *who, dfle_error *err);

#endif
