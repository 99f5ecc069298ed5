/*
 * invert_run.h - an inversion run from C: the affine-invariant ensemble
 * sampler (mcmc.h) over the priors (prior.h) and a log likelihood given
 * by an evaluator (evaluator.h), its proposals evaluated on a worker
 * pool (pool.h), the chain streamed to a resumable file, and the
 * summaries and diagnostics of the samples after burn-in (mcmc_diag.h).
 * What dfle.invert is, without Lua: the binding reads the table, gives
 * an evaluator that runs the script's build through the slope-area
 * likelihood, and builds the result table (doc/inversion.md).
 *
 * The evaluator of an inversion gives, for a proposal x (d values in
 * natural units, inside the priors' supports), y[0] = ln L(x) and, for
 * each parameter j whose prior is DFLE_PRIOR_CUSTOM, y[1 + j] = its log
 * density at x[j] (noutputs = 1 + d); status DFLE_EVAL_OUTSIDE for a
 * custom density that is zero there, any other failure (no steady state,
 * a profile the likelihood cannot use, an error) as in evaluator.h: a
 * proposal that failed has zero posterior and its walker stays.
 *
 * The chain file (one row per walker and step, the position after the
 * step):
 *
 *     # dfle.invert v2 seed=1 walkers=32 a=2 params=U:log-uniform[0.0001,0.001];... <identity>
 *     # dfle: 0.1.0
 *     # date: 2026-12-03T20:12:54Z
 *     # command: dfle run.lua            (what opts.describe says)
 *     # units: U=m/yr, ..., log_post=-, log_like=-
 *     index,step,walker,U,...,log_post,log_like,proposal
 *     1,0,1,0.000126451533767,...,-32.10303259,-46.79132086,initial
 *
 * index = step K + walker, so the ensemble file layer (ensemble.h)
 * streams, cuts and sorts it.  The lines between the first and the
 * header describe the file (written when it is created, kept by a
 * resume); the first line identifies the chain.  Positions are held at
 * 12 significant digits (every proposal and starting draw is rounded
 * to the double of its 12-digit decimal before it is evaluated), so the
 * file's text is the chain itself: it reads back to the same doubles and
 * a resumed chain continues bit for bit, and the chain is the same for
 * any number of workers (the random numbers of walker k at step s come
 * from their own stream, stream.h).  log_post and log_like are written
 * with 10 significant digits; the sampler keeps their exact values, and
 * a resume recomputes those of the walkers it continues from.
 *
 * A resume validates what it reads: every number finite, every position
 * inside its prior, whole steps without gaps, a walker that did not move
 * with the values of its step before, log_post - log_like equal to the
 * log prior (custom priors apart), and the last step's log_post and
 * log_like, and those of the row with the largest log_post, equal to
 * what the evaluator gives at their positions now (a complete chain
 * read back is checked so too, at the cost of walkers + 1 forward runs,
 * before it is summarised); a file that fails is refused with its line
 * named, and left as it is.  Rows in between are checked for
 * consistency, not evaluated again.
 *
 * Walker health: after burn-in a walker whose median log posterior lies
 * far below the others' (by more than half the 1 - 1e-6 quantile of
 * chi-square with d degrees of freedom: the drop at which a Gaussian
 * posterior has all but 1e-6 of its mass above), or whose acceptance is
 * below a quarter of the walkers' median and improbably so (binomial
 * p < 1e-6), is stranded: reported and warned by number.  A chain of
 * fewer than 50 steps after burn-in is not checked (the ensemble may
 * still be walking in, and a walker that never moved in fewer steps is
 * not improbable enough).  With
 * opts.move_stranded (default) the same test runs at steps burn/2 and
 * burn, on the steps since the previous check, and a stranded walker is
 * moved onto the position of a healthy one (a walker picked by its own
 * stream), its row saying "moved", so it can no longer set an interval.
 *
 * Prior bounds: a parameter's marginal piles against a finite bound of
 * its prior when the density of its samples within h of the bound is at
 * least a quarter of their density within h/2 of the median (h: a
 * tenth of the 95 % interval's width, in ln x for log-scaled
 * parameters) and the share P of samples within h of the bound clearly
 * exceeds the prior's own share P0 there (P > 2 P0 + 3 sqrt(P0 (1 - P0)
 * / n), n the effective sample size, at least the walkers: a prior that
 * piles at its bound, with data that say nothing, is not flagged), or
 * when the point estimate (dfle_invert_set_point) lies within 1e-3 of
 * the prior's width of it: flagged (result.bounded) and warned.  A
 * marginal near both bounds that is no more there than its prior is
 * warned of as not learned, and not flagged.
 */
