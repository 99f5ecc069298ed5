/*
 * invert_chain.c - the chain as CSV rows: the identity line, the lines
 * that describe the file (version, date, command, units) and the header,
 * one row per walker and step written as the chain grows, read back to
 * resume or extend it, and checked as it is read.
 *
 * index = step K + walker (1-based walker), so the file layer of
 * ensembles (dfle/ensemble.h: streamed rows, a cut last line dropped on
 * reopening, the sorted atomic rewrite at the end) serves as it is.
 * Positions have 12 significant digits and are the sampler's own values
 * (invert_run.c rounds every proposal to them), so they read back to the
 * same doubles: that is what lets a resumed chain continue bit for bit.
 *
 * A file is text anyone can edit, and a resume continues from what it
 * says; so every row is checked before a chain is built on it, and a
 * file that fails is refused naming its line (invert_run.h lists the
 * checks; the last step's log densities are recomputed by invert_run.c).
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
        "error", "moved"};
    return proposal >= 0 && proposal < DFLE_PROPOSAL_N ? names[proposal] : "unknown";
}

double inv_round(double v, int digits)
{
    char buf[40];
    if (!isfinite(v))
        return v;
    snprintf(buf, sizeof buf, "%.*g", digits, v);
    return strtod(buf, NULL);
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
    dfle_text_printf(&m, "# dfle.invert v2 seed=%lu walkers=%zu a=%.17g params=", o.seed,
                     o.walkers, o.a);
    for (size_t j = 0; j < o.d; j++) {
        if (j > 0)
            dfle_text_str(&m, ";");
        dfle_text_str(&m, o.names[j]);
        dfle_text_str(&m, ":");
        dfle_prior_describe(&o.priors[j], buf, sizeof buf);
        dfle_text_str(&m, buf);
    }
    /* Moving stranded walkers changes the chain, so it is part of what
     * the chain is; the steps it looks at follow burn (invert_health.c). */
    if (!o.move_stranded)
        dfle_text_str(&m, " moves=off");
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

/* The lines between the identity and the header of a new file: the
 * version and date, what opts.describe says (the command, ...), the
 * units of the columns; joined by '\n' (malloc'd, NULL if out of memory). */
static char *comment_lines(const dfle_invert_opts *o)
{
    const size_t nc = o->d + 5;
    const char **names = calloc(2 * nc, sizeof *names), **units = names + nc;
    dfle_record *own = NULL;
    char *text = NULL, *line;
    size_t len = 0;
    FILE *fp = NULL;

    if (names == NULL || dfle_record_new(&own, NULL) != DFLE_OK) {
        free(names);
        return NULL;
    }
    /* A describe record that has its own stamp says it once. */
    if (o->describe == NULL)
        dfle_record_stamp(own);
    names[0] = "index", units[0] = "-";
    names[1] = "step", units[1] = "-";
    names[2] = "walker", units[2] = "-";
    for (size_t j = 0; j < o->d; j++) {
        names[3 + j] = o->names[j];
        units[3 + j] = o->units != NULL ? o->units[j] : NULL;
    }
    names[3 + o->d] = "log_post", units[3 + o->d] = "-";
    names[4 + o->d] = "log_like", units[4 + o->d] = "-";
    if (dfle_record_status(own, NULL) == DFLE_OK &&
        (o->describe == NULL || dfle_record_status(o->describe, NULL) == DFLE_OK))
        fp = open_memstream(&text, &len);
    if (fp != NULL) {
        dfle_record_write_comments(own, fp);
        if (o->describe != NULL)
            dfle_record_write_comments(o->describe, fp);
        if ((line = dfle_units_line(names, units, nc)) != NULL)
            fprintf(fp, "%s\n", line);
        free(line);
        if (fclose(fp) != 0) {
            free(text);
            text = NULL;
        }
    }
    if (text != NULL && len > 0 && text[len - 1] == '\n')
        text[len - 1] = '\0';
    dfle_record_free(own);
    free(names);
    return text;
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
        dfle_text_printf(&R->row, ",%.*g", INV_X_DIGITS, r->x[at * d + j]);
    dfle_text_printf(&R->row, ",%.*g,%.*g,%s", INV_LP_DIGITS, r->log_post[at], INV_LP_DIGITS,
                     r->log_like[at], dfle_proposal_name(r->proposal[at]));
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
        int done = dfle_ens_file_done(R->file, index);
        const char *was = R->partial != NULL && s == R->partial_step ? R->partial[k] : NULL;
        if (done && was == NULL)
            continue; /* a resumed step: the same row is there */
        if (format_row(R, s, k) != 0)
            return dfle_error_set(err, DFLE_ENOMEM, "invert: out of memory");
        if (done) {
            /* A step the file holds in part, redone: its rows must come
             * out as they are (they stay in the file). */
            if (strcmp(was, R->row.s) != 0) {
                char place[300];
                inv_row_place(R, s, k, place, sizeof place);
                return dfle_error_set(err, DFLE_EINVAL,
                                      "invert: %s: step %zu, walker %zu: the row in the file "
                                      "('%.100s') is not what the step gives when run again "
                                      "('%.100s'): the file was damaged or edited, or the "
                                      "model changed; remove it, pass resume = false, or choose "
                                      "another 'out'", place, s, k + 1, was, R->row.s);
            }
            continue;
        }
        if ((st = dfle_ens_file_append(R->file, index, R->row.s, err)) != DFLE_OK)
            return dfle_drive_prefix(err, "invert");
    }
    return DFLE_OK;
}

