/*
 * gdal_lib.h - GDAL, loaded on first use (extlib.h); private to the
 * library.
 *
 * dfle calls GDAL to read, resample and crop DEMs (dem/), to write
 * GeoTIFFs (io/raster.c) and GeoPackages (io/vector.c, OGR), and for
 * CRS work: CF grid mappings and longitude/latitude (OSR).  The library does not link GDAL: dfle_gdal_load opens
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
#include <gdal_alg.h>
#include <gdal_utils.h>
#include <ogr_api.h>
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
    X(CPLErr, GDALSetRasterUnitType, (GDALRasterBandH, const char *))                        \
    X(CPLErr, GDALSetMetadataItem, (GDALMajorObjectH, const char *, const char *, const char *)) \
    X(GDALWarpAppOptions *, GDALWarpAppOptionsNew, (char **, GDALWarpAppOptionsForBinary *))  \
    X(void, GDALWarpAppOptionsFree, (GDALWarpAppOptions *))                                  \
    X(GDALDatasetH, GDALWarp,                                                                \
      (const char *, GDALDatasetH, int, GDALDatasetH *, const GDALWarpAppOptions *, int *))  \
    X(GDALTranslateOptions *, GDALTranslateOptionsNew,                                       \
      (char **, GDALTranslateOptionsForBinary *))                                            \
    X(void, GDALTranslateOptionsFree, (GDALTranslateOptions *))                              \
    X(GDALDatasetH, GDALTranslate,                                                           \
      (const char *, GDALDatasetH, const GDALTranslateOptions *, int *))                     \
    X(CPLErr, GDALPolygonize,                                                                \
      (GDALRasterBandH, GDALRasterBandH, OGRLayerH, int, char **, GDALProgressFunc, void *)) \
    X(OGRLayerH, GDALDatasetCreateLayer,                                                     \
      (GDALDatasetH, const char *, OGRSpatialReferenceH, OGRwkbGeometryType, CSLConstList))  \
    X(OGRErr, GDALDatasetStartTransaction, (GDALDatasetH, int))                              \
    X(OGRErr, GDALDatasetCommitTransaction, (GDALDatasetH))                                  \
    X(OGRFieldDefnH, OGR_Fld_Create, (const char *, OGRFieldType))                           \
    X(void, OGR_Fld_Destroy, (OGRFieldDefnH))                                                \
    X(OGRErr, OGR_L_CreateField, (OGRLayerH, OGRFieldDefnH, int))                            \
    X(OGRFeatureDefnH, OGR_L_GetLayerDefn, (OGRLayerH))                                      \
    X(OGRErr, OGR_L_CreateFeature, (OGRLayerH, OGRFeatureH))                                 \
    X(OGRErr, OGR_L_SetFeature, (OGRLayerH, OGRFeatureH))                                    \
    X(void, OGR_L_ResetReading, (OGRLayerH))                                                 \
    X(OGRFeatureH, OGR_L_GetNextFeature, (OGRLayerH))                                        \
    X(OGRFeatureH, OGR_F_Create, (OGRFeatureDefnH))                                          \
    X(void, OGR_F_Destroy, (OGRFeatureH))                                                    \
    X(void, OGR_F_SetFieldDouble, (OGRFeatureH, int, double))                                \
    X(void, OGR_F_SetFieldInteger64, (OGRFeatureH, int, GIntBig))                            \
    X(void, OGR_F_SetFieldString, (OGRFeatureH, int, const char *))                          \
    X(OGRErr, OGR_F_SetGeometryDirectly, (OGRFeatureH, OGRGeometryH))                        \
    X(OGRGeometryH, OGR_F_GetGeometryRef, (OGRFeatureH))                                     \
    X(OGRGeometryH, OGR_G_CreateGeometry, (OGRwkbGeometryType))                              \
    X(void, OGR_G_DestroyGeometry, (OGRGeometryH))                                           \
    X(void, OGR_G_AddPoint_2D, (OGRGeometryH, double, double))                               \
    X(double, OGR_G_Area, (OGRGeometryH))                                                    \
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
    X(const char *, OSRGetAttrValue, (OGRSpatialReferenceH, const char *, int))             \
    X(double, OSRGetProjParm, (OGRSpatialReferenceH, const char *, double, OGRErr *))         \
    X(double, OSRGetSemiMajor, (OGRSpatialReferenceH, OGRErr *))                              \
    X(double, OSRGetInvFlattening, (OGRSpatialReferenceH, OGRErr *))                          \
    X(double, OSRGetPrimeMeridian, (OGRSpatialReferenceH, char **))                           \
    X(OGRSpatialReferenceH, OSRCloneGeogCS, (OGRSpatialReferenceH))                           \
    X(int, OSRIsSame, (OGRSpatialReferenceH, OGRSpatialReferenceH))                           \
    X(void, OSRSetAxisMappingStrategy, (OGRSpatialReferenceH, OSRAxisMappingStrategy))        \
    X(OGRCoordinateTransformationH, OCTNewCoordinateTransformation,                          \
      (OGRSpatialReferenceH, OGRSpatialReferenceH))                                          \
    X(void, OCTDestroyCoordinateTransformation, (OGRCoordinateTransformationH))               \
    X(int, OCTTransform, (OGRCoordinateTransformationH, int, double *, double *, double *))   \
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
#define GDALSetRasterUnitType (dfle_gdal_fn.GDALSetRasterUnitType)
#define GDALSetMetadataItem (dfle_gdal_fn.GDALSetMetadataItem)
#define GDALWarpAppOptionsNew (dfle_gdal_fn.GDALWarpAppOptionsNew)
#define GDALWarpAppOptionsFree (dfle_gdal_fn.GDALWarpAppOptionsFree)
#define GDALWarp (dfle_gdal_fn.GDALWarp)
#define GDALTranslateOptionsNew (dfle_gdal_fn.GDALTranslateOptionsNew)
#define GDALTranslateOptionsFree (dfle_gdal_fn.GDALTranslateOptionsFree)
#define GDALTranslate (dfle_gdal_fn.GDALTranslate)
#define GDALPolygonize (dfle_gdal_fn.GDALPolygonize)
#define GDALDatasetCreateLayer (dfle_gdal_fn.GDALDatasetCreateLayer)
#define GDALDatasetStartTransaction (dfle_gdal_fn.GDALDatasetStartTransaction)
#define GDALDatasetCommitTransaction (dfle_gdal_fn.GDALDatasetCommitTransaction)
#define OGR_Fld_Create (dfle_gdal_fn.OGR_Fld_Create)
#define OGR_Fld_Destroy (dfle_gdal_fn.OGR_Fld_Destroy)
#define OGR_L_CreateField (dfle_gdal_fn.OGR_L_CreateField)
#define OGR_L_GetLayerDefn (dfle_gdal_fn.OGR_L_GetLayerDefn)
#define OGR_L_CreateFeature (dfle_gdal_fn.OGR_L_CreateFeature)
#define OGR_L_SetFeature (dfle_gdal_fn.OGR_L_SetFeature)
#define OGR_L_ResetReading (dfle_gdal_fn.OGR_L_ResetReading)
#define OGR_L_GetNextFeature (dfle_gdal_fn.OGR_L_GetNextFeature)
#define OGR_F_Create (dfle_gdal_fn.OGR_F_Create)
#define OGR_F_Destroy (dfle_gdal_fn.OGR_F_Destroy)
#define OGR_F_SetFieldDouble (dfle_gdal_fn.OGR_F_SetFieldDouble)
#define OGR_F_SetFieldInteger64 (dfle_gdal_fn.OGR_F_SetFieldInteger64)
#define OGR_F_SetFieldString (dfle_gdal_fn.OGR_F_SetFieldString)
#define OGR_F_SetGeometryDirectly (dfle_gdal_fn.OGR_F_SetGeometryDirectly)
#define OGR_F_GetGeometryRef (dfle_gdal_fn.OGR_F_GetGeometryRef)
#define OGR_G_CreateGeometry (dfle_gdal_fn.OGR_G_CreateGeometry)
#define OGR_G_DestroyGeometry (dfle_gdal_fn.OGR_G_DestroyGeometry)
#define OGR_G_AddPoint_2D (dfle_gdal_fn.OGR_G_AddPoint_2D)
#define OGR_G_Area (dfle_gdal_fn.OGR_G_Area)
#define OSRGetAttrValue (dfle_gdal_fn.OSRGetAttrValue)
#define OSRGetProjParm (dfle_gdal_fn.OSRGetProjParm)
#define OSRGetSemiMajor (dfle_gdal_fn.OSRGetSemiMajor)
#define OSRGetInvFlattening (dfle_gdal_fn.OSRGetInvFlattening)
#define OSRGetPrimeMeridian (dfle_gdal_fn.OSRGetPrimeMeridian)
#define OSRCloneGeogCS (dfle_gdal_fn.OSRCloneGeogCS)
#define OSRIsSame (dfle_gdal_fn.OSRIsSame)
#define OSRSetAxisMappingStrategy (dfle_gdal_fn.OSRSetAxisMappingStrategy)
#define OCTNewCoordinateTransformation (dfle_gdal_fn.OCTNewCoordinateTransformation)
#define OCTDestroyCoordinateTransformation (dfle_gdal_fn.OCTDestroyCoordinateTransformation)
#define OCTTransform (dfle_gdal_fn.OCTTransform)
#define VSIStatL (dfle_gdal_fn.VSIStatL)
#define VSIFree (dfle_gdal_fn.VSIFree) /* CPLFree is VSIFree */
#endif

#endif
