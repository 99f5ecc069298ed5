/*
 * ensemble.c - ensemble result files (streamed rows, resume, sorted
 * rewrite, gather of shards) and the thread-safe queue of sample indices.
 *
 * Kept free of Lua so that any driver (threads, MPI ranks, shards) uses
 * the same file rules; see dfle/ensemble.h for the format.
 */
#include "dfle/ensemble.h"

#include "dfle/file.h"

#include <assert.h>
#include <errno.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

struct dfle_ens_file {
    char *path;
    FILE *fp;
    size_t n;
    unsigned char *done; /* n flags */
    size_t ndone;
    pthread_mutex_t lock;
};

struct dfle_ens_queue {
    size_t n, shard_i, shard_n, limit, next, handed;
    const dfle_ens_file *done;
    size_t total;
    int stopped;
    /* Indices given back (a worker lost before their rows), handed out
     * again before the rest. */
    size_t *back, nback, capback;
    pthread_mutex_t lock;
};

static char *dup_range(const char *s, size_t len)
{
    char *p = malloc(len + 1);
    if (p != NULL) {
        memcpy(p, s, len);
        p[len] = '\0';
    }
    return p;
}

void dfle_ens_table_free(dfle_ens_table *t)
{
    if (t == NULL)
        return;
    for (size_t i = 0; i < t->nrows; i++)
        free(t->rows[i]);
    free(t->rows);
    free(t->index);
    free(t->line);
    free(t->meta);
    free(t->comments);
    free(t->header);
    free(t);
}

/* Whole file into memory: a regular file only (a device such as
 * /dev/zero would be read without end). */
static int slurp(const char *path, char **text, size_t *len, dfle_error *err)
{
    return dfle_file_read_all(path, DFLE_FILE_READ_MAX, text, len, err);
}

typedef struct row_ref {
    size_t index;
    char *row;
    size_t line;
} row_ref;

static int cmp_rows(const void *a, const void *b)
{
    const row_ref *x = a, *y = b;
    return x->index < y->index ? -1 : x->index > y->index;
}

/* The leading index field of a row: a whole number >= 1. */
static int parse_index(const char *row, size_t *index)
{
    char *end;
    unsigned long long v;
    if (row[0] < '1' || row[0] > '9')
        return 0;
    errno = 0;
    v = strtoull(row, &end, 10);
    if (errno != 0 || (*end != ',' && *end != '\0'))
        return 0;
    *index = (size_t)v;
    return 1;
}

