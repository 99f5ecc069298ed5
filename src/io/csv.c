/*
 * csv.c - reader for numeric tables with a header line (dfle/csv.h has
 * the rules).  It exists so that PAWN and the ensemble tools can read
 * back the tables dfle and other tools write, with errors that point at
 * the file and line, not just "bad input".
 *
 * The whole file is read into memory and parsed line by line; columns
 * grow by doubling.  Nothing is printed; every failure frees what was
 * built and returns a status with a message.
 */
#include "dfle/csv.h"

#include "dfle/file.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define BAD_TEXT_MAX 40

void dfle_csv_free(dfle_csv *csv)
{
    if (csv == NULL)
        return;
    for (size_t j = 0; j < csv->ncols; j++) {
        if (csv->names != NULL)
            free(csv->names[j]);
        if (csv->cols != NULL)
            free(csv->cols[j]);
        if (csv->bad_text != NULL)
            free(csv->bad_text[j]);
    }
    free(csv->names);
    free(csv->cols);
    free(csv->bad_text);
    free(csv->bad_line);
    free(csv->line);
    free(csv->source);
    free(csv);
}

static char *copy_span(const char *s, size_t len)
{
    char *c = malloc(len + 1);
    if (c != NULL) {
        memcpy(c, s, len);
        c[len] = '\0';
    }
    return c;
}

/* One line being split into fields: the field text is copied into a
 * growable buffer (quotes resolved). */
typedef struct field_buf {
    char *s;
    size_t len, cap;
} field_buf;

static int buf_put(field_buf *b, char c)
{
    if (b->len + 1 >= b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 64;
        char *s = realloc(b->s, cap);
        if (s == NULL)
            return -1;
        b->s = s;
        b->cap = cap;
    }
    b->s[b->len++] = c;
    b->s[b->len] = '\0';
    return 0;
}

static int is_blank(char c)
{
    return c == ' ' || c == '\t';
}

/* Read the field starting at *p (line ends at `end`) into b; *p moves
 * past the field and its comma.  *last is set when the line has no more
 * fields.  Returns 0, -1 (out of memory) or -2 (unterminated quote). */
static int next_field(const char **p, const char *end, field_buf *b, int *last)
{
    const char *q = *p;

    if (b->s == NULL) {
        if ((b->s = malloc(64)) == NULL)
            return -1;
        b->cap = 64;
    }
    b->len = 0;
    b->s[0] = '\0';
    while (q < end && is_blank(*q))
        q++;
    if (q < end && *q == '"') {
        q++;
        for (;;) {
            if (q >= end)
                return -2;
            if (*q == '"') {
                if (q + 1 < end && q[1] == '"') {
                    if (buf_put(b, '"') != 0)
                        return -1;
                    q += 2;
                    continue;
                }
                q++;
                break;
            }
            if (buf_put(b, *q++) != 0)
                return -1;
        }
        while (q < end && *q != ',')
            q++; /* text after the closing quote is ignored (only blanks expected) */
    } else {
        while (q < end && *q != ',')
            if (buf_put(b, *q++) != 0)
                return -1;
        while (b->len > 0 && is_blank(b->s[b->len - 1]))
            b->s[--b->len] = '\0';
    }
    if (q < end && *q == ',') {
        *last = 0;
        q++;
    } else {
        *last = 1;
    }
    *p = q;
    return 0;
}

/* Number of a field: 1 and *v on success, 0 if it is not a number. */
static int parse_number(const char *s, double *v)
{
    char *endp;

    if (s[0] == '\0') {
        *v = NAN;
        return 1;
    }
    *v = strtod(s, &endp);
    /* Overflow gives +-HUGE_VAL and underflow a tiny value: both are what
     * the text says, so ERANGE is not an error here. */
    return *endp == '\0';
}

typedef struct parser {
    dfle_csv *csv;
    size_t cap;        /* row capacity of the columns */
    field_buf field;
    dfle_error *err;
} parser;

static int oom(parser *ps)
{
    return dfle_error_set(ps->err, DFLE_ENOMEM, "%s: out of memory", ps->csv->source);
}

