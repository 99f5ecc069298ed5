/*
 * solver_explicit.c - forward Euler with a CFL-limited step, the paper's
 * method and the reference the other methods are checked against.
 *
 * Why the step has this form: erosion at a node depends on its slope to
 * the receiver, so a slope perturbation travels upstream like a
 * kinematic wave with speed c = |dE/dS| [m/yr] (dfle_model_celerity).
 * Forward Euler with that upwind difference is stable while
 * c dt / L <= 1 at every node, so
 *   dt = min over nodes of cfl L_i / c_i,
 * capped at dt_max and at the time left to the next stop.
 */
#include <math.h>

#include "solvers/solver_internal.h"

/* The CFL step over the nodes' wave speeds c: the smallest
 * cfl L_i / c_i, found as the largest c_i / L_i (a product with 1 / L,
 * where one division at the end gives exactly the old single-dx value
 * for a channel).  NaN and Inf are caught by one sum, then named. */
static int cfl_step(dfle_model *m, const double *c, double *dt, dfle_error *err)
{
    const size_t n = dfle_model_size(m);
    const double *L = dfle_model_flow_length(m), cfl = dfle_model_cfl(m);
    double sum = 0.0, best = 0.0;
    size_t at = n;

    if (dfle_model_uniform_flow_length(m)) {
        for (size_t i = 0; i < n; i++) {
            sum += c[i];
            if (c[i] > best)
                best = c[i], at = i;
        }
    } else {
        for (size_t i = 0; i < n; i++) {
            sum += c[i];
            if (c[i] / L[i] > best)
                best = c[i] / L[i], at = i;
        }
    }
    if (!isfinite(sum)) {
        for (size_t i = 0; i < n; i++)
            if (!isfinite(c[i]))
                return dfle_error_set(err, DFLE_ENUMERIC,
                                      "model: erosion rate has no finite slope derivative at "
                                      "node %zu at t = %g yr", i + 1, dfle_model_time(m));
    }
    *dt = dfle_model_dt_max(m);
    if (at < n && cfl * L[at] / c[at] < *dt)
        *dt = cfl * L[at] / c[at];
    return DFLE_OK;
}

int dfle_explicit_step(dfle_model *m, double *dt, dfle_error *err)
{
    const double *c;
    int st;
    if ((st = dfle_model_celerity(m, &c, err)) != DFLE_OK)
        return st;
    return cfl_step(m, c, dt, err);
}

int dfle_explicit_advance(dfle_model *m, double dt_limit, double *dt_taken, void *state,
                          dfle_error *err)
{
    const size_t n = dfle_model_size(m);
    const double *dzdt;
    double dt = 0.0, *z;
    int st;
    (void)state;

    if ((st = dfle_explicit_step(m, &dt, err)) != DFLE_OK)
        return st;
    if (dt > dt_limit)
        dt = dt_limit;
    if ((dzdt = dfle_model_field(m, DFLE_FIELD_DZDT, err)) == NULL)
        return err != NULL ? err->code : DFLE_ESTATE;
    /* dz/dt is 0 on base nodes: they stay where they are. */
    z = dfle_model_z(m);
    for (size_t i = 0; i < n; i++)
        z[i] += dt * dzdt[i];
    dfle_model_touch(m);
    *dt_taken = dt;
    return DFLE_OK;
}

static int explicit_run(dfle_model *m, const dfle_run_opts *o, dfle_run_result *res,
                        dfle_error *err)
{
    res->method = DFLE_METHOD_EXPLICIT;
    return dfle_stepping_run(m, o, dfle_explicit_advance, NULL, res, err);
}

const dfle_solver_ops dfle_solver_explicit = {
    .version = DFLE_SOLVER_OPS_VERSION,
    .name = "explicit",
    .run = explicit_run,
};
