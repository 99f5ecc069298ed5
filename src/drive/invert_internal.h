/*
 * invert_internal.h - what the files of the inversion driver share (not
 * installed): invert_run.c (the options, the starting ensemble, the
 * sampling loop on the pool), invert_chain.c (the chain file: its
 * lines, rows, resume) and invert_summary.c (the samples after burn-in
 * summarised, the diagnostics).
 */
#ifndef DFLE_INVERT_INTERNAL_H
#define DFLE_INVERT_INTERNAL_H

#include "dfle/ensemble.h"
#include "dfle/invert_run.h"
#include "drive/drive_internal.h"

/* A run: the options with their defaults resolved, and the result it
 * fills (dfle_invert, invert_run.h). */
typedef struct inv_run {
    dfle_invert_opts o;     /* walkers and burn resolved               */
    dfle_invert_result *r;
    dfle_ens_file *file;    /* the chain file, open for appending      */
    dfle_text row;          /* one formatted row                       */
} inv_run;
struct dfle_invert {
    inv_run R;
};

/* invert_run.c: the options checked, defaults resolved into *res. */
int inv_resolve(const dfle_invert_opts *o, dfle_invert_opts *res, dfle_error *err);

/* invert_chain.c */
/* Open (or resume) the chain file of R->o.out, reading back the steps
 * it holds; R->r->have set.  A status with err ("invert: ..."). */
int inv_open_chain(inv_run *R, dfle_error *err);
/* Read the chain in R->o.out into R->r (no lock, no writing): have set. */
int inv_read_chain(inv_run *R, const char *path, dfle_error *err);
/* Append the rows of step s the file does not have yet. */
int inv_write_step(inv_run *R, size_t s, dfle_error *err);

/* invert_summary.c: the summaries and warnings of a complete chain (or
 * the warning that it is not). */
int inv_summarize(dfle_invert_result *r);

#endif
