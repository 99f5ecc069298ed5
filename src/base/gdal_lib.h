/*
 * gdal_lib.h - GDAL, loaded on first use (extlib.h); private to the
 * library.
 *
 * dfle calls GDAL to read DEMs (dem/dem.c) and to write GeoTIFFs
 * (io/raster.c).  The library does not link GDAL: dfle_gdal_load opens
 * it on the first call that needs it, fills the table below and runs
 * GDALAllRegister, once per process.
 *
 * Include this header in place of GDAL's: after GDAL's declarations it
 * redefines every name in DFLE_GDAL_FNS to the table's pointer, so code
 * calling GDAL reads as plain GDAL.  Call dfle_gdal_load at each entry
 * point before the first GDAL call.  To call another GDAL function, add
 * it to DFLE_GDAL_FNS with the type GDAL's header gives it (gdal_lib.c
 * checks the two agree at compile time) and a #define below; a call to
 * a function missing from the table does not link, because nothing in
 * dfle links GDAL.
 */
#ifndef DFLE_BASE_GDAL_LIB_H
#define DFLE_BASE_GDAL_LIB_H

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_vsi.h>
#include <gdal.h>
#include <ogr_srs_api.h>

#include "dfle/error.h"

/* X(return type, name, parameter types), as GDAL declares each. */
#define DFLE_GDAL_FNS(X)                                                                     \
    X(void, GDALAllRegister, (void))                                                         \
    X(GDALDatasetH, GDALOpenEx,                                                              \
      (const char *, unsigned int, const char *const *, const char *const *,                 \
       const char *const *))                                                                 \
    X(GDALDatasetH, GDALCreate,                                                              \
      (GDALDriverH, const char *, int, int, int, GDALDataType, CSLConstList))                \
    X(void, GDALClose, (GDALDatasetH))                                                       \
    X(GDALDriverH, GDALGetDriverByName, (const char *))                                      \
    X(GDALDriverH, GDALGetDatasetDriver, (GDALDatasetH))                                     \
    X(const char *, GDALGetDriverShortName, (GDALDriverH))                                   \
    X(CPLErr, GDALGetGeoTransform, (GDALDatasetH, double *))                                 \
    X(CPLErr, GDALSetGeoTransform, (GDALDatasetH, double *))                                 \
    X(CPLErr, GDALSetProjection, (GDALDatasetH, const char *))                               \
    X(OGRSpatialReferenceH, GDALGetSpatialRef, (GDALDatasetH))                               \
    X(int, GDALGetRasterCount, (GDALDatasetH))                                               \
    X(int, GDALGetRasterXSize, (GDALDatasetH))                                               \
    X(int, GDALGetRasterYSize, (GDALDatasetH))                                               \
    X(GDALRasterBandH, GDALGetRasterBand, (GDALDatasetH, int))                               \
    X(CPLErr, GDALRasterIO,                                                                  \
      (GDALRasterBandH, GDALRWFlag, int, int, int, int, void *, int, int, GDALDataType, int, \
       int))                                                                                 \
    X(GDALDataType, GDALGetRasterDataType, (GDALRasterBandH))                                \
    X(const char *, GDALGetRasterUnitType, (GDALRasterBandH))                                \
    X(double, GDALGetRasterNoDataValue, (GDALRasterBandH, int *))                            \
    X(CPLErr, GDALSetRasterNoDataValue, (GDALRasterBandH, double))                           \
    X(double, GDALGetRasterScale, (GDALRasterBandH, int *))                                  \
    X(double, GDALGetRasterOffset, (GDALRasterBandH, int *))                                 \
    X(int, GDALGetMaskFlags, (GDALRasterBandH))                                              \
    X(GDALRasterBandH, GDALGetMaskBand, (GDALRasterBandH))                                   \
    X(void, GDALSetDescription, (GDALMajorObjectH, const char *))                            \
    X(OGRSpatialReferenceH, OSRNewSpatialReference, (const char *))                          \
    X(void, OSRDestroySpatialReference, (OGRSpatialReferenceH))                              \
    X(OGRErr, OSRSetFromUserInput, (OGRSpatialReferenceH, const char *))                     \
    X(OGRErr, OSRExportToWkt, (OGRSpatialReferenceH, char **))                               \
    X(const char *, OSRGetName, (OGRSpatialReferenceH))                                      \
    X(int, OSRIsGeographic, (OGRSpatialReferenceH))                                          \
    X(int, OSRIsProjected, (OGRSpatialReferenceH))                                           \
    X(double, OSRGetLinearUnits, (OGRSpatialReferenceH, char **))                            \
    X(const char *, OSRGetAuthorityName, (OGRSpatialReferenceH, const char *))               \
    X(const char *, OSRGetAuthorityCode, (OGRSpatialReferenceH, const char *))               \
    X(OGRSpatialReferenceH *, OSRFindMatches, (OGRSpatialReferenceH, char **, int *, int **)) \
    X(void, OSRFreeSRSArray, (OGRSpatialReferenceH *))                                       \
    X(void, CPLPushErrorHandler, (CPLErrorHandler))                                          \
    X(void, CPLPopErrorHandler, (void))                                                      \
    X(void, CPLQuietErrorHandler, (CPLErr, CPLErrorNum, const char *))                       \
    X(void, CPLErrorReset, (void))                                                           \
    X(const char *, CPLGetLastErrorMsg, (void))                                              \
    X(CPLErr, CPLGetLastErrorType, (void))                                                   \
    X(int, VSIStatL, (const char *, VSIStatBufL *))                                          \
    X(void, VSIFree, (void *))

