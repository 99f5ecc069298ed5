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

int dfle_explicit_advance(dfle_model *m, double dt_limit, double *dt_taken, void *state,
                          dfle_error *err)
{
    const size_t n = dfle_model_size(m);
    const double *L = dfle_model_flow_length(m), cfl = dfle_model_cfl(m);
    const double *c, *dzdt = NULL;
    double dt = dfle_model_dt_max(m), *z;
    int st;
    (void)state;

    if ((st = dfle_model_celerity(m, &c, err)) != DFLE_OK)
        return st;
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(c[i]))
            return dfle_error_set(err, DFLE_ENUMERIC,
                                  "model: erosion rate has no finite slope derivative at node "
                                  "%zu at t = %g yr", i + 1, dfle_model_time(m));
        /* (cfl L) / c, smallest where c is largest */
        if (c[i] > 0 && cfl * L[i] / c[i] < dt)
            dt = cfl * L[i] / c[i];
    }
    if (dt > dt_limit)
        dt = dt_limit;
    if ((dzdt = dfle_model_field(m, DFLE_FIELD_DZDT, err)) == NULL)
        return err != NULL ? err->code : DFLE_ESTATE;
    z = dfle_model_z(m);
    for (size_t i = 0; i < n; i++)
        if (!dfle_model_is_base(m, i))
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
    .name = "explicit",
    .run = explicit_run,
};
