/*
 * netcdf_lib.h - the netCDF C library, loaded on first use (extlib.h);
 * private to the library.
 *
 * dfle calls libnetcdf to write NetCDF files (io/netcdf.c, io/
 * netcdf_1d.c, io/netcdf_cf.c) and to read a record back
 * (io/netcdf_read.c).  The library does not link it (it brings HDF5 and
 * curl): dfle_netcdf_load opens it on the first call that needs it and
 * fills the table below, once per process.
 *
 * Include this header in place of <netcdf.h>: after netCDF's
 * declarations it redefines every name in DFLE_NETCDF_FNS to the
 * table's pointer, so code calling netCDF reads as plain netCDF.  Call
 * dfle_netcdf_load at each entry point before the first netCDF call.
 * To call another function, add it to DFLE_NETCDF_FNS with the type
 * <netcdf.h> gives it (netcdf_lib.c checks the two agree at compile
 * time) and a #define below; a call to a function missing from the
 * table does not link, because nothing in dfle links libnetcdf.
 */
#ifndef DFLE_BASE_NETCDF_LIB_H
#define DFLE_BASE_NETCDF_LIB_H

#include <stddef.h>

#include <netcdf.h>

#include "dfle/error.h"

/* X(return type, name, parameter types), as <netcdf.h> declares each. */
#define DFLE_NETCDF_FNS(X)                                                                   \
    X(int, nc_create, (const char *, int, int *))                                            \
    X(int, nc_close, (int))                                                                  \
    X(int, nc_sync, (int))                                                                   \
    X(int, nc_enddef, (int))                                                                 \
    X(int, nc_def_dim, (int, const char *, size_t, int *))                                   \
    X(int, nc_def_var, (int, const char *, nc_type, int, const int *, int *))                \
    X(int, nc_inq_dimlen, (int, int, size_t *))                                              \
    X(int, nc_inq_vardimid, (int, int, int *))                                               \
    X(int, nc_put_att_text, (int, int, const char *, size_t, const char *))                  \
    X(int, nc_put_att_double, (int, int, const char *, nc_type, size_t, const double *))     \
    X(int, nc_put_var_double, (int, int, const double *))                                    \
    X(int, nc_put_var1_double, (int, int, const size_t *, const double *))                   \
    X(int, nc_put_vara_double, (int, int, const size_t *, const size_t *, const double *))   \
    X(int, nc_put_var_text, (int, int, const char *))                                        \
    X(int, nc_open, (const char *, int, int *))                                              \
    X(int, nc_redef, (int))                                                                  \
    X(int, nc_def_var_deflate, (int, int, int, int, int))                                    \
    X(int, nc_def_var_chunking, (int, int, int, const size_t *))                             \
    X(int, nc_inq_dimid, (int, const char *, int *))                                         \
    X(int, nc_inq_varid, (int, const char *, int *))                                         \
    X(int, nc_inq_varndims, (int, int, int *))                                               \
    X(int, nc_inq_vartype, (int, int, nc_type *))                                            \
    X(int, nc_inq_attlen, (int, int, const char *, size_t *))                                \
    X(int, nc_get_att_text, (int, int, const char *, char *))                                \
    X(int, nc_get_var_double, (int, int, double *))                                          \
    X(int, nc_get_vara_double, (int, int, const size_t *, const size_t *, double *))         \
    X(int, nc_put_att_schar, (int, int, const char *, nc_type, size_t, const signed char *)) \
    X(int, nc_put_vara_schar, (int, int, const size_t *, const size_t *, const signed char *)) \
    X(int, nc_put_vara_float, (int, int, const size_t *, const size_t *, const float *))     \
    X(const char *, nc_strerror, (int))

#define DFLE_NETCDF_MEMBER(ret, name, params) ret(*name) params;
typedef struct dfle_netcdf_fns {
    DFLE_NETCDF_FNS(DFLE_NETCDF_MEMBER)
} dfle_netcdf_fns;
#undef DFLE_NETCDF_MEMBER

/* The table; written once by dfle_netcdf_load, read-only afterwards. */
extern dfle_netcdf_fns dfle_netcdf_fn;

/* Load libnetcdf if this process has not yet (thread-safe), then
 * DFLE_OK; DFLE_EEXTERNAL with "<who>: netCDF could not be loaded:
 * <why>; install ..." when it cannot be, at this call and every later
 * one. */
int dfle_netcdf_load(const char *who, dfle_error *err);

#ifndef DFLE_NETCDF_LIB_TABLE /* defined only where the table is filled */
#define nc_create (dfle_netcdf_fn.nc_create)
#define nc_close (dfle_netcdf_fn.nc_close)
#define nc_sync (dfle_netcdf_fn.nc_sync)
#define nc_enddef (dfle_netcdf_fn.nc_enddef)
#define nc_def_dim (dfle_netcdf_fn.nc_def_dim)
#define nc_def_var (dfle_netcdf_fn.nc_def_var)
#define nc_inq_dimlen (dfle_netcdf_fn.nc_inq_dimlen)
#define nc_inq_vardimid (dfle_netcdf_fn.nc_inq_vardimid)
#define nc_put_att_text (dfle_netcdf_fn.nc_put_att_text)
#define nc_put_att_double (dfle_netcdf_fn.nc_put_att_double)
#define nc_put_var_double (dfle_netcdf_fn.nc_put_var_double)
#define nc_put_var1_double (dfle_netcdf_fn.nc_put_var1_double)
#define nc_put_vara_double (dfle_netcdf_fn.nc_put_vara_double)
#define nc_put_var_text (dfle_netcdf_fn.nc_put_var_text)
#define nc_open (dfle_netcdf_fn.nc_open)
#define nc_redef (dfle_netcdf_fn.nc_redef)
#define nc_def_var_deflate (dfle_netcdf_fn.nc_def_var_deflate)
#define nc_def_var_chunking (dfle_netcdf_fn.nc_def_var_chunking)
#define nc_inq_dimid (dfle_netcdf_fn.nc_inq_dimid)
#define nc_inq_varid (dfle_netcdf_fn.nc_inq_varid)
#define nc_inq_varndims (dfle_netcdf_fn.nc_inq_varndims)
#define nc_inq_vartype (dfle_netcdf_fn.nc_inq_vartype)
#define nc_inq_attlen (dfle_netcdf_fn.nc_inq_attlen)
#define nc_get_att_text (dfle_netcdf_fn.nc_get_att_text)
#define nc_get_var_double (dfle_netcdf_fn.nc_get_var_double)
#define nc_get_vara_double (dfle_netcdf_fn.nc_get_vara_double)
#define nc_put_att_schar (dfle_netcdf_fn.nc_put_att_schar)
#define nc_put_vara_schar (dfle_netcdf_fn.nc_put_vara_schar)
#define nc_put_vara_float (dfle_netcdf_fn.nc_put_vara_float)
#define nc_strerror (dfle_netcdf_fn.nc_strerror)
#endif

#endif
