/*
 * invert_chain.c - the chain as CSV rows: the identity line and header,
 * one row per walker and step written as the chain grows, read back to
 * resume or extend it.
 *
 * index = step K + walker (1-based walker), so the file layer of
 * ensembles (dfle/ensemble.h: streamed rows, a cut last line dropped on
 * reopening, the sorted atomic rewrite at the end) serves as it is.
 * Numbers carry 17 significant digits: they read back to the same
 * doubles, which is what lets a resumed chain continue bit for bit.
 */
#include "drive/invert_internal.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

const char *dfle_proposal_name(int proposal)
{
    static const char *const names[DFLE_PROPOSAL_N] = {
        "initial", "accepted", "rejected", "outside_prior", "not_converged", "invalid_profile",
        "error"};
    return proposal >= 0 && proposal < DFLE_PROPOSAL_N ? names[proposal] : "unknown";
}

int dfle_invert_identity(const dfle_invert_opts *opts, char **meta, char **header,
                         dfle_error *err)
{
    dfle_invert_opts o;
    dfle_text m, h;
    char buf[512];
    int st;

    *meta = *header = NULL;
    if ((st = inv_resolve(opts, &o, err)) != DFLE_OK)
        return st;
    dfle_text_init(&m);
    dfle_text_printf(&m, "# dfle.invert v1 seed=%lu walkers=%zu a=%.17g params=", o.seed,
                     o.walkers, o.a);
    for (size_t j = 0; j < o.d; j++) {
        if (j > 0)
            dfle_text_str(&m, ";");
        dfle_text_str(&m, o.names[j]);
        dfle_text_str(&m, ":");
        dfle_prior_describe(&o.priors[j], buf, sizeof buf);
        dfle_text_str(&m, buf);
    }
    if (o.identity != NULL)
        dfle_text_str(&m, o.identity);
    dfle_text_init(&h);
    dfle_text_str(&h, "index,step,walker");
    for (size_t j = 0; j < o.d; j++) {
        dfle_text_str(&h, ",");
        dfle_text_str(&h, o.names[j]);
    }
    dfle_text_str(&h, ",log_post,log_like,proposal");
    *meta = dfle_text_take(&m);
    *header = dfle_text_take(&h);
    if (*meta == NULL || *header == NULL) {
        free(*meta);
        free(*header);
        *meta = *header = NULL;
        return dfle_error_set(err, DFLE_ENOMEM, "invert: out of memory");
    }
    return DFLE_OK;
}

/* ------------------------------------------------------------------ */
/* Rows.                                                               */

static int format_row(inv_run *R, size_t step, size_t k)
{
    const dfle_invert_result *r = R->r;
    const size_t K = r->walkers, d = r->d, at = step * K + k;
    dfle_text_clear(&R->row);
    dfle_text_printf(&R->row, "%zu,%zu,%zu", at + 1, step, k + 1);
    for (size_t j = 0; j < d; j++)
        dfle_text_printf(&R->row, ",%.17g", r->x[at * d + j]);
    dfle_text_printf(&R->row, ",%.17g,%.17g,%s", r->log_post[at], r->log_like[at],
                     dfle_proposal_name(r->proposal[at]));
    return R->row.oom ? -1 : 0;
}

int inv_write_step(inv_run *R, size_t s, dfle_error *err)
{
    const size_t K = R->r->walkers;
    int st;
    if (R->file == NULL)
        return DFLE_OK;
    for (size_t k = 0; k < K; k++) {
        size_t index = s * K + k + 1;
        if (dfle_ens_file_done(R->file, index))
            continue; /* a resumed step: the same row is there */
        if (format_row(R, s, k) != 0)
            return dfle_error_set(err, DFLE_ENOMEM, "invert: out of memory");
        if ((st = dfle_ens_file_append(R->file, index, R->row.s, err)) != DFLE_OK)
            return dfle_drive_prefix(err, "invert");
    }
    return DFLE_OK;
}

/* ------------------------------------------------------------------ */
/* Reading back.                                                       */

static int proposal_code(const char *s)
{
    for (int c = 0; c < DFLE_PROPOSAL_N; c++)
        if (strcmp(dfle_proposal_name(c), s) == 0)
            return c;
    return -1;
}

/* The next comma-separated number of *p. */
static int next_number(const char **p, double *v)
{
    char *end;
    errno = 0;
    *v = strtod(*p, &end);
    if (end == *p || (*end != ',' && *end != '\0'))
        return -1;
    *p = *end == ',' ? end + 1 : end;
    return 0;
}

