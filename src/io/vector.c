/*
 * vector.c - profiles, networks and catchments as GeoPackage layers
 * through OGR (vector.h).
 *
 * GDAL writes the GeoPackage (an SQLite file) at the temporary name of
 * dfle_file_begin_regular, one transaction a layer, and it is renamed
 * over the target once GDALClose has flushed it.  A catchment is the
 * network of every cell draining to the outlet (dfle_dem_network with
 * A_min one cell, snapped as everywhere in dfle), drawn as a mask and
 * traced by GDAL's polygonizer with 8-connected cells: a D8 catchment
 * is joined through corners, and 4-connected tracing would cut it into
 * pieces.
 */
#include "dfle/vector.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/gdal_lib.h" /* GDAL and OGR, loaded by the first write */
#include "dfle/file.h"
#include "dfle/raster.h"
#include "io/raster_internal.h"

void dfle_vector_opts_default(dfle_vector_opts *o)
{
    memset(o, 0, sizeof *o);
    o->outlet[0] = o->outlet[1] = NAN;
    o->radius = -1.0;
}

typedef struct writer {
    const char *path;
    GDALDatasetH ds;
    OGRSpatialReferenceH srs;
    dfle_error *err;
} writer;

static const char *gdal_message(const char *fallback)
{
    const char *m = CPLGetLastErrorMsg();
    return m != NULL && m[0] != '\0' ? m : fallback;
}

static int fail(writer *w, const char *what)
{
    return dfle_error_set(w->err, DFLE_EIO, "vector: cannot write '%s' (%s): %s", w->path, what,
                          gdal_message("GDAL failed"));
}

/* A layer with fields of the given names and types. */
static OGRLayerH new_layer(writer *w, const char *name, OGRwkbGeometryType type,
                           const char *const *fields, const OGRFieldType *types, size_t n)
{
    char *opts[] = {"SPATIAL_INDEX=YES", NULL};
    OGRLayerH layer = GDALDatasetCreateLayer(w->ds, name, w->srs, type, opts);
    for (size_t k = 0; layer != NULL && k < n; k++) {
        OGRFieldDefnH f = OGR_Fld_Create(fields[k], types[k]);
        if (f == NULL || OGR_L_CreateField(layer, f, 1) != OGRERR_NONE)
            layer = NULL;
        if (f != NULL)
            OGR_Fld_Destroy(f);
    }
    return layer;
}

/* The cell fields in "channels" and "cells": cell, receiver, then the
 * profile's fields. */
static const char *const cell_fields[] = {"cell", "receiver", "x", "d", "z", "A", "S", "E", "N"};
static const enum dfle_profile_field cell_values[] = {
    DFLE_PROFILE_X, DFLE_PROFILE_D, DFLE_PROFILE_Z, DFLE_PROFILE_A, DFLE_PROFILE_S,
    DFLE_PROFILE_E, DFLE_PROFILE_N};
enum { N_CELL_FIELDS = sizeof cell_fields / sizeof cell_fields[0] };

