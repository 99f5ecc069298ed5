/*
 * lua_invert_internal.h - what the files of dfle.invert share (not
 * installed):
 *
 *   lua_invert.c         the entry point: spec, chain file, point
 *                        estimate, sampling, result
 *   lua_invert_spec.c    the table checked into a problem (priors, data,
 *                        channel) and its identity line
 *   lua_invert_data.c    the data binned into areas and log slopes
 *   lua_invert_lsq.c     the least-squares point estimate
 *   lua_invert_loop.c    the sampling loop
 *   lua_invert_eval.c    one log-posterior evaluation in one Lua state
 *   lua_invert_pool.c    worker threads evaluating batches of proposals
 *   lua_invert_chain.c   chain rows: formatting, and reading back to resume
 *   lua_invert_result.c  the result table, its summary text, predictions
 *   lua_invert_plot.c    dfle.plot.corner, dfle.plot.posterior_predictive
 *
 * Every Lua state that evaluates the posterior (the main one and each
 * worker's, see lua_ensemble_internal.h for the replay) builds its own
 * inv_problem from the same table, so evaluations are pure functions of
 * the parameters and the chain does not depend on who evaluated what.
 */
#ifndef DFLE_LUA_INVERT_INTERNAL_H
#define DFLE_LUA_INVERT_INTERNAL_H

#include <pthread.h>
#include <stddef.h>
#include <stdint.h>

#include "lua/core/dfle_lua.h"
#include "lua/ensemble/lua_ensemble_internal.h"
#include "dfle/csv.h"
#include "dfle/ensemble.h"
#include "dfle/mcmc.h"
#include "dfle/prior.h"

#define INV_BOX "dfle.invert_run"
#define INV_RESULT "dfle.inversion"
#define INV_MSG 200 /* a failed evaluation's message, kept per proposal */

/* What became of a walker's proposal at a step (the chain's `proposal`
 * column); the failures are tallied. */
enum inv_status {
    INV_INITIAL,     /* step 0: the starting ensemble                  */
    INV_ACCEPTED,
    INV_REJECTED,    /* evaluated, not accepted                        */
    INV_OUTSIDE,     /* outside the prior's support: not run           */
    INV_NOT_CONVERGED, /* no steady state                              */
    INV_INVALID,     /* a profile the likelihood cannot use            */
    INV_ERROR,       /* raised: in build, the run, a prior density     */
    INV_NSTATUS
};
extern const char *const inv_status_name[INV_NSTATUS];

typedef struct inv_pool inv_pool;

/* The problem and, in the main state, the run: freed by the box's __gc
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
    /* --- sampler settings --- */
    size_t walkers, steps, burn;
    uint64_t seed;
    double a;
    int lsq, resume, workers, nested;
    /* --- the run (main state only) --- */
    dfle_mcmc *mc;
    dfle_ens_file *file;
    double *X, *LP, *LL;     /* (steps + 1) x K (x d): the chain        */
    unsigned char *ST;       /* (steps + 1) x K: enum inv_status         */
    size_t done;             /* steps complete in X (0 = only the start) */
    size_t have;             /* steps + 1 held in X (a file may hold more)*/
    inv_pool *pool;
    dfle_csv *csv;           /* data file being read                    */
    dfle_ens_table *table;   /* chain file being checked                */
    char *row;               /* one formatted row                       */
    size_t rowcap;
    double fwd_seconds;      /* forward-model CPU time, all evaluators  */
    size_t evaluations;      /* forward runs by this call               */
    size_t init_failed;      /* starting draws without a density        */
} inv_run;

/* The context table of an inversion (lua_invert_spec.c) holds: names,
 * build, channel, fixed, run, density (name -> ln p function), meta,
 * header, out, data (the binned data: A, S, count, raw, kind, outside)
 * and box (the inv_run); failure_messages after a run. */

