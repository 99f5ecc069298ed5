/*
 * ensemble_run.c - dfle_ensemble_run (ensemble_run.h): the design, the
 * file's lines, the resumable file and the queue of samples it lacks,
 * the pool that evaluates them, and each result as a row.
 *
 * The row is the same text whichever worker, process or shard ran the
 * sample, so the sorted file is too.  The file rules themselves
 * (streaming, locking, resume, the sorted rewrite, gather) are the io
 * layer's (src/io/ensemble.c).
 */
#include "dfle/ensemble_run.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dfle/ensemble.h"
#include "drive/drive_internal.h"

#ifndef DFLE_VERSION
#define DFLE_VERSION "unknown"
#endif

void dfle_ensemble_opts_default(dfle_ensemble_opts *o)
{
    memset(o, 0, sizeof *o);
    o->seed = 1;
    o->resume = 1;
    o->workers = 1;
}

/* ------------------------------------------------------------------ */
/* The options.                                                        */

static int check_column(const char *what, const char *name, dfle_error *err)
{
    static const char *const reserved[] = {"index", "status", "reason"};
    if (name == NULL || name[0] == '\0' || strpbrk(name, ",\"\r\n =") != NULL)
        return dfle_error_set(err, DFLE_EINVAL,
                              "ensemble: %s name '%s' cannot be a CSV column (no commas, "
                              "quotes, spaces, '=' or line breaks)",
                              what, name != NULL ? name : "");
    for (int k = 0; k < 3; k++)
        if (strcmp(name, reserved[k]) == 0)
            return dfle_error_set(err, DFLE_EINVAL,
                                  "ensemble: %s name '%s' is reserved for a column of the result",
                                  what, name);
    return DFLE_OK;
}

int dfle_ensemble_check(const dfle_ensemble_opts *o, dfle_error *err)
{
    int st;
    if (o->n < 1 || o->n > DFLE_SEED_MAX)
        return dfle_error_set(err, DFLE_EINVAL, "ensemble: n must be 1 .. %lu (got %zu)",
                              DFLE_SEED_MAX, o->n);
    if (o->seed > DFLE_SEED_MAX)
        return dfle_error_set(err, DFLE_EINVAL, "ensemble: seed must be 0 .. %lu (got %lu)",
                              DFLE_SEED_MAX, o->seed);
    if (o->nparams < 1 || o->params == NULL)
        return dfle_error_set(err, DFLE_EINVAL, "ensemble: the design needs a parameter");
    for (size_t k = 0; k < o->nparams; k++) {
        const dfle_ensemble_param *p = &o->params[k];
        dfle_lhs_param lp = {p->name, p->kind, p->lo, p->hi, NULL, p->nvalues};
        double one = 0;
        if (p->kind == DFLE_LHS_DISCRETE) {
            if (p->nvalues < 1 || p->value_text == NULL)
                return dfle_error_set(err, DFLE_EINVAL,
                                      "ensemble: parameter '%s': a discrete parameter needs its "
                                      "values' texts", p->name != NULL ? p->name : "");
            lp.values = &one;
            lp.nvalues = 1;
        }
        if ((st = dfle_lhs_param_check(&lp, err)) != DFLE_OK)
            return dfle_drive_prefix(err, "ensemble");
        if ((st = check_column("parameter", p->name, err)) != DFLE_OK)
            return st;
        for (size_t j = 0; j < k; j++)
            if (strcmp(o->params[j].name, p->name) == 0)
                return dfle_error_set(err, DFLE_EINVAL, "ensemble: parameter '%s' is given twice",
                                      p->name);
    }
    if (o->noutputs < 1 || o->outputs == NULL)
        return dfle_error_set(err, DFLE_EINVAL,
                              "ensemble: no outputs: name at least one (e.g. S_df, A_df)");
    for (size_t k = 0; k < o->noutputs; k++) {
        const char *name = o->outputs[k];
        if ((st = check_column("output", name, err)) != DFLE_OK)
            return st;
        for (size_t j = 0; j < o->nparams; j++)
            if (strcmp(o->params[j].name, name) == 0)
                return dfle_error_set(err, DFLE_EINVAL,
                                      "ensemble: '%s' is both a parameter and an output", name);
        for (size_t j = 0; j < k; j++)
            if (strcmp(o->outputs[j], name) == 0)
                return dfle_error_set(err, DFLE_EINVAL, "ensemble: output '%s' is listed twice",
                                      name);
    }
    if (o->out == NULL || o->out[0] == '\0')
        return dfle_error_set(err, DFLE_EINVAL, "ensemble: 'out', the file of rows, is needed");
    if (o->shard_n > 1 && (o->shard_i < 1 || o->shard_i > o->shard_n))
        return dfle_error_set(err, DFLE_EINVAL, "ensemble: shard %zu/%zu: need 1 <= i <= n",
                              o->shard_i, o->shard_n);
    if (o->workers < 1)
        return dfle_error_set(err, DFLE_EINVAL, "ensemble: workers must be >= 1 (got %d)",
                              o->workers);
    return DFLE_OK;
}