static int write_cells(writer *w, const dfle_profile *p, int lines)
{
    const OGRFieldType types[N_CELL_FIELDS] = {OFTInteger64, OFTInteger64, OFTReal, OFTReal,
                                               OFTReal, OFTReal, OFTReal, OFTReal, OFTReal};
    const size_t n = dfle_profile_size(p), *rcv = dfle_profile_receiver(p);
    const double *E = dfle_profile_field(p, DFLE_PROFILE_E), *N = dfle_profile_field(p, DFLE_PROFILE_N);
    OGRLayerH layer = new_layer(w, lines ? "channels" : "cells",
                                lines ? wkbLineString : wkbPoint, cell_fields, types,
                                N_CELL_FIELDS);
    if (layer == NULL)
        return fail(w, lines ? "the channels layer" : "the cells layer");
    if (GDALDatasetStartTransaction(w->ds, 0) != OGRERR_NONE)
        return fail(w, "a transaction");
    for (size_t i = 0; i < n; i++) {
        OGRFeatureH f;
        OGRGeometryH g;
        if (lines && rcv[i] == 0)
            continue; /* the outlet: the end of its donors' lines */
        f = OGR_F_Create(OGR_L_GetLayerDefn(layer));
        g = OGR_G_CreateGeometry(lines ? wkbLineString : wkbPoint);
        if (f == NULL || g == NULL) {
            if (f != NULL)
                OGR_F_Destroy(f);
            if (g != NULL)
                OGR_G_DestroyGeometry(g);
            return dfle_error_set(w->err, DFLE_ENOMEM, "vector: out of memory");
        }
        OGR_F_SetFieldInteger64(f, 0, (GIntBig)(i + 1));
        OGR_F_SetFieldInteger64(f, 1, (GIntBig)rcv[i]);
        for (size_t k = 0; k < sizeof cell_values / sizeof cell_values[0]; k++)
            OGR_F_SetFieldDouble(f, (int)k + 2, dfle_profile_field(p, cell_values[k])[i]);
        OGR_G_AddPoint_2D(g, E[i], N[i]);
        if (lines)
            OGR_G_AddPoint_2D(g, E[rcv[i] - 1], N[rcv[i] - 1]);
        OGR_F_SetGeometryDirectly(f, g);
        if (OGR_L_CreateFeature(layer, f) != OGRERR_NONE) {
            OGR_F_Destroy(f);
            return fail(w, "a feature");
        }
        OGR_F_Destroy(f);
    }
    if (GDALDatasetCommitTransaction(w->ds) != OGRERR_NONE)
        return fail(w, "a transaction");
    return DFLE_OK;
}

/* The catchment above the outlet as a mask, polygonized. */
static int write_catchment(writer *w, dfle_dem *dem, const dfle_vector_opts *o)
{
    static const char *const fields[] = {"value", "area", "cells", "outlet_E", "outlet_N",
                                         "given_E", "given_N"};
    const OGRFieldType types[] = {OFTInteger, OFTReal, OFTInteger64, OFTReal, OFTReal, OFTReal,
                                  OFTReal};
    const size_t nx = dfle_dem_nx(dem), ny = dfle_dem_ny(dem);
    dfle_network_opts no;
    dfle_profile *net = NULL;
    unsigned char *mask = NULL;
    GDALDriverH mem = GDALGetDriverByName("MEM");
    GDALDatasetH mds = NULL;
    OGRLayerH layer;
    OGRFeatureH f;
    double given[2], snapped[2], e[4];
    int st = DFLE_OK;
    char *popts[] = {"8CONNECTED=8", NULL};

    dfle_network_opts_default(&no);
    no.A_min = dfle_dem_dx(dem) * dfle_dem_dy(dem);
    no.has_outlet = 1;
    no.E = o->outlet[0], no.N = o->outlet[1];
    no.radius = o->radius;
    if ((st = dfle_dem_network(dem, &no, &net, w->err)) != DFLE_OK)
        return st;
    if ((mask = calloc(nx * ny, 1)) == NULL) {
        st = dfle_error_set(w->err, DFLE_ENOMEM, "vector: out of memory");
        goto done;
    }
    for (size_t i = 0; i < dfle_profile_size(net); i++) {
        size_t c;
        if (dfle_dem_cell_at(dem, dfle_profile_field(net, DFLE_PROFILE_E)[i],
                             dfle_profile_field(net, DFLE_PROFILE_N)[i], "cell", &c,
                             w->err) == DFLE_OK)
            mask[c] = 1;
    }
    dfle_dem_extent(dem, e);
    if (mem == NULL || (mds = GDALCreate(mem, "", (int)nx, (int)ny, 1, GDT_Byte, NULL)) == NULL) {
        st = fail(w, "the catchment's mask");
        goto done;
    }
    {
        double gt[6] = {e[0], dfle_dem_dx(dem), 0.0, e[3], 0.0, -dfle_dem_dy(dem)};
        GDALSetGeoTransform(mds, gt);
    }
    if (GDALRasterIO(GDALGetRasterBand(mds, 1), GF_Write, 0, 0, (int)nx, (int)ny, mask, (int)nx,
                     (int)ny, GDT_Byte, 0, 0) != CE_None) {
        st = fail(w, "the catchment's mask");
        goto done;
    }
    if ((layer = new_layer(w, "catchment", wkbPolygon, fields, types, 7)) == NULL) {
        st = fail(w, "the catchment layer");
        goto done;
    }
    if (GDALDatasetStartTransaction(w->ds, 0) != OGRERR_NONE ||
        GDALPolygonize(GDALGetRasterBand(mds, 1), GDALGetRasterBand(mds, 1), layer, 0, popts,
                       NULL, NULL) != CE_None) {
        st = fail(w, "the catchment polygon");
        goto done;
    }
    dfle_profile_point(net, given, snapped);
    OGR_L_ResetReading(layer);
    while ((f = OGR_L_GetNextFeature(layer)) != NULL) {
        /* One polygon; its own area, and what it stands for. */
        OGR_F_SetFieldDouble(f, 1, OGR_G_Area(OGR_F_GetGeometryRef(f)));
        OGR_F_SetFieldInteger64(f, 2, (GIntBig)dfle_profile_size(net));
        OGR_F_SetFieldDouble(f, 3, snapped[0]);
        OGR_F_SetFieldDouble(f, 4, snapped[1]);
        OGR_F_SetFieldDouble(f, 5, given[0]);
        OGR_F_SetFieldDouble(f, 6, given[1]);
        if (OGR_L_SetFeature(layer, f) != OGRERR_NONE)
            st = fail(w, "the catchment polygon");
        OGR_F_Destroy(f);
    }
    if (GDALDatasetCommitTransaction(w->ds) != OGRERR_NONE && st == DFLE_OK)
        st = fail(w, "a transaction");
done:
    if (mds != NULL)
        GDALClose(mds);
    free(mask);
    dfle_profile_free(net);
    return st;
}