/* lua_invert_spec.c: check the table at arg, push the context table;
 * *box receives the run (kept alive by ctx.box). */
void inv_read_spec(lua_State *L, int arg, inv_run **box);
void inv_push_box(lua_State *L); /* a new, empty run box */

/* lua_invert_eval.c: the log posterior of x (d values) in L with the
 * context at ctx; never raises.  *lp is -inf for every failure, whose
 * status is returned with a message in msg (may be NULL).  *fwd adds the
 * forward model's CPU time [s]. */
int inv_eval(lua_State *L, int ctx, inv_run *R, const double *x, double *lp, double *ll,
             double *fwd, char *msg, size_t msglen);
/* Residuals at x (the model parameters, natural units) into R->r;
 * DFLE_OK, DFLE_EFIT for a failed run (message in err). */
int inv_residuals(lua_State *L, int ctx, inv_run *R, const double *x, double *fwd,
                  dfle_error *err);
/* Forward run at x, then the model's slopes at n areas Aq into Sq
 * (for predictions); status as inv_eval. */
int inv_predict_at(lua_State *L, int ctx, inv_run *R, const double *x, size_t n,
                   const double *Aq, double *Sq, char *msg, size_t msglen);

/* lua_invert_data.c: data = profile | file | {A =, S =} of the table at
 * arg into R->A_obs, lnS_obs; pushes the data table of the result ({A,
 * S, count, raw, kind}, A and S set later).  Returns 1 for DEM data. */
int inv_read_data(lua_State *L, int arg, inv_run *R, size_t nbins, int nbins_given);
/* Leave out the bins outside the channel's areas; how many. */
size_t inv_clip_to_channel(inv_run *R, const dfle_channel *ch);

/* lua_invert_lsq.c: push res.lsq (never raises on a failed fit). */
void inv_push_lsq(lua_State *L, int ctx, inv_run *R);

/* lua_invert_loop.c: run the chain from R->have to R->steps on nw
 * evaluators (the main thread and nw - 1 workers replaying to the
 * call-th dfle.invert); sets ctx.failure_messages.  0, or -1 with msg
 * (the workers are stopped either way). */
int inv_sample(lua_State *L, int ctx, inv_run *R, int nw, lua_Integer call, char *msg,
               size_t msglen);

/* lua_invert_pool.c */
int inv_pool_start(lua_State *L, inv_run *R, int nthreads, lua_Integer call, const char *meta,
                   char *msg, size_t msglen);
/* Evaluate n points (n x d) in L (ctx) and on the workers; statuses,
 * log posteriors and likelihoods by point; messages INV_MSG apart.
 * Returns 0, or -1 when a worker failed (message in msg). */
int inv_pool_eval(lua_State *L, int ctx, inv_run *R, size_t n, const double *x, double *lp,
                  double *ll, unsigned char *st, char *msgs, char *msg, size_t msglen);
/* Stop and join the workers; -1 with msg if one of them failed. */
int inv_pool_stop(inv_run *R, char *msg, size_t msglen);

/* lua_invert_chain.c */
/* Format the row of (step, walker) from the chain in R into R->row. */
int inv_format_row(inv_run *R, size_t step, size_t k);
/* Read an existing chain file back into R->X.. (after the file is open
 * and checked); sets R->done.  0 or -1 with msg. */
int inv_read_chain(inv_run *R, const char *path, char *msg, size_t msglen);

/* lua_invert_result.c: push the result table of the chain in R. */
void inv_push_result(lua_State *L, int ctx, inv_run *R, int lsq_idx, double elapsed,
                     size_t ran);
/* The result's context table (for predictions), pushed; raises if the
 * value at idx is not a result. */
int inv_result_ctx(lua_State *L, int idx);
void inv_open_result(lua_State *L);

/* lua_invert_plot.c: dfle.plot.corner, dfle.plot.posterior_predictive */
void inv_open_plot(lua_State *L);

#endif
