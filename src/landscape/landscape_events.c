/*
 * landscape_events.c - debris flows of a population as events on a
 * held landscape (landscape_events.h): the landscape's own debris-flow
 * model, on the network of its data cells, runs the events of
 * solver_events.c, and the sums go from nodes back to cells.
 */
#include <stdlib.h>

#include "dfle/landscape_events.h"
#include "landscape_internal.h"

int dfle_landscape_run_events(dfle_landscape *ls, const dfle_events_opts *o,
                              dfle_events_result *res, double *sum, double *sum2,
                              dfle_error *err)
{
    double *node_sum;
    int st;

    res->events = res->steps = 0;
    res->years = 0.0;
    if (ls->model == NULL || dfle_model_population(ls->model) == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "landscape events: the landscape's router must "
                              "be a population (dfle.router.population)");
    if (!o->hold)
        return dfle_error_set(err, DFLE_EINVAL, "landscape events: hold must be true (events "
                              "gather statistics on the surface as it is; transients with "
                              "events run on a channel, dfle.model)");
    if ((st = ls_route(ls, err)) != DFLE_OK || (st = ls_model_evaluate(ls, err)) != DFLE_OK)
        return st;
    node_sum = malloc(2 * ls->n_data * sizeof *node_sum);
    if (node_sum == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "landscape events: out of memory");
    st = dfle_run_events(ls->model, o, res, node_sum, node_sum + ls->n_data, err);
    if (st == DFLE_OK)
        for (size_t c = 0; c < ls->n; c++) {
            const int data = ls->node_of[c] != LS_NONE;
            const size_t k = data ? ls->node_of[c] : 0;
            if (sum != NULL)
                sum[c] = data ? node_sum[k] : NAN;
            if (sum2 != NULL)
                sum2[c] = data ? node_sum[ls->n_data + k] : NAN;
        }
    free(node_sum);
    return st;
}
