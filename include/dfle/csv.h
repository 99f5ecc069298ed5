/*
 * csv.h - a small reader for numeric tables: one header line of column
 * names, then one row per line, fields separated by commas.
 *
 * Ensembles are written and exchanged as such tables; PAWN on given data
 * (dfle.pawn{file = ...}) reads them back.  Rules:
 *  - lines end in LF or CRLF; blank lines and lines whose first
 *    non-blank character is '#' are skipped (before the header too);
 *  - fields are trimmed of spaces and tabs; a field may be quoted
 *    ("a, b" or "say ""x"""), which allows commas in text columns;
 *  - every row has as many fields as the header;
 *  - a numeric field is anything strtod() reads completely (including
 *    nan, inf and C99 hex floats); an empty field is NaN (missing);
 *  - any other text is kept as NaN too, and the column remembers the
 *    first line where that happened: asking for that column by name then
 *    fails, naming file, line and text, while tables with text columns
 *    (a run's status, say) can still be read for their numeric ones.
 */
#ifndef DFLE_CSV_H
#define DFLE_CSV_H

#include <stddef.h>

#include "dfle/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dfle_csv {
    char *source;       /* file name (or label) used in messages          */
    size_t ncols;       /* columns in the header                          */
    size_t nrows;       /* data rows                                      */
    char **names;       /* ncols column names                             */
    double **cols;      /* ncols arrays of nrows values                   */
    size_t *line;       /* nrows: 1-based line number of each row         */
    size_t *bad_line;   /* ncols: first line with a non-numeric field, or 0 */
    char **bad_text;    /* ncols: that field (shortened), or NULL         */
} dfle_csv;

/* Read the file at `path`.  DFLE_EIO (cannot open or read), DFLE_EINVAL
 * ("path:line: ..." for malformed content), DFLE_ENOMEM. */
int dfle_csv_read(const char *path, dfle_csv **out, dfle_error *err);

/* Parse `len` bytes of CSV text; `source` names it in messages. */
int dfle_csv_parse(const char *text, size_t len, const char *source, dfle_csv **out,
                   dfle_error *err);

void dfle_csv_free(dfle_csv *csv); /* accepts NULL */

/* Index of the column named `name`, or -1. */
long dfle_csv_find(const dfle_csv *csv, const char *name);

/* The numeric column named `name` (nrows values) into *col.  DFLE_EINVAL
 * if there is no such column (the message lists the columns) or if it
 * holds text (the message gives the first such line). */
int dfle_csv_column(const dfle_csv *csv, const char *name, const double **col,
                    dfle_error *err);

#ifdef __cplusplus
}
#endif
#endif
