/*
 * lua_invert_internal.h - what the files of dfle.invert share (not
 * installed):
 *
 *   lua_invert.c         the entry point: spec, chain, point estimate,
 *                        sampling, result
 *   lua_invert_spec.c    the table checked into a problem (priors, data,
 *                        channel), the driver's options and the
 *                        identity of the problem
 *   lua_invert_data.c    the data binned into areas and log slopes
 *   lua_invert_lsq.c     the least-squares point estimate
 *   lua_invert_eval.c    one evaluation in one Lua state: the forward
 *                        model and the likelihood (the evaluator's kind)
 *   lua_invert_result.c  the result table, its summary text, predictions
 *   lua_invert_plot.c    dfle.plot.corner, dfle.plot.posterior_predictive
 *
 * The sampler, the chain file, resume, the worker pool, the summaries
 * and diagnostics are the C library's (dfle/invert_run.h).  Every Lua
 * state that evaluates the posterior (the main one and each worker's,
 * lua/drive/ replays the script) builds its own inv_run from the same
 * table, so evaluations are pure functions of the parameters and the
 * chain does not depend on who evaluated what.
 */
#ifndef DFLE_LUA_INVERT_INTERNAL_H
#define DFLE_LUA_INVERT_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "dfle/csv.h"
#include "dfle/invert_run.h"
#include "dfle/prior.h"
#include "lua/core/dfle_lua.h"
#include "lua/drive/lua_parallel.h"

#define INV_BOX "dfle.invert_run"
#define INV_RESULT "dfle.inversion"
#define INV_MSG DFLE_INVERT_MSG

/* The problem and, in the main state, the chain: freed by the box's __gc
 * if anything raises. */
typedef struct inv_run {
    /* --- the problem: free parameters (sigma last when inferred) --- */
    size_t d, nmodel;        /* free parameters; those passed to build  */
    dfle_prior *prior;       /* d                                       */
    int *logs;               /* d: log-scaled                           */
    unsigned char *custom;   /* d: a Lua density adds to the prior      */
    int sigma_free;          /* sigma is parameter d - 1                */
    double sigma;            /* the fixed noise sd, when not free       */
    size_t nobs;
    double *A_obs, *lnS_obs; /* the binned data                         */
    double *r;               /* nobs residuals: scratch                 */
    /* --- the driver's options (names, priors point into this box) --- */
    dfle_invert_opts o;
    const char **names;      /* d: held by the context table            */
    int lsq, nested;
    /* --- the run (main state only) --- */
    dfle_invert *inv;        /* the chain                               */
    dfle_csv *csv;           /* data file being read                    */
    dfle_lua_eval_spec ev;   /* the evaluator's texts                   */
    int ev_set;
    char *text[2];           /* the driver's texts, pushed then freed   */
    /* the chain as the result shows it (the driver's arrays)           */
    size_t walkers, steps, burn, have;
    const double *X, *LP, *LL;
    const unsigned char *ST;
    lua_State *L;            /* the calling state and its context table, */
    int ctx;                 /* for the Lua densities at summary time   */
    double lsq_seconds;      /* forward-model CPU time of the estimate  */
    size_t lsq_evaluations;
} inv_run;

/* The context table of an inversion (lua_invert_spec.c) holds: names,
 * build, channel, fixed, run, density (name -> ln p function), meta,
 * header, out, data (the binned data: A, S, count, raw, kind, outside)
 * and box (the inv_run); failure_messages after a run. */

/* lua_invert_spec.c: check the table at arg, push the context table;
 * *box receives the run (kept alive by ctx.box). */
void inv_read_spec(lua_State *L, int arg, inv_run **box);
void inv_push_box(lua_State *L); /* a new, empty run box */

/* lua_invert_eval.c: the evaluator's kind for dfle.invert. */
extern const dfle_lua_kind inv_kind;
/* Residuals at x (the model parameters, natural units) into R->r;
 * DFLE_OK, DFLE_EFIT for a failed run (message in err). */
int inv_residuals(lua_State *L, int ctx, inv_run *R, const double *x, double *fwd,
                  dfle_error *err);
/* Forward run at x, then the model's slopes at n areas Aq into Sq
 * (for predictions): DFLE_EVAL_OK or a failure's status. */
int inv_predict_at(lua_State *L, int ctx, inv_run *R, const double *x, size_t n,
                   const double *Aq, double *Sq);

/* lua_invert_data.c: data = profile | file | {A =, S =} of the table at
 * arg into R->A_obs, lnS_obs; pushes the data table of the result ({A,
 * S, count, raw, kind}, A and S set later).  Returns 1 for DEM data. */
int inv_read_data(lua_State *L, int arg, inv_run *R, size_t nbins, int nbins_given);
/* Leave out the bins outside the channel's areas; how many. */
size_t inv_clip_to_channel(inv_run *R, const dfle_channel *ch);

/* lua_invert_lsq.c: push res.lsq (never raises on a failed fit). */
void inv_push_lsq(lua_State *L, int ctx, inv_run *R);

/* lua_invert_result.c: push the result table of the chain in R->inv
 * (its arrays noted in R for predictions and plots). */
void inv_push_result(lua_State *L, int ctx, inv_run *R, int lsq_idx, double elapsed);
/* The result's context table (for predictions), pushed; raises if the
 * value at idx is not a result. */
int inv_result_ctx(lua_State *L, int idx);
void inv_open_result(lua_State *L);

/* lua_invert_plot.c: dfle.plot.corner, dfle.plot.posterior_predictive */
void inv_open_plot(lua_State *L);

#endif