static int parse_header(parser *ps, const char *p, const char *end, size_t lineno)
{
    dfle_csv *csv = ps->csv;
    size_t cap = 0;
    int last = 0, st;

    while (!last) {
        if ((st = next_field(&p, end, &ps->field, &last)) == -1)
            return oom(ps);
        if (st == -2)
            return dfle_error_set(ps->err, DFLE_EINVAL, "%s:%zu: unterminated quote in header",
                                  csv->source, lineno);
        if (ps->field.len == 0)
            return dfle_error_set(ps->err, DFLE_EINVAL,
                                  "%s:%zu: column %zu of the header has no name", csv->source,
                                  lineno, csv->ncols + 1);
        for (size_t j = 0; j < csv->ncols; j++)
            if (strcmp(csv->names[j], ps->field.s) == 0)
                return dfle_error_set(ps->err, DFLE_EINVAL,
                                      "%s:%zu: column name '%s' appears twice in the header",
                                      csv->source, lineno, ps->field.s);
        if (csv->ncols == cap) {
            size_t ncap = cap ? 2 * cap : 8;
            char **names = realloc(csv->names, ncap * sizeof *names);
            if (names == NULL)
                return oom(ps);
            csv->names = names;
            cap = ncap;
        }
        if ((csv->names[csv->ncols] = copy_span(ps->field.s, ps->field.len)) == NULL)
            return oom(ps);
        csv->ncols++;
    }
    csv->cols = calloc(csv->ncols, sizeof *csv->cols);
    csv->bad_line = calloc(csv->ncols, sizeof *csv->bad_line);
    csv->bad_text = calloc(csv->ncols, sizeof *csv->bad_text);
    if (csv->cols == NULL || csv->bad_line == NULL || csv->bad_text == NULL)
        return oom(ps);
    return DFLE_OK;
}

static int grow_rows(parser *ps)
{
    dfle_csv *csv = ps->csv;
    size_t ncap = ps->cap ? 2 * ps->cap : 256;
    size_t *line = realloc(csv->line, ncap * sizeof *line);

    if (line == NULL)
        return oom(ps);
    csv->line = line;
    for (size_t j = 0; j < csv->ncols; j++) {
        double *c = realloc(csv->cols[j], ncap * sizeof *c);
        if (c == NULL)
            return oom(ps);
        csv->cols[j] = c;
    }
    ps->cap = ncap;
    return DFLE_OK;
}

static int parse_row(parser *ps, const char *p, const char *end, size_t lineno)
{
    dfle_csv *csv = ps->csv;
    size_t row = csv->nrows, j = 0;
    int last = 0, st;

    if (row == ps->cap && (st = grow_rows(ps)) != DFLE_OK)
        return st;
    while (!last) {
        double v;
        if ((st = next_field(&p, end, &ps->field, &last)) == -1)
            return oom(ps);
        if (st == -2)
            return dfle_error_set(ps->err, DFLE_EINVAL, "%s:%zu: unterminated quote in field %zu",
                                  csv->source, lineno, j + 1);
        if (j >= csv->ncols) {
            j++;
            continue; /* counted for the message below */
        }
        if (!parse_number(ps->field.s, &v)) {
            v = NAN;
            if (csv->bad_line[j] == 0) {
                size_t len = ps->field.len < BAD_TEXT_MAX ? ps->field.len : BAD_TEXT_MAX;
                csv->bad_line[j] = lineno;
                if ((csv->bad_text[j] = copy_span(ps->field.s, len)) == NULL)
                    return oom(ps);
            }
        }
        csv->cols[j][row] = v;
        j++;
    }
    if (j != csv->ncols)
        return dfle_error_set(ps->err, DFLE_EINVAL,
                              "%s:%zu: %zu fields, but the header has %zu columns", csv->source,
                              lineno, j, csv->ncols);
    csv->line[row] = lineno;
    csv->nrows++;
    return DFLE_OK;
}

static int skip_line(const char *p, const char *end)
{
    while (p < end && (is_blank(*p) || *p == '\r'))
        p++;
    return p == end || *p == '#';
}