int dfle_ens_table_read(const char *path, dfle_ens_table **out, dfle_error *err)
{
    char *text = NULL;
    size_t len = 0, pos = 0, line = 0, cap = 0;
    row_ref *refs = NULL;
    dfle_ens_table *t;
    int st;

    *out = NULL;
    if ((st = slurp(path, &text, &len, err)) != DFLE_OK)
        return st;
    t = calloc(1, sizeof *t);
    if (t == NULL) {
        free(text);
        return dfle_error_set(err, DFLE_ENOMEM, "%s: out of memory", path);
    }
    while (pos < len) {
        char *nl = memchr(text + pos, '\n', len - pos);
        size_t end, ll;
        if (nl == NULL)
            break; /* truncated last line: a killed writer */
        line++;
        end = (size_t)(nl - text);
        ll = end - pos;
        if (ll > 0 && text[pos + ll - 1] == '\r')
            ll--;
        text[pos + ll] = '\0';
        if (line == 1) {
            if (text[pos] != '#') {
                st = dfle_error_set(err, DFLE_EINVAL,
                                    "%s:1: not an ensemble file (no '# dfle.ensemble' line)", path);
                goto fail;
            }
            if ((t->meta = dup_range(text + pos, ll)) == NULL)
                goto nomem;
        } else if (t->header == NULL && text[pos] == '#') {
            /* More comment lines (version, units) before the header. */
            size_t have = t->comments != NULL ? strlen(t->comments) : 0;
            char *c = realloc(t->comments, have + ll + 2);
            if (c == NULL)
                goto nomem;
            if (have > 0)
                c[have++] = '\n';
            memcpy(c + have, text + pos, ll);
            c[have + ll] = '\0';
            t->comments = c;
        } else if (t->header == NULL) {
            if (strncmp(text + pos, "index,", 6) != 0) {
                st = dfle_error_set(err, DFLE_EINVAL,
                                    "%s:%zu: not an ensemble file (header must start with "
                                    "'index,')", path, line);
                goto fail;
            }
            if ((t->header = dup_range(text + pos, ll)) == NULL)
                goto nomem;
        } else if (ll > 0) {
            size_t idx;
            if (!parse_index(text + pos, &idx)) {
                st = dfle_error_set(err, DFLE_EINVAL, "%s:%zu: row does not start with a sample index",
                                    path, line);
                goto fail;
            }
            if (t->nrows == cap) {
                row_ref *nr = realloc(refs, (cap * 2 + 64) * sizeof *nr);
                if (nr == NULL)
                    goto nomem;
                refs = nr;
                cap = cap * 2 + 64;
            }
            refs[t->nrows].index = idx;
            refs[t->nrows].line = line;
            if ((refs[t->nrows].row = dup_range(text + pos, ll)) == NULL)
                goto nomem;
            t->nrows++;
        }
        pos = end + 1;
        t->valid_bytes = (long)pos;
    }
    if (t->meta == NULL || t->header == NULL) {
        st = dfle_error_set(err, DFLE_EINVAL, "%s: not an ensemble file (missing header lines)", path);
        goto fail;
    }
    if (t->nrows > 0)
        qsort(refs, t->nrows, sizeof *refs, cmp_rows);
    for (size_t i = 1; i < t->nrows; i++)
        if (refs[i].index == refs[i - 1].index) {
            st = dfle_error_set(err, DFLE_EINVAL, "%s:%zu: sample %zu appears twice (also line %zu)",
                                path, refs[i].line > refs[i - 1].line ? refs[i].line : refs[i - 1].line,
                                refs[i].index,
                                refs[i].line > refs[i - 1].line ? refs[i - 1].line : refs[i].line);
            goto fail;
        }
    t->index = malloc((t->nrows ? t->nrows : 1) * sizeof *t->index);
    t->rows = malloc((t->nrows ? t->nrows : 1) * sizeof *t->rows);
    t->line = malloc((t->nrows ? t->nrows : 1) * sizeof *t->line);
    if (t->index == NULL || t->rows == NULL || t->line == NULL)
        goto nomem;
    for (size_t i = 0; i < t->nrows; i++) {
        t->index[i] = refs[i].index;
        t->rows[i] = refs[i].row;
        t->line[i] = refs[i].line;
    }
    free(refs);
    free(text);
    *out = t;
    return DFLE_OK;
nomem:
    st = dfle_error_set(err, DFLE_ENOMEM, "%s: out of memory", path);
fail:
    for (size_t i = 0; i < t->nrows; i++)
        free(refs[i].row);
    t->nrows = 0;
    free(refs);
    free(text);
    dfle_ens_table_free(t);
    return st;
}

/* The lines above the rows: meta, comments (if any), header. */
static int write_head(FILE *fp, const char *meta, const char *comments, const char *header)
{
    if (comments != NULL && comments[0] != '\0')
        return fprintf(fp, "%s\n%s\n%s\n", meta, comments, header);
    return fprintf(fp, "%s\n%s\n", meta, header);
}

int dfle_ens_table_write(const dfle_ens_table *t, const char *path, dfle_error *err)
{
    dfle_file out;
    int st;

    if ((st = dfle_file_begin(&out, path, "ensemble", err)) != DFLE_OK)
        return st;
    write_head(out.fp, t->meta, t->comments, t->header);
    for (size_t i = 0; i < t->nrows; i++) {
        fputs(t->rows[i], out.fp);
        fputc('\n', out.fp);
    }
    return dfle_file_commit(&out, err);
}

static void file_free(dfle_ens_file *f)
{
    if (f == NULL)
        return;
    if (f->fp != NULL)
        fclose(f->fp);
    pthread_mutex_destroy(&f->lock);
    free(f->done);
    free(f->path);
    free(f);
}

