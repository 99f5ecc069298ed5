/*
 * invert_internal.h - what the files of the inversion driver share (not
 * installed): invert_run.c (the options, the starting ensemble, the
 * sampling loop on the pool), invert_chain.c (the chain file: its
 * lines, rows, resume and what a resume checks), invert_health.c
 * (stranded walkers: found, moved in burn-in, reported),
 * invert_bounds.c (marginals held by a prior bound) and
 * invert_summary.c (the samples after burn-in summarised, the
 * diagnostics).
 */
#ifndef DFLE_INVERT_INTERNAL_H
#define DFLE_INVERT_INTERNAL_H

#include "dfle/ensemble.h"
#include "dfle/invert_run.h"
#include "drive/drive_internal.h"

/* Significant digits of the chain's positions (the sampler's own
 * values: proposals are rounded to them) and of its log densities (as
 * written; the sampler keeps them exact). */
#define INV_X_DIGITS 12
#define INV_LP_DIGITS 10

/* A run: the options with their defaults resolved, and the result it
 * fills (dfle_invert, invert_run.h). */
typedef struct inv_run {
    dfle_invert_opts o;     /* walkers and burn resolved               */
    dfle_invert_result *r;
    dfle_ens_file *file;    /* the chain file, open for appending      */
    dfle_text row;          /* one formatted row                       */
    size_t *line;           /* (steps + 1) x K: the file line a row was
                             * read from (0: not read), for messages    */
    double *point;          /* d: the point estimate (NaN: none)       */
    char **partial;         /* K: the rows of a step the file holds in
                             * part (a killed writer), as read, to be
                             * compared with the step redone; or NULL  */
    size_t partial_step;
} inv_run;
struct dfle_invert {
    inv_run R;
};

/* invert_run.c: the options checked, defaults resolved into *res. */
int inv_resolve(const dfle_invert_opts *o, dfle_invert_opts *res, dfle_error *err);

/* invert_chain.c */
/* v as the double of its decimal text with `digits` significant digits
 * (what the file holds, and reads back exactly). */
double inv_round(double v, int digits);
/* Open (or resume) the chain file of R->o.out, reading back (and
 * checking) the steps it holds; R->r->have set.  A status with err
 * ("invert: ..."). */
int inv_open_chain(inv_run *R, dfle_error *err);
/* Read the chain in R->o.out into R->r (no lock, no writing), checking
 * every row: have set. */
int inv_read_chain(inv_run *R, const char *path, dfle_error *err);
/* Free R->partial. */
void inv_forget_partial(inv_run *R);
/* Append the rows of step s the file does not have yet (a step held in
 * part is compared with its rows there). */
int inv_write_step(inv_run *R, size_t s, dfle_error *err);
/* "chain.csv:123" for the row of walker k (0-based) at step s, or the
 * file's name alone for a row not read from it. */
void inv_row_place(const inv_run *R, size_t s, size_t k, char *buf, size_t cap);

/* invert_health.c */
/* Scratch of the walker-health test. */
typedef struct inv_health {
    size_t K;
    unsigned char *flag;  /* K: stranded                              */
    double *acc;          /* K: acceptance over the window            */
    double *lp_med;       /* K: median log posterior over the window  */
    double acc_ref;       /* the walkers' median acceptance           */
    double lp_ref;        /* the median of their medians              */
    double drop;          /* the drop that strands (d's chi-square)   */
    double *scratch;      /* max(K, steps + 1)                        */
} inv_health;
/* Steps after burn-in below which no walker is called stranded: at
 * the walkers' median acceptance of 0.25, a walker that never moves in
 * 50 steps has probability 0.75^50 = 6e-7, the first count the 1e-6
 * binomial test can call improbable; fewer steps may also be the
 * ensemble still walking in from the prior. */
#define INV_HEALTH_MIN_STEPS 50
int inv_health_init(inv_health *h, size_t K, size_t d, size_t steps);
void inv_health_free(inv_health *h);
/* Flag the walkers stranded over steps s0 .. s1 (1 <= s0 <= s1) of r;
 * the number flagged. */
size_t inv_stranded(const dfle_invert_result *r, size_t s0, size_t s1, inv_health *h);
/* Whether the stranded walkers are checked (and moved) at the end of
 * step s of a chain with this burn-in: steps 25, 50, 100, ... <= burn. */
int inv_check_step(size_t s, size_t burn);
/* Move the walkers stranded over the steps (s/2, s] onto healthy
 * walkers' positions at step s (rows of step s in R->r filled; lp and ll
 * the walkers' exact log posterior and likelihood, updated).  Returns
 * how many were moved (0 when none is stranded, or too many are: the
 * ensemble is still walking in). */
size_t inv_move_stranded(inv_run *R, size_t s, double *lp, double *ll, inv_health *h);
/* The stranded walkers after burn-in and the moves of the chain, into
 * r (its summaries there), with warnings.  0, or -1 if memory
 * ran out. */
int inv_health_report(inv_run *R);

/* invert_bounds.c: the marginals held by a prior bound, into
 * r->bounded, with warnings.  0, or -1 if memory ran out. */
int inv_bounds(inv_run *R);

/* invert_summary.c: the summaries and warnings of a complete chain (or
 * the warning that it is not). */
int inv_summarize(inv_run *R);
/* Add a warning (a sentence) to r: 0, or -1 if memory ran out. */
int inv_warn(dfle_invert_result *r, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

#endif
