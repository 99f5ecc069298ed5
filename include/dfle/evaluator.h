/*
 * evaluator.h - what the drivers run many times: "given sample i and its
 * parameter vector x, produce its outputs".  An ensemble asks for the
 * outputs of a steady state (S_df, A_df, ...); an inversion for the log
 * likelihood of a proposal (ensemble_run.h, invert_run.h).
 *
 * An evaluator is an ops table and the pointer it is opened with.  Each
 * worker of a pool (pool.h) opens it once, in its own thread, and keeps
 * what open made (a Lua state that replayed a script, a model, scratch
 * memory) for every sample it runs, so the expensive set-up is paid once
 * per worker, as wrk keeps one Lua state per thread.  A binding (Lua,
 * Python) or a C program provides one; the drivers never know which.
 *
 * The contract that makes results independent of the number of workers:
 * eval is a pure function of x (and i): no randomness, no clock, no state
 * carried from one sample to the next that changes its outputs.
 *
 * Three outcomes of eval, kept apart so that an interrupt never turns
 * into a result:
 *  - DFLE_OK: the sample was evaluated, and out->status says how it went
 *    (a failed sample, e.g. a model without a steady state, is a result:
 *    its row says why);
 *  - DFLE_ECANCELED: the sample was cut short by an interrupt (a run
 *    stopped by Ctrl-C): no result, nothing is recorded, a resumed run
 *    evaluates it again;
 *  - any other negative status, with err set: the evaluator itself is
 *    broken (a worker's script could not be replayed): the run stops with
 *    that error.
 */
#ifndef DFLE_EVALUATOR_H
#define DFLE_EVALUATOR_H

#include <stddef.h>

#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The version of dfle_evaluator_ops this header describes: set .version
 * to it.  Later versions only append members, and the drivers read what
 * the table's version says it has (SQLite's iVersion). */
#define DFLE_EVALUATOR_VERSION 1

/* How an evaluated sample went (out->status), with its name in files. */
enum dfle_eval_status {
    DFLE_EVAL_OK = 0,            /* "ok"                                       */
    DFLE_EVAL_NOT_CONVERGED = 1, /* "not_converged": no steady state           */
    DFLE_EVAL_FIT_FAILED = 2,    /* "fit_failed": the slope-area fit failed    */
    DFLE_EVAL_NAN = 3,           /* "nan": an output is NaN or infinite (the
                                  * ensemble driver sets it itself)            */
    DFLE_EVAL_INVALID = 4,       /* "invalid_profile": a profile the
                                  * likelihood cannot use                      */
    DFLE_EVAL_OUTSIDE = 5,       /* "outside_prior": zero prior density        */
    DFLE_EVAL_ERROR = 6,         /* "error": anything else that failed         */
    DFLE_EVAL_NSTATUS
};
/* "ok", "not_converged", ...; "unknown" for another number. */
const char *dfle_eval_status_name(int status);

/* The longest reason kept (longer ones are cut, at a character boundary
 * of UTF-8 text). */
#define DFLE_EVAL_REASON_MAX 4096

/* out->flags */
enum {
    /* The reason is the text of a number (a script raised error(42)):
     * files write it as a number, unquoted. */
    DFLE_EVAL_REASON_NUMBER = 1u
};

/* What eval fills.  The driver provides y (noutputs values, set to NaN
 * before the call) and clears status, reason and flags. */
typedef struct dfle_eval_out {
    int status;                      /* enum dfle_eval_status             */
    double *y;                       /* the outputs                       */
    char reason[DFLE_EVAL_REASON_MAX]; /* why, when status is not OK      */
    unsigned flags;
    double seconds;                  /* the CPU time [s] of the model the
                                      * sample ran, if eval measures it
                                      * (its own part left out); else the
                                      * pool sets the whole call's        */
} dfle_eval_out;

/* Set out->reason (printf format), cut to fit. */
void dfle_eval_reason(dfle_eval_out *out, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

typedef struct dfle_evaluator_ops {
    int version;      /* DFLE_EVALUATOR_VERSION                          */
    const char *name; /* for messages: "lua.ensemble", "c.test", ...     */
    /* Required.  Open worker `worker`'s evaluator in the calling thread,
     * into *state.  Worker 0 is the thread that runs the pool itself
     * (pool.h, opts.caller), the others 1, 2, ...  0, or a negative
     * status with err set: the pool then stops with that error. */
    int (*open)(void *ud, int worker, void **state, dfle_error *err);
    /* Required.  Evaluate sample `index` (1-based, the driver's numbering)
     * with parameters x (the driver's count of them) into out; see the
     * three outcomes above.  Called only from the thread that opened
     * state, one sample at a time. */
    int (*eval)(void *state, size_t index, const double *x, dfle_eval_out *out,
                dfle_error *err);
    /* Optional.  Release state (called from the thread that opened it). */
    void (*close)(void *state);
} dfle_evaluator_ops;

/* An evaluator: the table, the pointer its open gets, and optionally a
 * key, text from which another process can open the same evaluator (the
 * MPI driver sends it to the other ranks, whose command makes the
 * evaluator from it: dfle-mpi's ranks replay the script up to the call
 * that the key names).  NULL: this process only. */
typedef struct dfle_evaluator {
    const dfle_evaluator_ops *ops;
    void *ud;
    const char *key;
} dfle_evaluator;

/* DFLE_EINVAL (naming what is wrong) unless ev is an evaluator of a
 * version this library knows with open and eval. */
int dfle_evaluator_check(const dfle_evaluator *ev, dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