int dfle_ens_file_open(const char *path, const char *meta, const char *comments,
                       const char *header, size_t n, int resume, dfle_ens_file **out,
                       dfle_error *err)
{
    dfle_ens_file *f;
    dfle_ens_table *t = NULL;
    struct stat sb;
    int st, fd = -1;

    *out = NULL;
    if (n == 0)
        return dfle_error_set(err, DFLE_EINVAL, "ensemble: n must be >= 1");
    if (meta[0] != '#' || strchr(meta, '\n') != NULL || strncmp(header, "index,", 6) != 0 ||
        strchr(header, '\n') != NULL)
        return dfle_error_set(err, DFLE_EINVAL, "ensemble: malformed meta or header line");
    for (const char *c = comments; c != NULL && *c != '\0'; c = strchr(c, '\n') + 1) {
        if (*c != '#')
            return dfle_error_set(err, DFLE_EINVAL, "ensemble: a comment line must start with '#'");
        if (strchr(c, '\n') == NULL)
            break;
    }
    f = calloc(1, sizeof *f);
    if (f == NULL || pthread_mutex_init(&f->lock, NULL) != 0) {
        free(f);
        return dfle_error_set(err, DFLE_ENOMEM, "%s: out of memory", path);
    }
    f->n = n;
    f->done = calloc(n, 1);
    f->path = dup_range(path, strlen(path));
    if (f->done == NULL || f->path == NULL) {
        file_free(f);
        return dfle_error_set(err, DFLE_ENOMEM, "%s: out of memory", path);
    }
    /* The file is locked before anything is read or written: two runs
     * with the same `out` would otherwise both resume from it and
     * interleave their rows (duplicates and torn lines).  The lock is the
     * descriptor's, so it goes with the process, however that ends. */
    fd = open(path, O_RDWR | O_CREAT, 0666);
    if (fd < 0) {
        st = dfle_error_set(err, DFLE_EIO, "%s: cannot open for writing: %s", path,
                            strerror(errno));
        goto fail;
    }
    if (fstat(fd, &sb) != 0 || !S_ISREG(sb.st_mode)) {
        st = dfle_error_set(err, DFLE_EINVAL, "%s: an ensemble's 'out' must be a regular file "
                            "(rows are appended and read back to resume), not a device or a "
                            "pipe", path);
        goto fail;
    }
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
        st = errno == EWOULDBLOCK
                 ? dfle_error_set(err, DFLE_EIO, "%s is being written by another run; wait for "
                                  "it to finish, or choose another 'out'", path)
                 : dfle_error_set(err, DFLE_EIO, "%s: cannot lock: %s", path, strerror(errno));
        goto fail;
    }
    if (resume && sb.st_size > 0) {
        if ((st = dfle_ens_table_read(path, &t, err)) != DFLE_OK)
            goto fail;
        if (strcmp(t->meta, meta) != 0 || strcmp(t->header, header) != 0) {
            st = dfle_error_set(err, DFLE_EINVAL,
                                "%s was written by a different ensemble (its first lines are "
                                "'%.120s' and '%.120s'); remove it, pass resume = false, or "
                                "choose another 'out'",
                                path, t->meta, t->header);
            goto fail;
        }
        for (size_t i = 0; i < t->nrows; i++) {
            if (t->index[i] < 1 || t->index[i] > n) {
                st = dfle_error_set(err, DFLE_EINVAL, "%s: sample index %zu is outside 1..%zu",
                                    path, t->index[i], n);
                goto fail;
            }
            f->done[t->index[i] - 1] = 1;
        }
        f->ndone = t->nrows;
        if (ftruncate(fd, t->valid_bytes) != 0) {
            st = dfle_error_set(err, DFLE_EIO, "%s: cannot cut the truncated last line: %s", path,
                                strerror(errno));
            goto fail;
        }
        dfle_ens_table_free(t);
        t = NULL;
        if (lseek(fd, 0, SEEK_END) < 0 || (f->fp = fdopen(fd, "a")) == NULL) {
            st = dfle_error_set(err, DFLE_EIO, "%s: cannot open for writing: %s", path,
                                strerror(errno));
            goto fail;
        }
        fd = -1; /* f->fp owns it */
    } else {
        if (ftruncate(fd, 0) != 0 || (f->fp = fdopen(fd, "w")) == NULL) {
            st = dfle_error_set(err, DFLE_EIO, "%s: cannot open for writing: %s", path,
                                strerror(errno));
            goto fail;
        }
        fd = -1;
        if (write_head(f->fp, meta, comments, header) < 0 || fflush(f->fp) != 0) {
            st = dfle_error_set(err, DFLE_EIO, "%s: cannot write: %s", path, strerror(errno));
            goto fail;
        }
    }
    *out = f;
    return DFLE_OK;
fail:
    if (fd >= 0)
        close(fd);
    dfle_ens_table_free(t);
    file_free(f);
    return st;
}

int dfle_ens_file_done(const dfle_ens_file *f, size_t index)
{
    return index >= 1 && index <= f->n && f->done[index - 1];
}

size_t dfle_ens_file_ndone(const dfle_ens_file *f) { return f->ndone; }