static void forget_partial(inv_run *R)
{
    if (R->partial != NULL)
        for (size_t k = 0; k < R->r->walkers; k++)
            free(R->partial[k]);
    free(R->partial);
    R->partial = NULL;
}

void inv_row_place(const inv_run *R, size_t s, size_t k, char *buf, size_t cap)
{
    size_t line = R->line != NULL ? R->line[s * R->r->walkers + k] : 0;
    if (line > 0)
        snprintf(buf, cap, "%s:%zu", R->o.out, line);
    else
        snprintf(buf, cap, "%s", R->o.out != NULL ? R->o.out : "the chain");
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

/* Whether a and b agree to what the file's digits hold, for numbers
 * made of log densities of size `scale`. */
static int same_lp(double a, double b, double scale)
{
    return fabs(a - b) <= 1e-9 * (1 + fabs(a) + fabs(b) + scale);
}

/* What is wrong with the row of walker k at step s (read into r), or
 * NULL; the message in buf. */
static const char *check_row(const inv_run *R, size_t s, size_t k, char *buf, size_t cap)
{
    const dfle_invert_result *r = R->r;
    const size_t K = r->walkers, d = r->d, at = s * K + k;
    const double *x = r->x + at * d;
    const int p = r->proposal[at];
    double lprior = 0;
    int custom = 0;

    for (size_t j = 0; j < d; j++) {
        const dfle_prior *pr = &R->o.priors[j];
        double lpj = dfle_prior_logpdf(pr, x[j]);
        if (!isfinite(x[j])) {
            snprintf(buf, cap, "%s is %g, not a finite number", R->o.names[j], x[j]);
            return buf;
        }
        if (!(lpj > -INFINITY)) {
            snprintf(buf, cap, "%s = %.12g lies outside its prior [%.12g, %.12g]",
                     R->o.names[j], x[j], pr->lo, pr->hi);
            return buf;
        }
        lprior += lpj;
        custom |= pr->kind == DFLE_PRIOR_CUSTOM;
    }
    if (!isfinite(r->log_post[at]) || !isfinite(r->log_like[at])) {
        snprintf(buf, cap, "log_post (%g) and log_like (%g) must be finite: a walker stands "
                 "where the posterior is not zero", r->log_post[at], r->log_like[at]);
        return buf;
    }
    if (!custom && !same_lp(r->log_post[at] - r->log_like[at], lprior,
                            fabs(r->log_post[at]) + fabs(r->log_like[at]))) {
        snprintf(buf, cap, "log_post - log_like = %.10g, but the priors give %.10g at its "
                 "position", r->log_post[at] - r->log_like[at], lprior);
        return buf;
    }
    if ((s == 0) != (p == DFLE_PROPOSAL_INITIAL)) {
        snprintf(buf, cap, "proposal '%s' at step %zu (step 0 is 'initial', and only it)",
                 dfle_proposal_name(p), s);
        return buf;
    }
    if (s > 0 && p != DFLE_PROPOSAL_ACCEPTED && p != DFLE_PROPOSAL_MOVED) {
        /* not moved: the position and densities of the step before */
        const size_t was = at - K;
        if (memcmp(x, r->x + was * d, d * sizeof *x) != 0 ||
            r->log_post[at] != r->log_post[was] || r->log_like[at] != r->log_like[was]) {
            snprintf(buf, cap, "walker %zu's proposal was '%s', so it stayed, but its values "
                     "differ from those of step %zu", k + 1, dfle_proposal_name(p), s - 1);
            return buf;
        }
    }
    if (p == DFLE_PROPOSAL_MOVED) {
        /* a move takes another walker's position at the same step */
        size_t j;
        for (j = 0; j < K; j++)
            if (j != k && memcmp(x, r->x + (s * K + j) * d, d * sizeof *x) == 0 &&
                r->log_post[at] == r->log_post[s * K + j])
                break;
        if (j == K) {
            snprintf(buf, cap, "walker %zu was 'moved', but no other walker of step %zu stands "
                     "where it does", k + 1, s);
            return buf;
        }
    }
    return NULL;
}

int inv_read_chain(inv_run *R, const char *path, dfle_error *err)
{
    dfle_invert_result *r = R->r;
    const size_t K = r->walkers, d = r->d, rows = (r->steps + 1) * K;
    dfle_ens_table *t = NULL;
    size_t nread = 0;
    char why[400];
    int st;

    r->have = 0;
    forget_partial(R);
    if ((st = dfle_ens_table_read(path, &t, err)) != DFLE_OK)
        return dfle_drive_prefix(err, "invert");
    free(R->line);
    if ((R->line = calloc(rows, sizeof *R->line)) == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "invert: out of memory");
        goto done;
    }
    for (size_t i = 0; i < t->nrows; i++) {
        const char *p = t->rows[i];
        const size_t line = t->line != NULL ? t->line[i] : 0;
        double v, step, walker;
        size_t at;
        int c;
        if (t->index[i] != i + 1) {
            /* rows are written in order: a gap is a damaged file */
            size_t miss = i + 1;
            st = dfle_error_set(err, DFLE_EINVAL,
                                "invert: %s:%zu: the chain has a gap before this row (index "
                                "%zu): the rows of step %zu, walker %zu (index %zu) and on are "
                                "missing; a chain holds whole steps in order, so this file was "
                                "damaged or edited: remove it, pass resume = false, or choose "
                                "another 'out'",
                                path, line, t->index[i], (miss - 1) / K, (miss - 1) % K + 1, miss);
            goto done;
        }
        if (next_number(&p, &v) != 0 || next_number(&p, &step) != 0 ||
            next_number(&p, &walker) != 0 || step < 0 || walker < 1 || walker > (double)K ||
            step != floor(step) || walker != floor(walker))
            goto bad;
        if (step > (double)r->steps)
            break; /* a longer chain than asked for: its first steps serve */
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
        R->line[at] = line;
        nread = at + 1;
        continue;
    bad:
        st = dfle_error_set(err, DFLE_EINVAL, "invert: %s:%zu: '%.80s' is not a row of this "
                            "chain (index,step,walker, the %zu parameters, log_post, log_like, "
                            "proposal)", path, line, t->rows[i], d);
        goto done;
    }
    /* The steps read, whole; a step cut short by a kill is redone (its
     * rows come out the same).  Each row is checked against the priors
     * and the step before it. */
    for (size_t at = 0; at < nread; at++) {
        const size_t s = at / K, k = at % K;
        if (s * K + K > nread)
            break;
        if (check_row(R, s, k, why, sizeof why) != NULL) {
            st = dfle_error_set(err, DFLE_EINVAL, "invert: %s:%zu: step %zu, walker %zu: %s; "
                                "the file was damaged or edited: remove it, pass resume = false, "
                                "or choose another 'out'", path, R->line[at], s, k + 1, why);
            goto done;
        }
        if (k == K - 1)
            r->have = s + 1;
    }
    /* The rows of a step held in part, kept to compare with its redo. */
    if (nread > r->have * K) {
        R->partial_step = r->have;
        if ((R->partial = calloc(K, sizeof *R->partial)) == NULL) {
            st = dfle_error_set(err, DFLE_ENOMEM, "invert: out of memory");
            goto done;
        }
        for (size_t i = r->have * K; i < nread; i++)
            if ((R->partial[i % K] = malloc(strlen(t->rows[i]) + 1)) == NULL) {
                st = dfle_error_set(err, DFLE_ENOMEM, "invert: out of memory");
                goto done;
            } else {
                strcpy(R->partial[i % K], t->rows[i]);
            }
    }
    st = DFLE_OK;
done:
    dfle_ens_table_free(t);
    return st;
}

