/*
 * ensemble_run.h - an ensemble run from C: a Latin hypercube design
 * (sampling.h), one evaluation per sample (evaluator.h) on a worker pool
 * (pool.h), one row per sample streamed to a resumable file
 * (ensemble.h).  What dfle.ensemble is, without Lua: the Lua binding
 * reads the table, gives an evaluator that runs the script's build and
 * measure, and reads the file back as the result.
 *
 * The file (doc/ensembles.md, "The file"):
 *
 *     # dfle.ensemble v1 n=64 seed=1 centered=false inputs=U,k_df outputs=S_df,A_df design=U:[0.0001,0.001];k_df:[5e-05,0.001,log]
 *     # dfle: 0.1.0
 *     # <the describe record's sections, one a line>
 *     # units: U=m/yr, S_df=-, A_df=m^2
 *     index,U,k_df,S_df,A_df,status,reason
 *     1,0.00063...,0.00012...,0.3698...,235246.57...,ok,""
 *
 * A row holds the sample's parameters, its outputs (NaN unless the
 * status is ok), the status (dfle_eval_status_name) and the reason,
 * quoted.  An output the evaluator gives as NaN or infinite makes the
 * row "nan", reason "output 'S_df' is NaN".  The finished file is the
 * same byte for byte for any number of workers, processes, shards and
 * resumes: the design and each evaluation are pure functions, and the
 * rows are sorted by index at the end.
 */
#ifndef DFLE_ENSEMBLE_RUN_H
#define DFLE_ENSEMBLE_RUN_H

#include <signal.h>
#include <stddef.h>

#include "dfle/error.h"
#include "dfle/evaluator.h"
#include "dfle/pool.h"
#include "dfle/record.h"
#include "dfle/sampling.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A parameter of the design.  The evaluator gets, for sample i, x[j] =
 * the parameter's value, or for a DISCRETE one the index (0, 1, ...) of
 * the value chosen. */
typedef struct dfle_ensemble_param {
    const char *name;    /* a CSV column: no commas, quotes, spaces, '='
                          * or line breaks; not index, status, reason    */
    const char *unit;    /* for the file's units line; NULL: none        */
    dfle_lhs_kind kind;
    double lo, hi;       /* UNIFORM and LOG_UNIFORM                       */
    size_t nvalues;      /* DISCRETE                                      */
    /* DISCRETE: each value as the file shows it (in the meta line and the
     * rows), e.g. "2", "0.5", "\"a\"" for a text (quoted). */
    const char *const *value_text;
} dfle_ensemble_param;

typedef struct dfle_ensemble_opts {
    /* The design (sampling.h: the same seed gives the same design). */
    size_t n;              /* samples, >= 1                               */
    unsigned long seed;    /* 0 .. DFLE_SEED_MAX                          */
    int centered;
    size_t nparams;
    const dfle_ensemble_param *params;
    /* The evaluator's outputs, in order: the columns after the
     * parameters, names like the parameters', units may be NULL. */
    size_t noutputs;
    const char *const *outputs;
    const char *const *output_units; /* NULL, or noutputs (entries NULL)  */
    /* The file. */
    const char *out;       /* before the shard's suffix                  */
    int resume;            /* 1: continue a file of this ensemble (default) */
    size_t limit;          /* run at most this many samples; 0: all      */
    size_t shard_i, shard_n; /* shard i of n (1-based); shard_n 0: all  */
    /* Comment lines under "# dfle: <version>", one per section of this
     * record (the options a binding ran samples with); may be NULL.  The
     * same for every run of the ensemble: no date, no command. */
    const dfle_record *describe;
    /* Where it runs. */
    int workers;           /* local evaluators (>= 1); 1 without a remote:
                            * the calling thread alone (worker 0)        */
    const dfle_remote *remote; /* other processes, or NULL               */
    int remote_workers;    /* what each of them is told (0: its default) */
    const volatile sig_atomic_t *interrupt;
    /* Optional: done/total samples so far (failed among them), from the
     * calling thread, about every 0.1 s and after the last. */
    void (*progress)(void *ud, size_t done, size_t total, size_t failed, double elapsed);
    /* Optional: a line a user should see ("resuming: 40 rows kept ..."). */
    void (*note)(void *ud, const char *line);
    void *ud;
} dfle_ensemble_opts;

/* n = 0 (required), seed = 1, resume on, one worker. */
void dfle_ensemble_opts_default(dfle_ensemble_opts *o);

typedef struct dfle_ensemble_result {
    char path[4096];    /* the file (with the shard's suffix)             */
    size_t kept;        /* rows the file had already                      */
    size_t total;       /* samples this call was to run                   */
    size_t ran;         /* samples it ran (rows written)                  */
    size_t failed;      /* ... of them not ok                             */
    int interrupted;    /* stopped by opts.interrupt before the end       */
} dfle_ensemble_result;

/* Check the options as dfle_ensemble_run does, without running: a
 * message naming what is wrong ("ensemble: 'U' is both a parameter and
 * an output"). */
int dfle_ensemble_check(const dfle_ensemble_opts *o, dfle_error *err);

/* The lines that identify the ensemble (resume and gather compare
 * them): the meta line and the header, malloc'd. */
int dfle_ensemble_identity(const dfle_ensemble_opts *o, char **meta, char **header,
                           dfle_error *err);

/* "dir/ens.csv" with shard i of n: "dir/ens.shard-2-of-4.csv" (n <= 1:
 * the path itself), into buf.  DFLE_EINVAL if it does not fit. */
int dfle_ensemble_shard_path(const char *out, size_t i, size_t n, char *buf, size_t cap,
                             dfle_error *err);

/* The unit dfle knows for an output of a steady-state sample (the fit's
 * S_df, A_df, ..., the run's time, runout_A, ...), or NULL. */
const char *dfle_ensemble_known_unit(const char *output);

/* Run the ensemble: open (or resume) the file, run the samples it lacks
 * on opts->workers evaluators of ev (and the remote's), append each row
 * as it comes, then rewrite the file sorted.  res is filled in every
 * case it can be.  DFLE_OK; DFLE_ECANCELED when interrupted (the rows
 * written stay as they are, whole lines; running again resumes);
 * otherwise the error (an evaluator's, the file's), the rows written
 * kept. */
int dfle_ensemble_run(const dfle_ensemble_opts *opts, const dfle_evaluator *ev,
                      dfle_ensemble_result *res, dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