#ifndef DFLE_INVERT_RUN_H
#define DFLE_INVERT_RUN_H

#include <signal.h>
#include <stddef.h>
#include <stdint.h>

#include "dfle/error.h"
#include "dfle/evaluator.h"
#include "dfle/mcmc_diag.h"
#include "dfle/prior.h"
#include "dfle/record.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What became of a walker's proposal at a step (the `proposal` column). */
enum dfle_proposal {
    DFLE_PROPOSAL_INITIAL,       /* "initial": step 0, the starting ensemble */
    DFLE_PROPOSAL_ACCEPTED,      /* "accepted"                               */
    DFLE_PROPOSAL_REJECTED,      /* "rejected": evaluated, not accepted      */
    DFLE_PROPOSAL_OUTSIDE,       /* "outside_prior": not run                 */
    DFLE_PROPOSAL_NOT_CONVERGED, /* "not_converged"                          */
    DFLE_PROPOSAL_INVALID,       /* "invalid_profile"                        */
    DFLE_PROPOSAL_ERROR,         /* "error"                                  */
    DFLE_PROPOSAL_MOVED,         /* "moved": a stranded walker moved onto a
                                  * healthy one's position in burn-in        */
    DFLE_PROPOSAL_N
};
const char *dfle_proposal_name(int proposal);

/* A failure's message is kept up to this length (with its NUL). */
#define DFLE_INVERT_MSG 200
/* Whether a marginal is held by a bound of its prior (result.bounded). */
enum dfle_bound {
    DFLE_BOUND_NONE = 0,
    DFLE_BOUND_LOWER = 1, /* "lower" */
    DFLE_BOUND_UPPER = 2, /* "upper" */
    DFLE_BOUND_BOTH = 3   /* "both": flat over the prior, not learned */
};
const char *dfle_bound_name(int bound); /* "none", "lower", "upper", "both" */

/* A walker found stranded after burn-in. */
typedef struct dfle_invert_walker {
    size_t walker;              /* 1-based                                   */
    double acceptance;          /* its acceptance after burn-in              */
    double ensemble_acceptance; /* the walkers' median                       */
    double lp_drop;             /* its median log posterior below the median
                                 * of the walkers' medians                   */
    double *median;             /* d: its median position                    */
} dfle_invert_walker;

/* A stranded walker moved in burn-in (a "moved" row of the chain). */
typedef struct dfle_invert_move {
    size_t step, walker, onto;  /* onto: the walker whose position it took */
    double lp_gain;             /* its log posterior after minus before     */
} dfle_invert_move;

/* opts.burn when not given: steps / 4. */
#define DFLE_INVERT_BURN_DEFAULT ((size_t)-1)

typedef struct dfle_invert_opts {
    size_t d;                  /* free parameters, >= 1                     */
    const char *const *names;  /* d: the chain's columns                    */
    const dfle_prior *priors;  /* d                                         */
    size_t walkers;            /* K, even, >= 2 d; 0: 32, or 2 d if more    */
    size_t steps;              /* N; 0: nothing to sample                   */
    size_t burn;               /* steps discarded; DFLE_INVERT_BURN_DEFAULT */
    unsigned long seed;        /* 0 .. 4294967295                           */
    double a;                  /* the stretch scale, > 1 (2)                */
    const char *out;           /* the chain file, or NULL: memory only      */
    int resume;                /* continue a file of this chain (1)         */
    int read_only;             /* only read the finished chain in `out`     */
    /* Appended to the file's first line (from " sigma=" or " fixed="
     * on): what else makes two inversions the same, the data, the model
     * and the likelihood, so that a resume refuses another one's file. */
    const char *identity;
    int workers;               /* evaluators: the calling thread and
                                * workers - 1 threads (0: 1)               */
    const volatile sig_atomic_t *interrupt;
    /* Optional: evaluations done/total of this call (failed among them),
     * after each step, from the calling thread. */
    void (*progress)(void *ud, size_t done, size_t total, size_t failed, double elapsed);
    void *ud;
    /* Appended after the first release of this struct (its defaults
     * come from dfle_invert_opts_default): */
    /* What made a new chain file, as its comment lines (the command, the
     * script, ...), after its own version and date lines; NULL: just
     * those.  Only read while the file is created. */
    const dfle_record *describe;
    /* d units of the parameters for the file's units line ("m/yr", "-"),
     * or NULL (none, or NULL entries: left out). */
    const char *const *units;
    /* Move walkers stranded in burn-in back into the ensemble (1). */
    int move_stranded;
    /* Optional: the log density (up to a constant) of the CUSTOM prior
     * of parameter j at x, as the evaluator adds it, for the prior-bound
     * rule (the prior's own mass near a bound); NULL: such a prior counts
     * as flat over its support.  Called on the calling thread while a
     * chain is summarised; -inf or NaN where it is zero. */
    double (*custom_logpdf)(void *ud, size_t j, double x);
    void *custom_ud;
} dfle_invert_opts;