#define DFLE_GDAL_MEMBER(ret, name, params) ret(*name) params;
typedef struct dfle_gdal_fns {
    DFLE_GDAL_FNS(DFLE_GDAL_MEMBER)
} dfle_gdal_fns;
#undef DFLE_GDAL_MEMBER

/* The table; written once by dfle_gdal_load, read-only afterwards. */
extern dfle_gdal_fns dfle_gdal_fn;

/* Load GDAL if this process has not yet (thread-safe), then DFLE_OK;
 * DFLE_EEXTERNAL with "<who>: GDAL could not be loaded: <why>; install
 * ..." when it cannot be, at this call and every later one. */
int dfle_gdal_load(const char *who, dfle_error *err);

#ifndef DFLE_GDAL_LIB_TABLE /* defined only where the table is filled */
#define GDALAllRegister (dfle_gdal_fn.GDALAllRegister)
#define GDALOpenEx (dfle_gdal_fn.GDALOpenEx)
#define GDALCreate (dfle_gdal_fn.GDALCreate)
#define GDALClose (dfle_gdal_fn.GDALClose)
#define GDALGetDriverByName (dfle_gdal_fn.GDALGetDriverByName)
#define GDALGetDatasetDriver (dfle_gdal_fn.GDALGetDatasetDriver)
#define GDALGetDriverShortName (dfle_gdal_fn.GDALGetDriverShortName)
#define GDALGetGeoTransform (dfle_gdal_fn.GDALGetGeoTransform)
#define GDALSetGeoTransform (dfle_gdal_fn.GDALSetGeoTransform)
#define GDALSetProjection (dfle_gdal_fn.GDALSetProjection)
#define GDALGetSpatialRef (dfle_gdal_fn.GDALGetSpatialRef)
#define GDALGetRasterCount (dfle_gdal_fn.GDALGetRasterCount)
#define GDALGetRasterXSize (dfle_gdal_fn.GDALGetRasterXSize)
#define GDALGetRasterYSize (dfle_gdal_fn.GDALGetRasterYSize)
#define GDALGetRasterBand (dfle_gdal_fn.GDALGetRasterBand)
#define GDALRasterIO (dfle_gdal_fn.GDALRasterIO)
#define GDALGetRasterDataType (dfle_gdal_fn.GDALGetRasterDataType)
#define GDALGetRasterUnitType (dfle_gdal_fn.GDALGetRasterUnitType)
#define GDALGetRasterNoDataValue (dfle_gdal_fn.GDALGetRasterNoDataValue)
#define GDALSetRasterNoDataValue (dfle_gdal_fn.GDALSetRasterNoDataValue)
#define GDALGetRasterScale (dfle_gdal_fn.GDALGetRasterScale)
#define GDALGetRasterOffset (dfle_gdal_fn.GDALGetRasterOffset)
#define GDALGetMaskFlags (dfle_gdal_fn.GDALGetMaskFlags)
#define GDALGetMaskBand (dfle_gdal_fn.GDALGetMaskBand)
#define GDALSetDescription (dfle_gdal_fn.GDALSetDescription)
#define OSRNewSpatialReference (dfle_gdal_fn.OSRNewSpatialReference)
#define OSRDestroySpatialReference (dfle_gdal_fn.OSRDestroySpatialReference)
#define OSRSetFromUserInput (dfle_gdal_fn.OSRSetFromUserInput)
#define OSRExportToWkt (dfle_gdal_fn.OSRExportToWkt)
#define OSRGetName (dfle_gdal_fn.OSRGetName)
#define OSRIsGeographic (dfle_gdal_fn.OSRIsGeographic)
#define OSRIsProjected (dfle_gdal_fn.OSRIsProjected)
#define OSRGetLinearUnits (dfle_gdal_fn.OSRGetLinearUnits)
#define OSRGetAuthorityName (dfle_gdal_fn.OSRGetAuthorityName)
#define OSRGetAuthorityCode (dfle_gdal_fn.OSRGetAuthorityCode)
#define OSRFindMatches (dfle_gdal_fn.OSRFindMatches)
#define OSRFreeSRSArray (dfle_gdal_fn.OSRFreeSRSArray)
#define CPLPushErrorHandler (dfle_gdal_fn.CPLPushErrorHandler)
#define CPLPopErrorHandler (dfle_gdal_fn.CPLPopErrorHandler)
#define CPLQuietErrorHandler (dfle_gdal_fn.CPLQuietErrorHandler)
#define CPLErrorReset (dfle_gdal_fn.CPLErrorReset)
#define CPLGetLastErrorMsg (dfle_gdal_fn.CPLGetLastErrorMsg)
#define CPLGetLastErrorType (dfle_gdal_fn.CPLGetLastErrorType)
#define VSIStatL (dfle_gdal_fn.VSIStatL)
#define VSIFree (dfle_gdal_fn.VSIFree) /* CPLFree is VSIFree */
#endif

#endif
