/*
 * dem_flow.c - filling and routing a DEM: the DEM's side of
 * src/drainage/, which does the work (doc/dem.md has the algorithms).
 *
 * What is the DEM's own: the rule that water may leave wherever the
 * data end (every edge OPEN, NoData OPEN), pits kept as sinks on an
 * unfilled DEM, the metric check before anything measures distance or
 * area, the cache (routing is redone only after a fill changed z), and
 * the topological order listed each cell before its receiver, which is
 * the drainage stack read backwards.
 */
#include "dem/dem_internal.h"

#include <stdlib.h>

/* The codes of dem.h are the drainage codes, and must stay so. */
_Static_assert((int)DFLE_DEM_DIR_OUT == (int)DFLE_DRAINAGE_DIR_OUT &&
                   (int)DFLE_DEM_DIR_SINK == (int)DFLE_DRAINAGE_DIR_SINK &&
                   (int)DFLE_DEM_DIR_NODATA == (int)DFLE_DRAINAGE_DIR_NODATA,
               "dem.h and drainage.h direction codes differ");

/* The routing object, made on first need: every edge and NoData open,
 * pits kept (fill first to route across them), Kahn's order. */
static int dem_drainage(dfle_dem *d, dfle_error *err)
{
    dfle_drainage_opts o;
    if (d->flow != NULL)
        return DFLE_OK;
    dfle_drainage_opts_default(&o);
    o.nx = d->nx;
    o.ny = d->ny;
    o.dx = d->dx;
    o.dy = d->dy;
    o.order = DFLE_DRAINAGE_KAHN;
    return dfle_drainage_new(&o, &d->flow, err);
}

int dfle_dem_fill(dfle_dem *d, dfle_dem_fill_stats *stats, dfle_error *err)
{
    dfle_drainage_fill_stats fs;
    int st;
    if ((st = dem_drainage(d, err)) != DFLE_OK ||
        (st = dfle_drainage_fill(d->flow, d->z, &fs, err)) != DFLE_OK)
        return st;
    d->filled = 1;
    if (fs.raised > 0)
        d->routed = 0; /* directions and areas were for the old z */
    if (stats != NULL) {
        stats->raised = fs.raised;
        stats->max_raise = fs.max_raise;
        stats->volume = fs.volume;
    }
    return DFLE_OK;
}

int dfle_dem_is_filled(const dfle_dem *d) { return d->filled; }

int dfle_dem_route(dfle_dem *d, dfle_error *err)
{
    const uint32_t *stack;
    size_t n_stack;
    int st;

    if (d->routed)
        return DFLE_OK;
    if ((st = dfle_dem_check_metric(d, "flow routing (D8, drainage area)", err)) != DFLE_OK ||
        (st = dem_drainage(d, err)) != DFLE_OK ||
        (st = dfle_drainage_route(d->flow, d->z, err)) != DFLE_OK)
        return st;
    stack = dfle_drainage_stack(d->flow, &n_stack);
    if (d->order == NULL && (d->order = malloc((d->n - d->n_nodata) * sizeof *d->order)) == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "dem: out of memory routing %zu cells", d->n);
    for (size_t j = 0; j < n_stack; j++)
        d->order[j] = stack[n_stack - 1 - j];
    /* A DEM routes once per fill: its workspace is not worth keeping. */
    dfle_drainage_trim(d->flow);
    d->routed = 1;
    return DFLE_OK;
}

int dfle_dem_is_routed(const dfle_dem *d) { return d->routed; }

const unsigned char *dfle_dem_dir(const dfle_dem *d)
{
    return d->routed ? dfle_drainage_dir(d->flow) : NULL;
}

const double *dfle_dem_area(const dfle_dem *d)
{
    return d->routed ? dfle_drainage_area(d->flow) : NULL;
}

const uint32_t *dfle_dem_order(const dfle_dem *d, size_t *n_order)
{
    if (n_order != NULL)
        *n_order = d->routed ? d->n - d->n_nodata : 0;
    return d->routed ? d->order : NULL;
}

long long dfle_dem_receiver(const dfle_dem *d, size_t i)
{
    const uint32_t *rcv;
    if (!d->routed || i >= d->n)
        return -1;
    rcv = dfle_drainage_receivers(d->flow);
    return rcv[i] == i ? -1 : (long long)rcv[i];
}

size_t dfle_dem_sink_count(const dfle_dem *d)
{
    return d->routed ? dfle_drainage_get_counts(d->flow).sinks : 0;
}

size_t dfle_dem_flat_count(const dfle_dem *d)
{
    return d->routed ? dfle_drainage_get_counts(d->flow).flats : 0;
}