/* ------------------------------------------------------------------ */
/* The file's lines.                                                   */

static void add_names(dfle_text *t, const dfle_ensemble_opts *o, int params)
{
    size_t n = params ? o->nparams : o->noutputs;
    for (size_t k = 0; k < n; k++) {
        if (k > 0)
            dfle_text_str(t, ",");
        dfle_text_str(t, params ? o->params[k].name : o->outputs[k]);
    }
}

int dfle_ensemble_identity(const dfle_ensemble_opts *o, char **meta, char **header,
                           dfle_error *err)
{
    dfle_text m, h;
    int st;

    *meta = *header = NULL;
    if ((st = dfle_ensemble_check(o, err)) != DFLE_OK)
        return st;
    dfle_text_init(&m);
    dfle_text_printf(&m, "# dfle.ensemble v1 n=%zu seed=%lu centered=%s inputs=", o->n, o->seed,
                     o->centered ? "true" : "false");
    add_names(&m, o, 1);
    dfle_text_str(&m, " outputs=");
    add_names(&m, o, 0);
    dfle_text_str(&m, " design=");
    for (size_t k = 0; k < o->nparams; k++) {
        const dfle_ensemble_param *p = &o->params[k];
        if (k > 0)
            dfle_text_str(&m, ";");
        dfle_text_str(&m, p->name);
        if (p->kind == DFLE_LHS_DISCRETE) {
            dfle_text_str(&m, ":{");
            for (size_t j = 0; j < p->nvalues; j++) {
                if (j > 0)
                    dfle_text_str(&m, ",");
                dfle_text_str(&m, p->value_text[j]);
            }
            dfle_text_str(&m, "}");
        } else {
            dfle_text_str(&m, ":[");
            dfle_text_number(&m, p->lo);
            dfle_text_str(&m, ",");
            dfle_text_number(&m, p->hi);
            dfle_text_str(&m, p->kind == DFLE_LHS_LOG_UNIFORM ? ",log]" : "]");
        }
    }
    dfle_text_init(&h);
    dfle_text_str(&h, "index,");
    add_names(&h, o, 1);
    dfle_text_str(&h, ",");
    add_names(&h, o, 0);
    dfle_text_str(&h, ",status,reason");
    *meta = dfle_text_take(&m);
    *header = dfle_text_take(&h);
    if (*meta == NULL || *header == NULL) {
        free(*meta);
        free(*header);
        *meta = *header = NULL;
        return dfle_error_set(err, DFLE_ENOMEM, "ensemble: out of memory");
    }
    return DFLE_OK;
}

/* The comment lines under the meta line: the version that started the
 * file, the describe record, the units of the columns; joined by '\n'. */
static char *comment_lines(const dfle_ensemble_opts *o)
{
    const size_t nc = o->nparams + o->noutputs + 3;
    const char **names = calloc(2 * nc, sizeof *names), **units = names + nc;
    dfle_record *own = NULL;
    char *text = NULL, *line;
    size_t len = 0;
    FILE *fp;

    if (names == NULL || dfle_record_new(&own, NULL) != DFLE_OK) {
        free(names);
        return NULL;
    }
    dfle_record_text(own, "dfle", DFLE_VERSION);
    names[0] = "index";
    for (size_t k = 0; k < o->nparams; k++) {
        names[1 + k] = o->params[k].name;
        units[1 + k] = o->params[k].unit;
    }
    for (size_t k = 0; k < o->noutputs; k++) {
        names[1 + o->nparams + k] = o->outputs[k];
        units[1 + o->nparams + k] = o->output_units != NULL ? o->output_units[k] : NULL;
    }
    names[nc - 2] = "status";
    names[nc - 1] = "reason";
    fp = dfle_record_status(own, NULL) == DFLE_OK &&
                 (o->describe == NULL || dfle_record_status(o->describe, NULL) == DFLE_OK)
             ? open_memstream(&text, &len)
             : NULL;
    if (fp != NULL) {
        dfle_record_write_comments(own, fp);
        dfle_record_write_comments(o->describe, fp);
        line = dfle_units_line(names, units, nc);
        if (line != NULL)
            fprintf(fp, "%s\n", line);
        free(line);
        if (fclose(fp) != 0) {
            free(text);
            text = NULL;
        }
    }
    if (text != NULL && len > 0 && text[len - 1] == '\n')
        text[len - 1] = '\0'; /* the lines, joined by '\n' */
    dfle_record_free(own);
    free(names);
    return text;
}