void inv_forget_partial(inv_run *R) { forget_partial(R); }

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
    char *meta = NULL, *header = NULL, *comments = NULL;
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
                                "invert: %s is not a chain of dfle.invert, or was damaged (%s); "
                                "remove it, pass resume = false, or choose another 'out'", path, e.msg);
            goto done;
        }
        if (t->nrows > 0 && t->index[t->nrows - 1] > n)
            n = t->index[t->nrows - 1];
        if (strncmp(t->meta, "# dfle.invert v1 ", 17) == 0) {
            st = dfle_error_set(err, DFLE_EINVAL,
                                "invert: %s is a chain of an earlier dfle (format v1, 17-digit "
                                "positions) that this one does not continue; remove it, pass "
                                "resume = false, or choose another 'out'", path);
            dfle_ens_table_free(t);
            goto done;
        }
        if (strncmp(t->meta, "# dfle.invert v2 ", 17) != 0) {
            /* not ours, or a format this dfle does not know */
            int other = strncmp(t->meta, "# dfle.invert v", 15) == 0;
            st = dfle_error_set(err, DFLE_EINVAL,
                                "invert: %s:1: '%.60s' is not %s: remove the file, pass resume "
                                "= false, or choose another 'out'", path, t->meta,
                                other ? "a chain format this dfle reads (v2)"
                                      : "the first line of a chain of dfle.invert");
            dfle_ens_table_free(t);
            goto done;
        }
        if (strcmp(t->meta, meta) == 0 && strcmp(t->header, header) != 0) {
            size_t line = 2;
            for (const char *c = t->comments; c != NULL && *c != '\0'; c++)
                line += *c == '\n';
            line += t->comments != NULL && t->comments[0] != '\0';
            st = dfle_error_set(err, DFLE_EINVAL,
                                "invert: %s:%zu: the columns '%.200s' are not this chain's "
                                "('%.200s'): the file was edited; remove it, pass resume = "
                                "false, or choose another 'out'", path, line, t->header, header);
            dfle_ens_table_free(t);
            goto done;
        }
        if (strcmp(t->meta, meta) != 0) {
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
    if ((comments = comment_lines(&R->o)) == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "invert: out of memory");
        goto done;
    }
    if ((st = dfle_ens_file_open(path, meta, comments, header, n, R->o.resume, &R->file, err)) !=
        DFLE_OK) {
        dfle_drive_prefix(err, "invert");
        goto done;
    }
    if (dfle_ens_file_ndone(R->file) > 0)
        st = inv_read_chain(R, path, err);
done:
    free(meta);
    free(header);
    free(comments);
    return st;
}