int dfle_csv_parse(const char *text, size_t len, const char *source, dfle_csv **out,
                   dfle_error *err)
{
    parser ps;
    const char *p = text, *stop = text + len;
    size_t lineno = 0;
    int have_header = 0, st = DFLE_OK;

    if (out == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "csv: output pointer is NULL");
    *out = NULL;
    if (text == NULL && len > 0)
        return dfle_error_set(err, DFLE_EINVAL, "csv: text is NULL");
    memset(&ps, 0, sizeof ps);
    ps.err = err;
    ps.csv = calloc(1, sizeof *ps.csv);
    if (ps.csv == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "csv: out of memory");
    if (source == NULL)
        source = "csv";
    ps.csv->source = copy_span(source, strlen(source));
    if (ps.csv->source == NULL) {
        dfle_csv_free(ps.csv);
        return dfle_error_set(err, DFLE_ENOMEM, "csv: out of memory");
    }
    /* A UTF-8 byte-order mark (spreadsheets write one) is not part of
     * the first column's name. */
    if (stop - p >= 3 && memcmp(p, "\xEF\xBB\xBF", 3) == 0)
        p += 3;
    while (p < stop && st == DFLE_OK) {
        const char *nl = memchr(p, '\n', (size_t)(stop - p));
        const char *end = nl != NULL ? nl : stop;
        const char *next = nl != NULL ? nl + 1 : stop;
        lineno++;
        /* C strings end at NUL: a field "7\0junk" would read as 7. */
        if (memchr(p, '\0', (size_t)(end - p)) != NULL) {
            st = dfle_error_set(err, DFLE_EINVAL, "%s:%zu: contains a NUL byte (a binary or "
                                "damaged file?)", ps.csv->source, lineno);
            break;
        }
        if (end > p && end[-1] == '\r')
            end--;
        if (!skip_line(p, end)) {
            if (!have_header) {
                st = parse_header(&ps, p, end, lineno);
                have_header = 1;
            } else {
                st = parse_row(&ps, p, end, lineno);
            }
        }
        p = next;
    }
    if (st == DFLE_OK && !have_header)
        st = dfle_error_set(err, DFLE_EINVAL, "%s: no header line (the file is empty)",
                            ps.csv->source);
    free(ps.field.s);
    if (st != DFLE_OK) {
        dfle_csv_free(ps.csv);
        return st;
    }
    *out = ps.csv;
    return DFLE_OK;
}

int dfle_csv_read(const char *path, dfle_csv **out, dfle_error *err)
{
    char *text;
    size_t len;
    int st;

    if (out == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "csv: output pointer is NULL");
    *out = NULL;
    if (path == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "csv: path is NULL");
    if ((st = dfle_file_read_all(path, DFLE_FILE_READ_MAX, &text, &len, err)) != DFLE_OK)
        return st;
    st = dfle_csv_parse(text, len, path, out, err);
    free(text);
    return st;
}

long dfle_csv_find(const dfle_csv *csv, const char *name)
{
    for (size_t j = 0; csv != NULL && name != NULL && j < csv->ncols; j++)
        if (strcmp(csv->names[j], name) == 0)
            return (long)j;
    return -1;
}

int dfle_csv_column(const dfle_csv *csv, const char *name, const double **col,
                    dfle_error *err)
{
    long j = dfle_csv_find(csv, name);

    if (j < 0) {
        char list[300];
        size_t used = 0;
        list[0] = '\0';
        for (size_t k = 0; csv != NULL && k < csv->ncols && used < sizeof list; k++)
            used += (size_t)snprintf(list + used, sizeof list - used, "%s%s", k ? ", " : "",
                                     csv->names[k]);
        return dfle_error_set(err, DFLE_EINVAL, "%s: no column '%s' (columns: %s)",
                              csv != NULL ? csv->source : "csv", name != NULL ? name : "(null)",
                              list);
    }
    if (csv->bad_line[j] != 0)
        return dfle_error_set(err, DFLE_EINVAL,
                              "%s:%zu: column '%s' is not numeric ('%s' is not a number)",
                              csv->source, csv->bad_line[j], name, csv->bad_text[j]);
    *col = csv->cols[j];
    return DFLE_OK;
}