int dfle_ensemble_shard_path(const char *out, size_t i, size_t n, char *buf, size_t cap,
                             dfle_error *err)
{
    const char *slash = strrchr(out, '/');
    const char *dot = strrchr(out, '.');
    int w;
    if (n <= 1) {
        w = snprintf(buf, cap, "%s", out);
    } else {
        if (dot == NULL || (slash != NULL && dot < slash) || dot == (slash ? slash + 1 : out))
            dot = out + strlen(out);
        w = snprintf(buf, cap, "%.*s.shard-%zu-of-%zu%s", (int)(dot - out), out, i, n, dot);
    }
    if (w < 0 || (size_t)w >= cap)
        return dfle_error_set(err, DFLE_EINVAL, "ensemble: the file name '%.80s...' is too long",
                              out);
    return DFLE_OK;
}

const char *dfle_ensemble_known_unit(const char *output)
{
    static const struct { const char *name, *unit; } known[] = {
        {"S_df", "-"},   {"A_df", "m^2"},   {"a2", "-"},      {"r2", "-"},       {"r2_log", "-"},
        {"rmse", "-"},   {"rmse_log", "-"}, {"S_max", "-"},   {"S_ch", "-"},
        {"S_max_minus_S_ch", "-"},          {"time", "yr"},   {"rate_ratio", "-"},
        {"dt_min", "yr"}, {"dt_max", "yr"}, {"runout_A", "m^2"}, {"runout_x", "m"}};
    for (size_t k = 0; k < sizeof known / sizeof known[0]; k++)
        if (strcmp(output, known[k].name) == 0)
            return known[k].unit;
    return NULL;
}

/* ------------------------------------------------------------------ */
/* The samples: the pool's task.                                       */

typedef struct ens_task {
    const dfle_ensemble_opts *o;
    dfle_ens_file *file;
    dfle_ens_queue *queue;
    dfle_lhs *design;
    pthread_mutex_t lock;
    size_t done, failed, total;
    double t0;
} ens_task;

static int task_next(void *ud, size_t *item, double *x)
{
    ens_task *t = ud;
    size_t i;
    if (!dfle_ens_queue_next(t->queue, &i))
        return 0;
    memcpy(x, dfle_lhs_row(t->design, i - 1), t->o->nparams * sizeof *x);
    *item = i;
    return 1;
}

/* The row of sample i: its parameters, outputs, status and reason. */
static void format_row(dfle_text *r, const dfle_ensemble_opts *o, const dfle_lhs *design,
                       size_t i, int status, const dfle_eval_out *out, const char *reason)
{
    const double *x = dfle_lhs_row(design, i - 1);
    dfle_text_printf(r, "%zu", i);
    for (size_t k = 0; k < o->nparams; k++) {
        dfle_text_str(r, ",");
        if (o->params[k].kind == DFLE_LHS_DISCRETE)
            dfle_text_str(r, o->params[k].value_text[dfle_lhs_choice(design, i - 1, k)]);
        else
            dfle_text_number(r, x[k]);
    }
    for (size_t k = 0; k < o->noutputs; k++) {
        dfle_text_str(r, ",");
        dfle_text_number(r, status == DFLE_EVAL_OK ? out->y[k] : NAN);
    }
    dfle_text_str(r, ",");
    dfle_text_str(r, dfle_eval_status_name(status));
    dfle_text_str(r, ",");
    if (status != DFLE_EVAL_OK && (out->flags & DFLE_EVAL_REASON_NUMBER))
        dfle_text_str(r, reason);
    else
        dfle_text_quoted(r, reason);
}