int inv_read_chain(inv_run *R, const char *path, dfle_error *err)
{
    dfle_invert_result *r = R->r;
    const size_t K = r->walkers, d = r->d;
    dfle_ens_table *t = NULL;
    unsigned char *seen = NULL;
    int st;

    r->have = 0;
    if ((st = dfle_ens_table_read(path, &t, err)) != DFLE_OK)
        return dfle_drive_prefix(err, "invert");
    seen = calloc((r->steps + 1) * K, 1);
    if (seen == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "invert: out of memory");
        goto done;
    }
    for (size_t i = 0; i < t->nrows; i++) {
        const char *p = t->rows[i];
        double v, step, walker;
        size_t at;
        int c;
        if (next_number(&p, &v) != 0 || next_number(&p, &step) != 0 ||
            next_number(&p, &walker) != 0 || step < 0 || walker < 1 || walker > (double)K ||
            step != floor(step) || walker != floor(walker))
            goto bad;
        if (step > (double)r->steps)
            continue; /* a longer chain than asked for: its first steps serve */
        at = (size_t)step * K + (size_t)walker - 1;
        if (t->index[i] != at + 1)
            goto bad;
        for (size_t j = 0; j < d; j++)
            if (next_number(&p, &r->x[at * d + j]) != 0)
                goto bad;
        if (next_number(&p, &r->log_post[at]) != 0 || next_number(&p, &r->log_like[at]) != 0)
            goto bad;
        if ((c = proposal_code(p)) < 0)
            goto bad;
        r->proposal[at] = (unsigned char)c;
        seen[at] = 1;
        continue;
    bad:
        st = dfle_error_set(err, DFLE_EINVAL, "invert: %s: row %zu ('%.80s') is not a row of this "
                            "chain", path, t->index[i], t->rows[i]);
        goto done;
    }
    /* Complete steps from the start; a step cut short by a kill is redone
     * (its rows come out the same). */
    for (size_t s = 0; s <= r->steps; s++) {
        size_t k = 0;
        while (k < K && seen[s * K + k])
            k++;
        if (k < K)
            break;
        r->have = s + 1;
    }
    st = DFLE_OK;
done:
    free(seen);
    dfle_ens_table_free(t);
    return st;
}

/* The first setting in which two identity lines differ, as
 * "seed=3 in the file, seed=4 here". */
static void difference(const char *file, const char *mine, char *buf, size_t cap)
{
    const char *a = file, *b = mine;
    while (*a != '\0' && *b != '\0') {
        size_t la = strcspn(a, " "), lb = strcspn(b, " ");
        if (la != lb || strncmp(a, b, la) != 0) {
            snprintf(buf, cap, "%.*s in the file, %.*s here", (int)la, a, (int)lb, b);
            return;
        }
        a += la + (a[la] == ' ');
        b += lb + (b[lb] == ' ');
    }
    snprintf(buf, cap, "the file's first lines differ");
}

int inv_open_chain(inv_run *R, dfle_error *err)
{
    const char *path = R->o.out;
    size_t n = (R->o.steps + 1) * R->o.walkers;
    char *meta = NULL, *header = NULL;
    struct stat sb;
    int st;

    if ((st = dfle_invert_identity(&R->o, &meta, &header, err)) != DFLE_OK)
        return st;
    /* A longer chain in the file is fine (its first steps serve), so the
     * file's own length sets how many rows it may hold. */
    if (R->o.resume && stat(path, &sb) == 0 && S_ISREG(sb.st_mode) && sb.st_size > 0) {
        dfle_ens_table *t = NULL;
        dfle_error e;
        if (dfle_ens_table_read(path, &t, &e) != DFLE_OK) {
            st = dfle_error_set(err, DFLE_EINVAL,
                                "invert: %s is not a chain of dfle.invert (%s); remove it, pass "
                                "resume = false, or choose another 'out'", path, e.msg);
            goto done;
        }
        if (t->nrows > 0 && t->index[t->nrows - 1] > n)
            n = t->index[t->nrows - 1];
        if (strcmp(t->meta, meta) != 0 || strcmp(t->header, header) != 0) {
            char why[400];
            difference(t->meta, meta, why, sizeof why);
            st = dfle_error_set(err, DFLE_EINVAL,
                                "invert: %s holds another inversion's chain (%s); remove it, "
                                "pass resume = false, or choose another 'out'", path, why);
            dfle_ens_table_free(t);
            goto done;
        }
        dfle_ens_table_free(t);
    }
    if ((st = dfle_ens_file_open(path, meta, NULL, header, n, R->o.resume, &R->file, err)) !=
        DFLE_OK) {
        dfle_drive_prefix(err, "invert");
        goto done;
    }
    if (dfle_ens_file_ndone(R->file) > 0)
        st = inv_read_chain(R, path, err);
done:
    free(meta);
    free(header);
    return st;
}
