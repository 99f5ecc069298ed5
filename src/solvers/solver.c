/*
 * solver.c - the dispatcher: check a run's options, pick the method and
 * fall back when the direct method finds no consistent steady state.
 *
 * The methods are solver ops tables (solver.h), one file each; this is
 * the only place that knows more than one of them.
 */
#include "dfle/solver.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "solvers/solver_internal.h"

void dfle_run_opts_default(dfle_run_opts *o)
{
    memset(o, 0, sizeof *o);
    o->max_time = 2e7;
    o->tol = 1e-3;
    o->max_steps = 10000000u;
    o->method = DFLE_METHOD_EXPLICIT;
    o->rtol = 1e-3;
    o->direct_tol = 2e-3;
}

const char *dfle_stop_reason_name(int reason)
{
    switch (reason) {
    case DFLE_STOP_STEADY: return "steady";
    case DFLE_STOP_TIME: return "time";
    case DFLE_STOP_STEPS: return "steps";
    case DFLE_STOP_INTERRUPTED: return "interrupted";
    default: return "unknown";
    }
}

static const dfle_solver_ops *const methods[] = {
    [DFLE_METHOD_EXPLICIT] = &dfle_solver_explicit,
    [DFLE_METHOD_IMPLICIT] = &dfle_solver_implicit,
    [DFLE_METHOD_DIRECT] = &dfle_solver_direct,
};

const char *dfle_method_name(int method)
{
    if (method == DFLE_METHOD_AUTO)
        return "auto";
    return method >= 0 && method < DFLE_METHOD_AUTO ? methods[method]->name : "unknown";
}

int dfle_method_lookup(const char *name)
{
    for (int k = 0; k <= DFLE_METHOD_AUTO; k++)
        if (strcmp(name, dfle_method_name(k)) == 0)
            return k;
    return -1;
}

int dfle_run_opts_check(const dfle_run_opts *o, int steady, dfle_error *err)
{
    if (!(isfinite(o->max_time) && o->max_time > 0))
        return dfle_error_set(err, DFLE_EINVAL, "max_time must be > 0 yr (got %g)", o->max_time);
    if (steady && !(isfinite(o->tol) && o->tol > 0))
        return dfle_error_set(err, DFLE_EINVAL, "tol must be > 0 (got %g)", o->tol);
    if (!(isfinite(o->tol) && o->tol >= 0))
        return dfle_error_set(err, DFLE_EINVAL, "tol must be >= 0 (got %g)", o->tol);
    if (o->max_steps == 0)
        return dfle_error_set(err, DFLE_EINVAL, "max_steps must be > 0");
    if (!(isfinite(o->rtol) && o->rtol > 0 && o->rtol < 1))
        return dfle_error_set(err, DFLE_EINVAL, "rtol must be in (0, 1) (got %g)", o->rtol);
    if (!(isfinite(o->direct_tol) && o->direct_tol > 0 && o->direct_tol < 1))
        return dfle_error_set(err, DFLE_EINVAL, "direct_tol must be in (0, 1) (got %g)",
                              o->direct_tol);
    if (o->n_record > 0 && (o->record_times == NULL || o->record_z == NULL))
        return dfle_error_set(err, DFLE_EINVAL, "record times need a place to record");
    for (size_t k = 0; k < o->n_record; k++)
        if (!(isfinite(o->record_times[k]) && o->record_times[k] >= 0 &&
              o->record_times[k] <= o->max_time &&
              (k == 0 || o->record_times[k] > o->record_times[k - 1])))
            return dfle_error_set(err, DFLE_EINVAL,
                                  "record times must increase within the run, [0, %g yr] (time "
                                  "%zu is %g)", o->max_time, k + 1, o->record_times[k]);
    if (o->method < 0 || o->method > DFLE_METHOD_AUTO)
        return dfle_error_set(err, DFLE_EINVAL, "unknown method %d", o->method);
    if (o->method == DFLE_METHOD_DIRECT && !(o->tol > 0))
        return dfle_error_set(err, DFLE_EINVAL, "method 'direct' finds steady states only (tol > "
                              "0): use 'explicit' or 'implicit' for a transient");
    if (o->method == DFLE_METHOD_DIRECT && o->n_record > 0)
        return dfle_error_set(err, DFLE_EINVAL, "the direct method has no time to record at");
    return DFLE_OK;
}

/* The checks, as the model's message ("model: ..."). */
static int check_opts(const dfle_run_opts *o, dfle_error *err)
{
    int st = dfle_run_opts_check(o, 0, err);
    if (st != DFLE_OK && err != NULL) {
        char msg[DFLE_ERROR_MSG_MAX];
        memcpy(msg, err->msg, sizeof msg);
        msg[sizeof msg - 1] = '\0';
        dfle_error_set(err, st, "model: %s", msg);
    }
    return st;
}

/* A model message without its "model: " prefix, to quote inside another. */
static const char *unprefixed(const char *msg)
{
    return strncmp(msg, "model: ", 7) == 0 ? msg + 7 : msg;
}

int dfle_solver_run(dfle_model *m, const dfle_run_opts *o, dfle_run_result *res,
                    dfle_error *err)
{
    dfle_run_opts opts = *o;
    char direct_why[DFLE_ERROR_MSG_MAX] = "";
    int st;

    memset(res, 0, sizeof *res);
    if ((st = check_opts(o, err)) != DFLE_OK)
        return st;
    if (opts.method == DFLE_METHOD_AUTO)
        opts.method = o->tol > 0 ? DFLE_METHOD_DIRECT : DFLE_METHOD_EXPLICIT;
    res->method = opts.method;
    if (o->interrupt != NULL && *o->interrupt) {
        /* Interrupted before it began: nothing to do, nothing changed. */
        res->reason = DFLE_STOP_INTERRUPTED;
        if (dfle_model_is_evaluated(m) || (st = dfle_model_evaluate(m, err)) == DFLE_OK)
            res->rate_ratio = dfle_model_rate_ratio(m);
        return st == DFLE_OK ? DFLE_OK : st;
    }
    if (opts.method != DFLE_METHOD_DIRECT)
        return methods[opts.method]->run(m, &opts, res, err);

    /* With U(t): the steady state for U at the current time. */
    if ((st = dfle_stepping_uplift(m, &opts, err)) != DFLE_OK)
        return st;
    st = dfle_solver_direct.run(m, &opts, res, err);
    if (st != DFLE_EFIT)
        return st;
    /* No consistent solution: step from where the direct method left the
     * state, and say why. */
    res->fallback = 1;
    snprintf(res->note, sizeof res->note, "direct: %.110s; continued by implicit stepping",
             err != NULL ? unprefixed(err->msg) : "no consistent solution");
    if (err != NULL)
        snprintf(direct_why, sizeof direct_why, "%s", unprefixed(err->msg));
    dfle_error_clear(err);
    st = dfle_solver_implicit.run(m, &opts, res, err);
    if (st != DFLE_OK && err != NULL) {
        /* Say both: why direct gave up, and why stepping failed too. */
        char why[DFLE_ERROR_MSG_MAX];
        snprintf(why, sizeof why, "%s", unprefixed(err->msg));
        dfle_error_set(err, st, "model: no steady state by the direct method (%.230s); "
                                "implicit stepping then failed: %.250s", direct_why, why);
    }
    return st;
}