static int task_done(void *ud, size_t item, const dfle_eval_out *out, dfle_error *err)
{
    ens_task *t = ud;
    const dfle_ensemble_opts *o = t->o;
    int status = out->status;
    const char *reason = status == DFLE_EVAL_OK ? "" : out->reason;
    char why[128];
    dfle_text row;
    int st;

    if (status < 0 || status >= DFLE_EVAL_NSTATUS)
        status = DFLE_EVAL_ERROR;
    /* A number that is not one makes the row a failure, not a result. */
    for (size_t k = 0; status == DFLE_EVAL_OK && k < o->noutputs; k++)
        if (!isfinite(out->y[k])) {
            snprintf(why, sizeof why, "output '%.80s' is %s", o->outputs[k],
                     isnan(out->y[k]) ? "NaN" : out->y[k] > 0 ? "inf" : "-inf");
            status = DFLE_EVAL_NAN;
            reason = why;
        }
    dfle_text_init(&row);
    format_row(&row, o, t->design, item, status, out, reason);
    if (row.oom) {
        dfle_text_free(&row);
        return dfle_error_set(err, DFLE_ENOMEM, "ensemble: out of memory for a row");
    }
    st = dfle_ens_file_append(t->file, item, row.s, err);
    dfle_text_free(&row);
    if (st != DFLE_OK)
        return st;
    pthread_mutex_lock(&t->lock);
    t->done++;
    t->failed += status != DFLE_EVAL_OK;
    pthread_mutex_unlock(&t->lock);
    return DFLE_OK;
}

static int task_give_back(void *ud, size_t item, dfle_error *err)
{
    ens_task *t = ud;
    return dfle_ens_queue_give_back(t->queue, item, err);
}

static void task_stop(void *ud)
{
    ens_task *t = ud;
    dfle_ens_queue_stop(t->queue);
}

static void task_tick(void *ud)
{
    ens_task *t = ud;
    size_t done, failed;
    if (t->o->progress == NULL)
        return;
    pthread_mutex_lock(&t->lock);
    done = t->done;
    failed = t->failed;
    pthread_mutex_unlock(&t->lock);
    t->o->progress(t->o->ud, done, t->total, failed, dfle_drive_now() - t->t0);
}

/* The design of the options (a discrete parameter's values are the
 * indices 0 .. k-1: the row's x). */
static int make_design(const dfle_ensemble_opts *o, dfle_lhs **out, dfle_error *err)
{
    dfle_lhs_param *lp = calloc(o->nparams, sizeof *lp);
    double **idx = calloc(o->nparams, sizeof *idx);
    dfle_lhs_opts lo;
    int st = DFLE_ENOMEM;

    if (lp != NULL && idx != NULL) {
        st = DFLE_OK;
        for (size_t k = 0; k < o->nparams && st == DFLE_OK; k++) {
            const dfle_ensemble_param *p = &o->params[k];
            lp[k] = (dfle_lhs_param){p->name, p->kind, p->lo, p->hi, NULL, 0};
            if (p->kind != DFLE_LHS_DISCRETE)
                continue;
            if ((idx[k] = malloc(p->nvalues * sizeof *idx[k])) == NULL) {
                st = DFLE_ENOMEM;
                break;
            }
            for (size_t j = 0; j < p->nvalues; j++)
                idx[k][j] = (double)j;
            lp[k].values = idx[k];
            lp[k].nvalues = p->nvalues;
        }
    }
    if (st == DFLE_OK) {
        dfle_lhs_opts_default(&lo);
        lo.n = o->n;
        lo.seed = o->seed;
        lo.centered = o->centered;
        st = dfle_lhs_new(&lo, o->nparams, lp, out, err);
        if (st != DFLE_OK)
            dfle_drive_prefix(err, "ensemble");
    } else {
        dfle_error_set(err, st, "ensemble: out of memory for the design");
    }
    for (size_t k = 0; idx != NULL && k < o->nparams; k++)
        free(idx[k]);
    free(idx);
    free(lp);
    return st;
}