int dfle_vector_write_gpkg(const char *path, const dfle_vector_opts *o, dfle_error *err)
{
    static const char *const gpkg[] = {".gpkg", NULL};
    const char *write_to, *wkt = NULL;
    writer w = {path, NULL, NULL, err};
    GDALDriverH drv;
    dfle_file f;
    int st;

    if (o->channels == NULL && o->catchment_of == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "vector: nothing to write to '%s'", path);
    if (!dfle_raster_has_extension(path, gpkg))
        return dfle_error_set(err, DFLE_EINVAL, "vector: '%s' is not the name of a GeoPackage: "
                              "the file is a GeoPackage, so its name must end in .gpkg", path);
    if (o->catchment_of != NULL && !(isfinite(o->outlet[0]) && isfinite(o->outlet[1])))
        return dfle_error_set(err, DFLE_EINVAL, "vector: a catchment needs its outlet (E, N)");
    if ((st = dfle_gdal_load("vector", err)) != DFLE_OK)
        return st;
    if ((drv = GDALGetDriverByName("GPKG")) == NULL)
        return dfle_error_set(err, DFLE_EIO, "vector: GDAL has no GPKG driver");
    if ((st = dfle_file_begin_regular(&f, path, "vector", &write_to, err)) != DFLE_OK)
        return st;
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
    /* The temporary file exists (empty): the driver makes a new one. */
    remove(write_to);
    wkt = o->channels != NULL ? dfle_profile_crs_wkt(o->channels)
                              : dfle_dem_crs_wkt(o->catchment_of);
    if (wkt != NULL) {
        w.srs = OSRNewSpatialReference(NULL);
        if (w.srs != NULL && OSRSetFromUserInput(w.srs, wkt) != OGRERR_NONE) {
            OSRDestroySpatialReference(w.srs);
            w.srs = NULL;
        }
    }
    if ((w.ds = GDALCreate(drv, write_to, 0, 0, 0, GDT_Unknown, NULL)) == NULL) {
        st = fail(&w, "create");
    } else {
        raster_put_record(w.ds, o->provenance);
        if (o->channels != NULL && (st = write_cells(&w, o->channels, 1)) == DFLE_OK)
            st = write_cells(&w, o->channels, 0);
        if (st == DFLE_OK && o->catchment_of != NULL)
            st = write_catchment(&w, o->catchment_of, o);
        GDALClose(w.ds);
        if (st == DFLE_OK && CPLGetLastErrorType() >= CE_Failure)
            st = fail(&w, "close");
    }
    if (w.srs != NULL)
        OSRDestroySpatialReference(w.srs);
    CPLPopErrorHandler();
    if (st != DFLE_OK) {
        dfle_file_abort(&f);
        return st;
    }
    return dfle_file_commit(&f, err);
}