int dfle_ens_file_append(dfle_ens_file *f, size_t index, const char *row, dfle_error *err)
{
    size_t idx;
    int st = DFLE_OK;

    if (!parse_index(row, &idx) || idx != index || strchr(row, '\n') != NULL)
        return dfle_error_set(err, DFLE_EINVAL, "ensemble: row for sample %zu is malformed", index);
    if (index < 1 || index > f->n)
        return dfle_error_set(err, DFLE_EINVAL, "ensemble: sample %zu is outside 1..%zu", index, f->n);
    pthread_mutex_lock(&f->lock);
    if (f->done[index - 1]) {
        st = dfle_error_set(err, DFLE_EINVAL, "ensemble: sample %zu already has a row", index);
    } else if (fputs(row, f->fp) < 0 || fputc('\n', f->fp) == EOF || fflush(f->fp) != 0) {
        st = dfle_error_set(err, DFLE_EIO, "%s: cannot write: %s", f->path, strerror(errno));
    } else {
        f->done[index - 1] = 1;
        f->ndone++;
    }
    pthread_mutex_unlock(&f->lock);
    return st;
}

int dfle_ens_file_close(dfle_ens_file *f, int sort, dfle_error *err)
{
    dfle_ens_table *t = NULL;
    int st = DFLE_OK;

    if (f == NULL)
        return DFLE_OK;
    /* The sorted rewrite happens while the lock is held (it goes with
     * the descriptor fclose closes): a second run let in between would
     * lock the old file, which the rename then unlinks, and append its
     * rows where nobody reads them. */
    if (fflush(f->fp) != 0)
        st = dfle_error_set(err, DFLE_EIO, "%s: cannot write: %s", f->path, strerror(errno));
    if (st == DFLE_OK && sort && (st = dfle_ens_table_read(f->path, &t, err)) == DFLE_OK)
        st = dfle_ens_table_write(t, f->path, err);
    if (fclose(f->fp) != 0 && st == DFLE_OK)
        st = dfle_error_set(err, DFLE_EIO, "%s: cannot write: %s", f->path, strerror(errno));
    f->fp = NULL;
    dfle_ens_table_free(t);
    file_free(f);
    return st;
}

int dfle_ens_gather(const char *const *files, size_t nfiles, const char *out, size_t *nrows,
                    dfle_error *err)
{
    dfle_ens_table **t;
    dfle_ens_table merged = {0};
    size_t total = 0, k = 0;
    int st = DFLE_OK;

    if (nrows != NULL)
        *nrows = 0;
    if (nfiles == 0)
        return dfle_error_set(err, DFLE_EINVAL, "gather: no files given");
    t = calloc(nfiles, sizeof *t);
    if (t == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "gather: out of memory");
    for (size_t i = 0; i < nfiles && st == DFLE_OK; i++) {
        st = dfle_ens_table_read(files[i], &t[i], err);
        if (st == DFLE_OK && i > 0 &&
            (strcmp(t[i]->meta, t[0]->meta) != 0 || strcmp(t[i]->header, t[0]->header) != 0))
            st = dfle_error_set(err, DFLE_EINVAL,
                                "gather: %s and %s come from different ensembles (their first "
                                "lines differ)", files[0], files[i]);
        if (st == DFLE_OK)
            total += t[i]->nrows;
    }
    if (st == DFLE_OK) {
        row_ref *refs = malloc((total ? total : 1) * sizeof *refs);
        size_t *from = malloc((total ? total : 1) * sizeof *from);
        merged.index = malloc((total ? total : 1) * sizeof *merged.index);
        merged.rows = malloc((total ? total : 1) * sizeof *merged.rows);
        if (refs == NULL || from == NULL || merged.index == NULL || merged.rows == NULL) {
            st = dfle_error_set(err, DFLE_ENOMEM, "gather: out of memory");
        } else {
            size_t m = 0;
            for (size_t i = 0; i < nfiles; i++)
                for (size_t r = 0; r < t[i]->nrows; r++) {
                    refs[m].index = t[i]->index[r];
                    refs[m].row = t[i]->rows[r];
                    refs[m].line = i; /* file number, for messages */
                    m++;
                }
            qsort(refs, total, sizeof *refs, cmp_rows);
            for (size_t r = 0; r < total && st == DFLE_OK; r++) {
                if (k > 0 && merged.index[k - 1] == refs[r].index) {
                    if (strcmp(merged.rows[k - 1], refs[r].row) != 0)
                        st = dfle_error_set(err, DFLE_EINVAL,
                                            "gather: sample %zu differs between %s and %s",
                                            refs[r].index, files[from[k - 1]], files[refs[r].line]);
                    continue;
                }
                merged.index[k] = refs[r].index;
                merged.rows[k] = refs[r].row;
                from[k] = refs[r].line;
                k++;
            }
        }
        free(refs);
        free(from);
    }
    if (st == DFLE_OK) {
        merged.meta = t[0]->meta;
        merged.comments = t[0]->comments;
        merged.header = t[0]->header;
        merged.nrows = k;
        st = dfle_ens_table_write(&merged, out, err);
        if (st == DFLE_OK && nrows != NULL)
            *nrows = k;
    }
    free(merged.index);
    free(merged.rows);
    for (size_t i = 0; i < nfiles; i++)
        dfle_ens_table_free(t[i]);
    free(t);
    return st;
}

