/*
 * landscape_events.h - debris flows of a population as events on a
 * landscape (model_events.h for one channel).
 *
 * A landscape's debris-flow model (landscape.h) erodes every channel
 * cell at the population's expected rate.  Here the same population is
 * read as events: in each step of dt years Poisson(lambda dt) events,
 * each a volume factor drawn from the population's distribution and
 * released at every channel head at once (the volume of each head
 * scaling with its area, as for one flow; the combine rule joins them),
 * routed over the surface as it is.  The surface is held: a run gives
 * the statistics of the events' erosion, whose long-run mean is the
 * expected rate.  One seeded generator (MT19937) drawn in the order of
 * time: a run is a function of its seed alone.
 */
#ifndef DFLE_LANDSCAPE_EVENTS_H
#define DFLE_LANDSCAPE_EVENTS_H

#include "dfle/landscape.h"
#include "dfle/model_events.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Events on the landscape's current surface (o->hold must be 1: the
 * surface does not change).  sum and sum2 (nx * ny values each, may be
 * NULL) receive per cell the sum of the events' erosion depths [m] and
 * of their squares [m^2] (NaN on NoData, 0 where no flow goes): sum /
 * years is the mean rate, sqrt(sum2) / years its standard error.
 * DFLE_EINVAL without a population router or with hold = 0. */
int dfle_landscape_run_events(dfle_landscape *ls, const dfle_events_opts *o,
                              dfle_events_result *res, double *sum, double *sum2,
                              dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
