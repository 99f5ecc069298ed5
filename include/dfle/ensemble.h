/*
 * ensemble.h - the on-disk side of ensemble runs: result files that
 * grow row by row, resume after a kill, and merge from shards.
 *
 * An ensemble file is a CSV table (read back by dfle_csv_read and
 * dfle.pawn) laid out as
 *
 *     # <meta line: what ensemble this is, e.g. "# dfle.ensemble n=64 seed=1">
 *     # <more comment lines, e.g. "# dfle: 0.1.0", "# units: A_df=m^2">
 *     index,<columns...>
 *     17,<fields...>
 *     3,<fields...>
 *
 * one row per finished sample, in any order while a run is going on;
 * the first field is the 1-based sample index.  Rows are appended and
 * flushed one at a time, so a killed run leaves complete rows and at
 * most one truncated last line, which reopening discards.  When a run
 * has finished, the file is rewritten sorted by index (through a
 * temporary file and rename), so that the finished file is the same,
 * byte for byte, whatever the number of workers, ranks or shards.
 *
 * The row text itself is the caller's (the ensemble driver,
 * ensemble_run.h, formats it); this layer only knows the index field,
 * the lines above the rows and lines.  Appending is thread-safe.  The meta and header lines identify
 * the ensemble (resume and gather compare them); the comment lines
 * between them only describe it (the version that started the file,
 * units, options), are written when a file is created and kept as they
 * are by resume, rewrite and gather (which takes the first file's), so
 * they must be the same for every run of the ensemble (no date) for the
 * byte-for-byte guarantees to hold.
 */
#ifndef DFLE_ENSEMBLE_H
#define DFLE_ENSEMBLE_H

#include <stddef.h>

#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The rows of an ensemble file, sorted by index. */
typedef struct dfle_ens_table {
    char *meta;      /* first line, starting with '#'               */
    char *comments;  /* the '#' lines after it, joined by '\n', or NULL */
    char *header;    /* column line, starting with "index,"         */
    size_t nrows;
    size_t *index;   /* nrows 1-based sample indices, increasing    */
    char **rows;     /* nrows complete lines (no newline), index first */
    long valid_bytes; /* length of the file up to its last complete line */
    size_t *line;    /* nrows: the file line of each row (1-based), for
                      * messages; NULL in a table not read from a file */
} dfle_ens_table;

/* Read an ensemble file.  A last line without its newline (a run killed
 * while writing) is left out.  DFLE_EIO if it cannot be read,
 * DFLE_EINVAL ("path:line: ...") for a malformed file or a sample index
 * appearing twice, DFLE_ENOMEM. */
int dfle_ens_table_read(const char *path, dfle_ens_table **out, dfle_error *err);
void dfle_ens_table_free(dfle_ens_table *t); /* accepts NULL */

/* Write the table to `path` (meta, header, rows in index order) through
 * `path`.tmp and rename, so readers never see half a file. */
int dfle_ens_table_write(const dfle_ens_table *t, const char *path, dfle_error *err);

/* An ensemble file open for appending. */
typedef struct dfle_ens_file dfle_ens_file;

/* Open `path` for the samples 1..n of the ensemble described by `meta`
 * and `header` (single lines, no newline; meta starts with '#'), with
 * the comment lines `comments` (each starting with '#', joined by '\n';
 * may be NULL).  A missing file is created with those lines.  An
 * existing file is resumed when `resume` is set: its meta and header must equal the
 * given ones (else DFLE_EINVAL: the file belongs to another ensemble),
 * its indices must lie in 1..n, a truncated last line is cut off, and
 * its rows count as done.  Without `resume` an existing file is
 * replaced. */
int dfle_ens_file_open(const char *path, const char *meta, const char *comments,
                       const char *header, size_t n, int resume, dfle_ens_file **out,
                       dfle_error *err);

/* Whether sample `index` (1-based) already has a row; rows done. */
int dfle_ens_file_done(const dfle_ens_file *f, size_t index);
size_t dfle_ens_file_ndone(const dfle_ens_file *f);

/* Append one row (a line without newline whose first field is `index`)
 * and flush it.  Thread-safe.  DFLE_EINVAL for an index out of range or
 * already done, DFLE_EIO if writing fails. */
int dfle_ens_file_append(dfle_ens_file *f, size_t index, const char *row, dfle_error *err);

/* Close the file; with `sort`, rewrite it in index order (see top).
 * Frees f in every case (accepts NULL). */
int dfle_ens_file_close(dfle_ens_file *f, int sort, dfle_error *err);

/* Merge ensemble files (shards) into `out`, sorted by index.  All must
 * have the same meta and header lines; a sample present in two files
 * must have identical rows (else DFLE_EINVAL naming both files).
 * *nrows receives the number of rows written (may be NULL). */
int dfle_ens_gather(const char *const *files, size_t nfiles, const char *out, size_t *nrows,
                    dfle_error *err);

/* Hand out sample indices 1..n to workers: those not yet done and in
 * shard `shard_i` of `shard_n` (1-based; the samples with
 * (index - 1) mod shard_n == shard_i - 1; shard_n = 0 or 1: all).
 * Thread-safe: each index is returned once.  `done` may be NULL. */
typedef struct dfle_ens_queue dfle_ens_queue;
int dfle_ens_queue_new(size_t n, size_t shard_i, size_t shard_n, const dfle_ens_file *done,
                       size_t limit, dfle_ens_queue **out, dfle_error *err);
void dfle_ens_queue_free(dfle_ens_queue *q);
/* Number of samples the queue will hand out in all. */
size_t dfle_ens_queue_total(const dfle_ens_queue *q);
/* Next index into *index: 1, or 0 when the queue is empty or stopped. */
int dfle_ens_queue_next(dfle_ens_queue *q, size_t *index);
/* Give back an index handed out whose sample will not have a row (its
 * worker was lost): dfle_ens_queue_next hands it out again, before any
 * other.  Thread-safe.  DFLE_ENOMEM. */
int dfle_ens_queue_give_back(dfle_ens_queue *q, size_t index, dfle_error *err);
/* Make every later dfle_ens_queue_next return 0. */
void dfle_ens_queue_stop(dfle_ens_queue *q);
/* Indices dfle_ens_queue_next would still hand out (0 once stopped).
 * Thread-safe. */
size_t dfle_ens_queue_pending(dfle_ens_queue *q);

/* Whether `index` belongs to shard shard_i of shard_n (rule above). */
int dfle_ens_in_shard(size_t index, size_t shard_i, size_t shard_n);

#ifdef __cplusplus
}
#endif
#endif