int dfle_ens_in_shard(size_t index, size_t shard_i, size_t shard_n)
{
    return shard_n <= 1 || (index - 1) % shard_n == shard_i - 1;
}

int dfle_ens_queue_new(size_t n, size_t shard_i, size_t shard_n, const dfle_ens_file *done,
                       size_t limit, dfle_ens_queue **out, dfle_error *err)
{
    dfle_ens_queue *q;

    *out = NULL;
    if (shard_n > 1 && (shard_i < 1 || shard_i > shard_n))
        return dfle_error_set(err, DFLE_EINVAL, "ensemble: shard %zu/%zu: need 1 <= i <= n",
                              shard_i, shard_n);
    q = calloc(1, sizeof *q);
    if (q == NULL || pthread_mutex_init(&q->lock, NULL) != 0) {
        free(q);
        return dfle_error_set(err, DFLE_ENOMEM, "ensemble: out of memory");
    }
    q->n = n;
    q->shard_i = shard_i;
    q->shard_n = shard_n;
    q->done = done;
    q->limit = limit;
    q->next = 1;
    for (size_t i = 1; i <= n; i++)
        if (dfle_ens_in_shard(i, shard_i, shard_n) && (done == NULL || !dfle_ens_file_done(done, i)))
            q->total++;
    if (limit > 0 && q->total > limit)
        q->total = limit;
    *out = q;
    return DFLE_OK;
}

void dfle_ens_queue_free(dfle_ens_queue *q)
{
    if (q == NULL)
        return;
    pthread_mutex_destroy(&q->lock);
    free(q->back);
    free(q);
}

size_t dfle_ens_queue_total(const dfle_ens_queue *q) { return q->total; }

int dfle_ens_queue_next(dfle_ens_queue *q, size_t *index)
{
    int got = 0;
    pthread_mutex_lock(&q->lock);
    if (!q->stopped && q->nback > 0) {
        *index = q->back[--q->nback];
        q->handed++;
        got = 1;
    }
    while (!got && !q->stopped && q->handed < q->total && q->next <= q->n) {
        size_t i = q->next++;
        if (dfle_ens_in_shard(i, q->shard_i, q->shard_n) &&
            (q->done == NULL || !dfle_ens_file_done(q->done, i))) {
            *index = i;
            q->handed++;
            got = 1;
            break;
        }
    }
    pthread_mutex_unlock(&q->lock);
    return got;
}

size_t dfle_ens_queue_pending(dfle_ens_queue *q)
{
    size_t n;
    pthread_mutex_lock(&q->lock);
    n = q->stopped ? 0 : q->total - q->handed;
    pthread_mutex_unlock(&q->lock);
    return n;
}

int dfle_ens_queue_give_back(dfle_ens_queue *q, size_t index, dfle_error *err)
{
    int st = DFLE_OK;
    pthread_mutex_lock(&q->lock);
    if (q->nback == q->capback) {
        size_t cap = q->capback > 0 ? 2 * q->capback : 16;
        size_t *b = realloc(q->back, cap * sizeof *b);
        if (b == NULL) {
            st = dfle_error_set(err, DFLE_ENOMEM, "ensemble: out of memory");
        } else {
            q->back = b;
            q->capback = cap;
        }
    }
    if (st == DFLE_OK) {
        assert(q->handed > 0 && index >= 1 && index <= q->n);
        q->back[q->nback++] = index;
        q->handed--;
    }
    pthread_mutex_unlock(&q->lock);
    return st;
}

void dfle_ens_queue_stop(dfle_ens_queue *q)
{
    pthread_mutex_lock(&q->lock);
    q->stopped = 1;
    pthread_mutex_unlock(&q->lock);
}