/* walkers 0 (the default), burn default, seed 1, a = 2, resume, 1 worker,
 * move_stranded. */
void dfle_invert_opts_default(dfle_invert_opts *o);

/* The chain and what it says.  Arrays are (steps + 1) x walkers (x d),
 * step by step, walker by walker. */
typedef struct dfle_invert_result {
    size_t d, walkers, steps, burn;
    size_t have;               /* steps + 1 complete when the chain is     */
    size_t ran;                /* steps run by this call                   */
    double *x, *log_post, *log_like;
    unsigned char *proposal;   /* enum dfle_proposal                       */
    size_t evaluations;        /* proposals evaluated by this call         */
    double forward_seconds;    /* their evaluators' CPU time [s]           */
    size_t init_failed;        /* starting draws with zero posterior       */
    char failure[DFLE_PROPOSAL_N][DFLE_INVERT_MSG]; /* the first message of
                                * each kind of failure (this call), or ""  */
    int interrupted;           /* stopped at a whole step by an interrupt  */
    /* --- the samples after burn-in (when complete and steps >= 1) ---   */
    int complete;
    size_t nsamples;           /* walkers x (steps - burn)                 */
    dfle_summary *summary;     /* d                                        */
    double *tau;               /* d: autocorrelation times [steps], NaN
                                * for a parameter no walker moved in       */
    double tau_max;
    size_t ess;
    int converged;             /* steps - burn >= 50 tau_max               */
    double acceptance;         /* over steps 1 .. steps                    */
    double *acceptance_walkers;/* walkers                                  */
    size_t tally[DFLE_PROPOSAL_N]; /* proposals by outcome, steps 1 .. steps */
    size_t best;               /* row of the largest log_post              */
    size_t nwarnings;
    char **warnings;           /* what to be careful of, sentences         */
    /* Appended after the first release of this struct: */
    size_t nstranded;          /* walkers stranded after burn-in           */
    dfle_invert_walker *stranded;
    size_t nmoved;             /* stranded walkers moved in burn-in (the
                                * chain's "moved" rows; any call)          */
    dfle_invert_move *moved;
    unsigned char *bounded;    /* d: enum dfle_bound                       */
    double threshold_lp;       /* the log-posterior drop that strands      */
    size_t first_alert;        /* warnings[first_alert ..]: stranded
                                * walkers and prior bounds, what says that
                                * a number printed is not the data's (a
                                * binding shows them at run time)          */
} dfle_invert_result;

/* The options checked (and defaults resolved) as dfle_invert_new does,
 * without running; a message naming what is wrong. */
int dfle_invert_check(const dfle_invert_opts *o, dfle_error *err);

/* The first line and the header of the chain file, malloc'd. */
int dfle_invert_identity(const dfle_invert_opts *o, char **meta, char **header,
                         dfle_error *err);

/* An inversion: its options, its chain, its file. */
typedef struct dfle_invert dfle_invert;

/* Check the options, make room for the chain, and open its file: a new
 * one, or one of this inversion to resume or extend (another
 * inversion's is refused, naming the first difference); with
 * opts->read_only, read a finished chain and summarise it.  opts is
 * copied, its arrays and texts must outlive the object. */
int dfle_invert_new(const dfle_invert_opts *opts, dfle_invert **out, dfle_error *err);

/* A point estimate (the least-squares fit: d values in natural units,
 * NaN where there is none) to be checked against the priors' bounds
 * with the samples: one on a bound flags that parameter (see the top).
 * Call before dfle_invert_run; NULL forgets it. */
int dfle_invert_set_point(dfle_invert *inv, const double *x, dfle_error *err);

/* Run the chain from where it is to opts->steps on opts->workers
 * evaluators of ev, close the file (sorted), and summarise it.
 * DFLE_OK (at once when the chain is complete); DFLE_ECANCELED when
 * interrupted (the chain, and the file, hold the whole steps done;
 * running again resumes); or the error, the rows written kept. */
int dfle_invert_run(dfle_invert *inv, const dfle_evaluator *ev, dfle_error *err);

/* The chain and its summaries as they are now.  Valid until the next
 * dfle_invert_run or dfle_invert_free. */
const dfle_invert_result *dfle_invert_result_of(const dfle_invert *inv);

void dfle_invert_free(dfle_invert *inv); /* closes the file; accepts NULL */

#ifdef __cplusplus
}
#endif
#endif
