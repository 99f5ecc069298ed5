/*
 * law.c - the generic erosion-law handle: an ops table plus its state.
 *
 * Built-in laws and laws written in Lua both arrive here as a
 * dfle_law_ops table; the model calls nothing else, so it cannot tell
 * them apart (law.h explains the flow_factor / rate split).
 */
#include "dfle/law.h"

#include <stdlib.h>

struct dfle_law {
    const dfle_law_ops *ops;
    void *state;
};

int dfle_law_new(const dfle_law_ops *ops, void *state, dfle_law **out,
                 dfle_error *err)
{
    dfle_law *law;

    *out = NULL;
    if (ops != NULL && (ops->version < 1 || ops->version > DFLE_LAW_OPS_VERSION)) {
        if (ops->destroy != NULL) /* later versions only append: it is where we look */
            ops->destroy(state);
        return dfle_error_set(err, DFLE_EINVAL,
                              "law %s: ops version %d, this library knows 1 to %d (set "
                              ".version = DFLE_LAW_OPS_VERSION)",
                              ops->name != NULL ? ops->name : "?", ops->version,
                              DFLE_LAW_OPS_VERSION);
    }
    if (ops == NULL || ops->flow_factor == NULL || ops->rate == NULL) {
        if (ops != NULL && ops->destroy != NULL)
            ops->destroy(state);
        return dfle_error_set(err, DFLE_EINVAL,
                              "law: ops table needs flow_factor() and rate()");
    }
    law = malloc(sizeof *law);
    if (law == NULL) {
        if (ops->destroy != NULL)
            ops->destroy(state);
        return dfle_error_set(err, DFLE_ENOMEM, "law: out of memory");
    }
    law->ops = ops;
    law->state = state;
    *out = law;
    return DFLE_OK;
}

void dfle_law_free(dfle_law *law)
{
    if (law == NULL)
        return;
    if (law->ops->destroy != NULL)
        law->ops->destroy(law->state);
    free(law);
}

int dfle_law_flow_factor(dfle_law *law, const dfle_law_ctx *ctx, double *F,
                         dfle_error *err)
{
    return law->ops->flow_factor(law->state, ctx, F, err);
}

int dfle_law_rate(dfle_law *law, const dfle_law_ctx *ctx, const double *F,
                  double *E, dfle_error *err)
{
    return law->ops->rate(law->state, ctx, F, E, err);
}

int dfle_law_rate_dlnS(dfle_law *law, const dfle_law_ctx *ctx, const double *F,
                       const double *E, const dfle_flow_dlnS *d, double *dE, dfle_error *err)
{
    if (law->ops->rate_dlnS == NULL)
        return dfle_error_set(err, DFLE_ESTATE,
                              "law.%s cannot say how its rate answers the slope", law->ops->name);
    return law->ops->rate_dlnS(law->state, ctx, F, E, d, dE, err);
}

int dfle_law_has_rate_dlnS(const dfle_law *law) { return law->ops->rate_dlnS != NULL; }

size_t dfle_law_params(const dfle_law *law, dfle_param *out, size_t cap)
{
    if (law->ops->params == NULL)
        return (size_t)-1;
    return law->ops->params(law->state, out, cap);
}

const char *dfle_law_name(const dfle_law *law) { return law->ops->name; }
const dfle_law_ops *dfle_law_get_ops(const dfle_law *law) { return law->ops; }
void *dfle_law_state(const dfle_law *law) { return law->state; }