static void say(const dfle_ensemble_opts *o, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static void say(const dfle_ensemble_opts *o, const char *fmt, ...)
{
    char line[DFLE_ERROR_MSG_MAX + 64];
    va_list ap;
    if (o->note == NULL)
        return;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    o->note(o->ud, line);
}

/* Run the task on a pool: DFLE_OK, DFLE_ECANCELED or the first error. */
static int run_samples(const dfle_ensemble_opts *o, const dfle_evaluator *ev, ens_task *t,
                       dfle_error *err)
{
    dfle_pool_opts po;
    dfle_pool_task pt;
    dfle_pool *pool;
    dfle_error e2 = {0};
    int st, st2;

    dfle_pool_opts_default(&po);
    /* Workers are threads when there are several, or when other
     * processes take part (the calling thread then waits for them). */
    po.threads = o->workers > 1 || o->remote != NULL ? o->workers : 0;
    po.caller = po.threads == 0;
    po.ninputs = o->nparams;
    po.noutputs = o->noutputs;
    po.interrupt = o->interrupt;
    po.remote = o->remote;
    po.remote_workers = o->remote_workers;
    if ((st = dfle_pool_new(ev, &po, &pool, err)) != DFLE_OK)
        return st;
    memset(&pt, 0, sizeof pt);
    pt.next = task_next;
    pt.done = task_done;
    pt.give_back = task_give_back;
    pt.stop = task_stop;
    pt.tick = task_tick;
    pt.ud = t;
    pt.total = t->total;
    st = dfle_pool_run(pool, &pt, err);
    st2 = dfle_pool_free(pool, &e2);
    if (st == DFLE_OK && st2 != DFLE_OK) {
        st = st2;
        if (err != NULL)
            *err = e2;
    }
    task_tick(t);
    return st;
}

int dfle_ensemble_run(const dfle_ensemble_opts *o, const dfle_evaluator *ev,
                      dfle_ensemble_result *res, dfle_error *err)
{
    char *meta = NULL, *header = NULL, *comments = NULL;
    ens_task t;
    int st, interrupted;

    memset(res, 0, sizeof *res);
    memset(&t, 0, sizeof t);
    if ((st = dfle_ensemble_identity(o, &meta, &header, err)) != DFLE_OK)
        return st;
    if ((st = dfle_evaluator_check(ev, err)) != DFLE_OK ||
        (st = dfle_ensemble_shard_path(o->out, o->shard_i, o->shard_n, res->path,
                                       sizeof res->path, err)) != DFLE_OK)
        goto done;
    if ((comments = comment_lines(o)) == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "ensemble: out of memory");
        goto done;
    }
    if ((st = dfle_ens_file_open(res->path, meta, comments, header, o->n, o->resume, &t.file,
                                 err)) != DFLE_OK ||
        (st = dfle_ens_queue_new(o->n, o->shard_i, o->shard_n, t.file, o->limit, &t.queue,
                                 err)) != DFLE_OK) {
        dfle_drive_prefix(err, "ensemble");
        goto done;
    }
    t.o = o;
    t.total = res->total = dfle_ens_queue_total(t.queue);
    res->kept = dfle_ens_file_ndone(t.file);
    if (res->kept > 0 && res->total > 0)
        say(o, "ensemble %s: resuming: %zu finished rows kept, %zu sample%s to run", res->path,
            res->kept, res->total, res->total == 1 ? "" : "s");
    else if (res->kept > 0)
        say(o, "ensemble %s: all %zu rows were done before; nothing to run", res->path,
            res->kept);
    if (res->total > 0) {
        if ((st = make_design(o, &t.design, err)) != DFLE_OK)
            goto done;
        pthread_mutex_init(&t.lock, NULL);
        t.t0 = dfle_drive_now();
        st = run_samples(o, ev, &t, err);
        pthread_mutex_destroy(&t.lock);
        res->ran = t.done;
        res->failed = t.failed;
    }
    interrupted = (st == DFLE_ECANCELED || (o->interrupt != NULL && *o->interrupt)) &&
                  res->ran < res->total;
    if (st != DFLE_OK && st != DFLE_ECANCELED) {
        /* The rows so far are results: kept, and sorted. */
        char msg[DFLE_ERROR_MSG_MAX];
        dfle_drive_prefix(err, "ensemble");
        snprintf(msg, sizeof msg, "%s", err != NULL ? err->msg : "failed");
        dfle_ens_file_close(t.file, 1, NULL);
        t.file = NULL;
        dfle_error_set(err, st, "%s (%zu rows written are kept; run again to resume)", msg,
                       res->ran);
        goto done;
    }
    res->interrupted = interrupted;
    /* Cut short, the rows stay as written (whole lines, in the order
     * they finished; the resumed run sorts them): the sorted rewrite
     * syncs the disk, which on a busy machine takes longer than the
     * moment between the SIGTERM and the SIGKILL with which mpirun ends
     * a job, and the caller's message must get out first. */
    st = dfle_ens_file_close(t.file, !interrupted, err);
    t.file = NULL;
    if (st != DFLE_OK)
        dfle_drive_prefix(err, "ensemble");
    else if (interrupted)
        st = dfle_error_set(err, DFLE_ECANCELED,
                            "ensemble: interrupted: %zu finished rows are in %s, and running "
                            "again resumes it",
                            res->kept + res->ran, res->path);
done:
    dfle_ens_file_close(t.file, 0, NULL);
    dfle_ens_queue_free(t.queue);
    dfle_lhs_free(t.design);
    free(meta);
    free(header);
    free(comments);
    return st;
}
