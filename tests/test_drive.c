/*
 * test_drive.c - the driver layer without Lua: the worker pool
 * (pool.h), dfle_ensemble_run and dfle_invert_new/run with evaluators
 * written in C on a small model.  Checked: the same results for 1, 2
 * and 3 workers, with and without the calling thread working; files
 * byte-identical for any worker count, after a resume and after an
 * interrupt and a resume; failed samples as rows, an interrupt never
 * as one; an evaluator's failure stops a run with its message.
 */
#include "dfle_test.h"

#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "dfle/channel.h"
#include "dfle/ensemble_run.h"
#include "dfle/fluvial.h"
#include "dfle/invert_run.h"
#include "dfle/law_power.h"
#include "dfle/likelihood.h"
#include "dfle/model.h"
#include "dfle/pool.h"
#include "dfle/router_empirical.h"
#include "dfle/solver.h"

static char dir[64];

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/dfle-test-drive-XXXXXX");
    /* Files made at different moments compare byte for byte only with
     * one date in their comment lines. */
    setenv("SOURCE_DATE_EPOCH", "86400", 1);
    return mkdtemp(dir) == NULL ? -1 : 0;
}

static int teardown(void **state)
{
    char cmd[128];
    (void)state;
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd) != 0;
}

static const char *path(const char *name)
{
    static char buf[4][160];
    static int k;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "%s/%s", dir, name);
    return buf[k];
}

static char *slurp(const char *name) { return dfle_test_slurp(path(name)); }

/* ------------------------------------------------------------------ */
/* The pool with an arithmetic evaluator.                              */

typedef struct toy {
    atomic_int opens, closes;
    int fail_open_worker;  /* 1..: that worker's open fails             */
    size_t fail_item;      /* eval of this item fails                   */
    size_t cancel_item;    /* eval of this item is cut short            */
} toy;

static int toy_open(void *ud, int worker, void **state, dfle_error *err)
{
    toy *t = ud;
    if (worker == t->fail_open_worker)
        return dfle_error_set(err, DFLE_ECALLBACK, "worker %d cannot open", worker);
    atomic_fetch_add(&t->opens, 1);
    *state = t;
    return DFLE_OK;
}

static int toy_eval(void *state, size_t index, const double *x, dfle_eval_out *out,
                    dfle_error *err)
{
    toy *t = state;
    if (index == t->fail_item)
        return dfle_error_set(err, DFLE_ECALLBACK, "item %zu is broken", index);
    if (index == t->cancel_item)
        return DFLE_ECANCELED;
    out->y[0] = sin(x[0]) * (double)index;
    out->y[1] = x[0] * x[0];
    if (index % 7 == 0) {
        out->status = DFLE_EVAL_ERROR;
        dfle_eval_reason(out, "item %zu fails as a result", index);
    }
    return DFLE_OK;
}

static void toy_close(void *state)
{
    toy *t = state;
    atomic_fetch_add(&t->closes, 1);
}

static const dfle_evaluator_ops toy_ops = {
    .version = DFLE_EVALUATOR_VERSION, .name = "c.toy",
    .open = toy_open, .eval = toy_eval, .close = toy_close};

enum { NITEMS = 200 };

typedef struct toy_task {
    pthread_mutex_t lock;
    size_t next, done;
    double y[NITEMS + 1][2];
    int status[NITEMS + 1];
    volatile sig_atomic_t *flag;
    size_t raise_after;
} toy_task;

static int tt_next(void *ud, size_t *item, double *x)
{
    toy_task *t = ud;
    int got;
    pthread_mutex_lock(&t->lock);
    got = t->next < NITEMS;
    if (got) {
        *item = ++t->next;
        x[0] = 0.1 * (double)*item;
    }
    pthread_mutex_unlock(&t->lock);
    return got;
}

static int tt_done(void *ud, size_t item, const dfle_eval_out *out, dfle_error *err)
{
    toy_task *t = ud;
    (void)err;
    pthread_mutex_lock(&t->lock);
    t->y[item][0] = out->y[0];
    t->y[item][1] = out->y[1];
    t->status[item] = out->status + 1;
    if (++t->done == t->raise_after && t->flag != NULL)
        *t->flag = SIGINT;
    pthread_mutex_unlock(&t->lock);
    return DFLE_OK;
}

static int run_toy(toy *ev_ud, int threads, int caller, toy_task *t,
                   const volatile sig_atomic_t *flag, dfle_error *err)
{
    dfle_evaluator ev = {&toy_ops, ev_ud, NULL};
    dfle_pool_opts o;
    dfle_pool_task pt = {tt_next, tt_done, NULL, NULL, NULL, t, NITEMS};
    dfle_pool *p;
    int st;
    dfle_pool_opts_default(&o);
    o.threads = threads;
    o.caller = caller;
    o.ninputs = 1;
    o.noutputs = 2;
    o.interrupt = flag;
    if ((st = dfle_pool_new(&ev, &o, &p, err)) != DFLE_OK)
        return st;
    st = dfle_pool_run(p, &pt, err);
    if (st == DFLE_OK) { /* a second run on the same pool: nothing left to do */
        st = dfle_pool_run(p, &pt, err);
    }
    {
        dfle_error e2;
        int st2 = dfle_pool_free(p, &e2);
        if (st == DFLE_OK && st2 != DFLE_OK) {
            st = st2;
            *err = e2;
        }
    }
    return st;
}

static void pool_results_do_not_depend_on_workers(void **state)
{
    static toy_task ref, got;
    dfle_error err;
    static const int shapes[][2] = {{0, 1}, {1, 0}, {2, 0}, {3, 0}, {1, 1}, {2, 1}};
    (void)state;
    memset(&ref, 0, sizeof ref);
    pthread_mutex_init(&ref.lock, NULL);
    {
        toy t = {0};
        t.fail_open_worker = -1;
        assert_ok(run_toy(&t, 0, 1, &ref, NULL, &err), &err);
        assert_int_equal(t.opens, 1);
        assert_int_equal(t.closes, 1);
    }
    assert_int_equal(ref.done, NITEMS);
    for (size_t k = 0; k < sizeof shapes / sizeof shapes[0]; k++) {
        toy t = {0};
        t.fail_open_worker = -1;
        memset(&got, 0, sizeof got);
        pthread_mutex_init(&got.lock, NULL);
        assert_ok(run_toy(&t, shapes[k][0], shapes[k][1], &got, NULL, &err), &err);
        /* each worker opened once and closed once */
        assert_int_equal(t.opens, shapes[k][0] + shapes[k][1]);
        assert_int_equal(t.closes, t.opens);
        assert_int_equal(got.done, NITEMS);
        assert_memory_equal(got.y, ref.y, sizeof ref.y);
        assert_memory_equal(got.status, ref.status, sizeof ref.status);
        pthread_mutex_destroy(&got.lock);
    }
    /* a failed sample is a result, with its status */
    assert_int_equal(ref.status[7], DFLE_EVAL_ERROR + 1);
    assert_int_equal(ref.status[8], DFLE_EVAL_OK + 1);
    pthread_mutex_destroy(&ref.lock);
}

static void pool_stops_on_errors(void **state)
{
    static toy_task tt;
    dfle_error err;
    (void)state;
    /* an evaluator's failure stops the run, with its message */
    for (int threads = 0; threads <= 2; threads++) {
        toy t = {0};
        t.fail_open_worker = -1;
        t.fail_item = 50;
        memset(&tt, 0, sizeof tt);
        pthread_mutex_init(&tt.lock, NULL);
        assert_int_equal(run_toy(&t, threads, threads == 0, &tt, NULL, &err), DFLE_ECALLBACK);
        assert_string_equal(err.msg, "item 50 is broken");
        assert_int_equal(tt.status[50], 0);
        assert_true(tt.done < NITEMS);
        pthread_mutex_destroy(&tt.lock);
    }
    /* a worker that cannot open stops the run with its message */
    {
        toy t = {0};
        t.fail_open_worker = 2;
        memset(&tt, 0, sizeof tt);
        pthread_mutex_init(&tt.lock, NULL);
        assert_int_equal(run_toy(&t, 2, 0, &tt, NULL, &err), DFLE_ECALLBACK);
        assert_string_equal(err.msg, "worker 2 cannot open");
        pthread_mutex_destroy(&tt.lock);
    }
    /* a pool with no worker, an evaluator of an unknown version */
    {
        static const dfle_evaluator_ops v0 = {.name = "old", .open = toy_open, .eval = toy_eval};
        toy t = {0};
        dfle_evaluator ev = {&v0, &t, NULL};
        dfle_pool_opts o;
        dfle_pool *p = NULL;
        dfle_pool_opts_default(&o);
        assert_int_equal(dfle_pool_new(&ev, &o, &p, &err), DFLE_EINVAL);
        assert_msg_contains(err.msg, "ops version 0");
        ev.ops = &toy_ops;
        o.caller = 0;
        assert_int_equal(dfle_pool_new(&ev, &o, &p, &err), DFLE_EINVAL);
        assert_null(p);
    }
}

static void pool_interrupts_are_not_results(void **state)
{
    static toy_task tt;
    volatile sig_atomic_t flag = 0;
    dfle_error err;
    (void)state;
    for (int threads = 0; threads <= 3; threads++) {
        toy t = {0};
        t.fail_open_worker = -1;
        flag = 0;
        memset(&tt, 0, sizeof tt);
        pthread_mutex_init(&tt.lock, NULL);
        tt.flag = &flag;
        tt.raise_after = 20;
        assert_int_equal(run_toy(&t, threads, threads == 0, &tt, &flag, &err), DFLE_ECANCELED);
        /* no worker took an item after the flag: those running finished */
        assert_true(tt.done >= 20 && tt.done <= 20 + (size_t)threads);
        pthread_mutex_destroy(&tt.lock);
    }
    /* an item the evaluator cut short is no result, and stops the run */
    {
        toy t = {0};
        t.fail_open_worker = -1;
        t.cancel_item = 30;
        memset(&tt, 0, sizeof tt);
        pthread_mutex_init(&tt.lock, NULL);
        assert_int_equal(run_toy(&t, 0, 1, &tt, NULL, &err), DFLE_ECANCELED);
        assert_int_equal(tt.status[30], 0);
        assert_int_equal(tt.done, 29);
        pthread_mutex_destroy(&tt.lock);
    }
}

/* ------------------------------------------------------------------ */
/* A model evaluator: a steady state of the empirical model.           */

static dfle_channel *CH;        /* shared: read-only after construction */
static dfle_fluvial *FLUVIAL;   /* shared: read-only                     */
static volatile sig_atomic_t INTERRUPT;
static atomic_int EVALS;        /* evaluations, to raise INTERRUPT after */
static int INTERRUPT_AFTER;

typedef struct model_worker {
    dfle_router *rt;
    double *r; /* residuals (inversion) */
} model_worker;

static int mw_open(void *ud, int worker, void **state, dfle_error *err)
{
    model_worker *w = calloc(1, sizeof *w);
    dfle_empirical_opts eo;
    int st;
    (void)ud, (void)worker;
    if (w == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "out of memory");
    dfle_empirical_opts_default(&eo);
    if ((st = dfle_router_new_empirical(&eo, &w->rt, err)) != DFLE_OK) {
        free(w);
        return st;
    }
    w->r = calloc(64, sizeof *w->r);
    *state = w;
    return DFLE_OK;
}

static void mw_close(void *state)
{
    model_worker *w = state;
    dfle_router_free(w->rt);
    free(w->r);
    free(w);
}

/* The steady state of the model for U [m/yr] and k_df: *m, or a status. */
static int steady(model_worker *w, double U, double k_df, dfle_model **m, dfle_law **law,
                  dfle_run_result *res, dfle_error *err)
{
    dfle_power_law_opts po;
    dfle_model_opts mo;
    dfle_run_opts ro;
    int st;
    *m = NULL;
    dfle_power_law_opts_default(&po);
    po.k_df = k_df;
    if ((st = dfle_law_new_power(&po, law, err)) != DFLE_OK)
        return st;
    dfle_model_opts_default(&mo);
    mo.channel = CH;
    mo.fluvial = FLUVIAL;
    mo.router = w->rt;
    mo.law = *law;
    mo.U = U;
    dfle_run_opts_default(&ro);
    ro.method = DFLE_METHOD_DIRECT;
    if ((st = dfle_model_new(&mo, m, err)) != DFLE_OK)
        return st;
    return dfle_solver_run(*m, &ro, res, err);
}

/* Ensemble: outputs S at the head and the relief; x = (U, k_df, choice of
 * alpha-like discrete parameter, unused but in the rows). */
static int ens_eval(void *state, size_t index, const double *x, dfle_eval_out *out,
                    dfle_error *err)
{
    model_worker *w = state;
    dfle_model *m = NULL;
    dfle_law *law = NULL;
    dfle_run_result res;
    dfle_error e;
    int st;
    (void)err;
    if (INTERRUPT_AFTER > 0 && atomic_fetch_add(&EVALS, 1) + 1 >= INTERRUPT_AFTER)
        INTERRUPT = SIGINT;
    if (index % 11 == 0) { /* a failure of the sample's own */
        out->status = DFLE_EVAL_ERROR;
        dfle_eval_reason(out, "sample %zu: a \"quoted\"\nreason", index);
        return DFLE_OK;
    }
    st = steady(w, x[0], x[1], &m, &law, &res, &e);
    if (st != DFLE_OK) {
        out->status = DFLE_EVAL_ERROR;
        dfle_eval_reason(out, "%s", e.msg);
    } else if (!res.converged) {
        out->status = DFLE_EVAL_NOT_CONVERGED;
        dfle_eval_reason(out, "%s", dfle_stop_reason_name(res.reason));
    } else {
        const double *S = dfle_model_field(m, DFLE_FIELD_S, &e);
        const double *z = dfle_model_field(m, DFLE_FIELD_Z, &e);
        out->y[0] = S[0];
        out->y[1] = index % 13 == 0 ? NAN : z[0]; /* the driver calls it "nan" */
    }
    dfle_model_free(m);
    dfle_law_free(law);
    return DFLE_OK;
}

static const dfle_evaluator_ops ens_ops = {
    .version = DFLE_EVALUATOR_VERSION, .name = "c.ensemble",
    .open = mw_open, .eval = ens_eval, .close = mw_close};

static int model_setup(void **state)
{
    dfle_channel_opts co;
    dfle_stochastic_threshold_opts so;
    dfle_error err;
    if (setup(state) != 0)
        return -1;
    dfle_channel_opts_default(&co);
    co.dx = 25;
    co.A_max = 1e6;
    dfle_stochastic_threshold_opts_default(&so);
    if (dfle_channel_new(&co, &CH, &err) != DFLE_OK ||
        dfle_fluvial_new_stochastic_threshold(&so, &FLUVIAL, &err) != DFLE_OK)
        return -1;
    return 0;
}

static int model_teardown(void **state)
{
    dfle_channel_free(CH);
    dfle_fluvial_free(FLUVIAL);
    CH = NULL;
    FLUVIAL = NULL;
    return teardown(state);
}

static const char *const alpha_text[] = {"4", "6", "\"six and a half\""};
static const char *const outputs[] = {"S_head", "relief"};
static const char *const output_units[] = {"-", "m"};

static void ens_opts(dfle_ensemble_opts *o, dfle_ensemble_param *p, const char *out, int workers)
{
    dfle_ensemble_opts_default(o);
    p[0] = (dfle_ensemble_param){"U", "m/yr", DFLE_LHS_UNIFORM, 1e-4, 1e-3, 0, NULL};
    p[1] = (dfle_ensemble_param){"k_df", NULL, DFLE_LHS_LOG_UNIFORM, 5e-5, 1e-3, 0, NULL};
    p[2] = (dfle_ensemble_param){"alpha", NULL, DFLE_LHS_DISCRETE, 0, 0, 3, alpha_text};
    o->n = 30;
    o->seed = 5;
    o->nparams = 3;
    o->params = p;
    o->noutputs = 2;
    o->outputs = outputs;
    o->output_units = output_units;
    o->out = path(out);
    o->workers = workers;
    o->interrupt = &INTERRUPT;
}

static void ensemble_the_same_for_any_workers_and_resumes(void **state)
{
    dfle_evaluator ev = {&ens_ops, NULL, NULL};
    dfle_ensemble_param p[3];
    dfle_ensemble_opts o;
    dfle_ensemble_result res;
    dfle_error err;
    char *ref, *got, name[32];
    (void)state;
    INTERRUPT = 0;
    INTERRUPT_AFTER = 0;
    ens_opts(&o, p, "ref.csv", 1);
    assert_ok(dfle_ensemble_run(&o, &ev, &res, &err), &err);
    assert_int_equal(res.ran, 30);
    assert_int_equal(res.kept, 0);
    assert_true(res.failed >= 4); /* 11, 22 (own failures), 13, 26 (nan) */
    ref = slurp("ref.csv");
    /* the file: its lines, and rows of every status */
    assert_non_null(strstr(ref, "# dfle.ensemble v1 n=30 seed=5 centered=false inputs=U,k_df,"
                                "alpha outputs=S_head,relief design=U:[0.0001,0.001];"
                                "k_df:[5.0000000000000002e-05,0.001,log];alpha:{4,6,\"six and a "
                                "half\"}\n# dfle: "));
    assert_non_null(strstr(ref, "\n# units: U=m/yr, S_head=-, relief=m\n"
                                "index,U,k_df,alpha,S_head,relief,status,reason\n1,"));
    assert_non_null(strstr(ref, ",nan,nan,error,\"sample 11: a \"\"quoted\"\" reason\"\n"));
    assert_non_null(strstr(ref, ",nan,nan,nan,\"output 'relief' is NaN\"\n"));
    assert_non_null(strstr(ref, ",ok,\"\"\n"));
    for (int w = 2; w <= 3; w++) {
        snprintf(name, sizeof name, "w%d.csv", w);
        ens_opts(&o, p, name, w);
        assert_ok(dfle_ensemble_run(&o, &ev, &res, &err), &err);
        got = slurp(name);
        assert_string_equal(got, ref);
        free(got);
    }
    /* 12 samples, then the rest on 3 workers */
    ens_opts(&o, p, "limit.csv", 2);
    o.limit = 12;
    assert_ok(dfle_ensemble_run(&o, &ev, &res, &err), &err);
    assert_int_equal(res.ran, 12);
    ens_opts(&o, p, "limit.csv", 3);
    assert_ok(dfle_ensemble_run(&o, &ev, &res, &err), &err);
    assert_int_equal(res.kept, 12);
    assert_int_equal(res.ran, 18);
    got = slurp("limit.csv");
    assert_string_equal(got, ref);
    free(got);
    /* interrupted (no sample running then is a row), then resumed */
    for (int w = 1; w <= 3; w++) {
        snprintf(name, sizeof name, "int%d.csv", w);
        ens_opts(&o, p, name, w);
        INTERRUPT = 0;
        atomic_store(&EVALS, 0);
        INTERRUPT_AFTER = 8;
        assert_int_equal(dfle_ensemble_run(&o, &ev, &res, &err), DFLE_ECANCELED);
        assert_true(res.interrupted);
        assert_true(res.ran >= 7 && res.ran < 30);
        assert_msg_contains(err.msg, "running again resumes it");
        INTERRUPT = 0;
        INTERRUPT_AFTER = 0;
        assert_ok(dfle_ensemble_run(&o, &ev, &res, &err), &err);
        assert_int_equal(res.kept + res.ran, 30);
        got = slurp(name);
        assert_string_equal(got, ref);
        free(got);
    }
    /* another ensemble's file is refused; a name that cannot be a column */
    ens_opts(&o, p, "ref.csv", 1);
    o.seed = 6;
    assert_int_equal(dfle_ensemble_run(&o, &ev, &res, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "was written by a different ensemble");
    o.seed = 5;
    p[0].name = "U,V";
    assert_int_equal(dfle_ensemble_run(&o, &ev, &res, &err), DFLE_EINVAL);
    assert_string_equal(err.msg, "ensemble: parameter name 'U,V' cannot be a CSV column (no "
                                 "commas, quotes, spaces, '=' or line breaks)");
    free(ref);
}

/* ------------------------------------------------------------------ */
/* An inversion: U and k_df from the model's own slopes, sigma free.   */

enum { NOBS = 8 };
static double A_OBS[NOBS], LNS_OBS[NOBS];

static int inv_eval(void *state, size_t index, const double *x, dfle_eval_out *out,
                    dfle_error *err)
{
    model_worker *w = state;
    dfle_model *m = NULL;
    dfle_law *law = NULL;
    dfle_run_result res;
    dfle_error e;
    int st;
    (void)index, (void)err;
    if (INTERRUPT_AFTER > 0 && atomic_fetch_add(&EVALS, 1) + 1 >= INTERRUPT_AFTER)
        INTERRUPT = SIGINT;
    st = steady(w, x[0], x[1], &m, &law, &res, &e);
    if (st != DFLE_OK) {
        out->status = DFLE_EVAL_ERROR;
        dfle_eval_reason(out, "%s", e.msg);
    } else if (!res.converged) {
        out->status = DFLE_EVAL_NOT_CONVERGED;
        dfle_eval_reason(out, "no steady state");
    } else {
        const double *A = dfle_model_field(m, DFLE_FIELD_A, &e);
        const double *S = dfle_model_field(m, DFLE_FIELD_S, &e);
        if (dfle_log_slope_residuals(dfle_model_size(m), A, S, NOBS, A_OBS, LNS_OBS, w->r,
                                     &e) != DFLE_OK) {
            out->status = DFLE_EVAL_INVALID;
            dfle_eval_reason(out, "%s", e.msg);
        } else {
            out->y[0] = dfle_gauss_loglike(NOBS, w->r, x[2]);
        }
    }
    dfle_model_free(m);
    dfle_law_free(law);
    return DFLE_OK;
}

static const dfle_evaluator_ops inv_ops = {
    .version = DFLE_EVALUATOR_VERSION, .name = "c.invert",
    .open = mw_open, .eval = inv_eval, .close = mw_close};

static const char *const inv_names[] = {"U", "k_df", "sigma"};
static dfle_prior inv_priors[3];

static void inv_opts(dfle_invert_opts *o, const char *out, size_t steps, int workers)
{
    dfle_invert_opts_default(o);
    inv_priors[0] = (dfle_prior){DFLE_PRIOR_LOG_UNIFORM, 1e-4, 1e-3, 0, 0, 0};
    inv_priors[1] = (dfle_prior){DFLE_PRIOR_LOG_UNIFORM, 5e-5, 1e-3, 0, 0, 0};
    inv_priors[2] = (dfle_prior){DFLE_PRIOR_LOG_UNIFORM, 0.005, 2, 0, 0, 0};
    o->d = 3;
    o->names = inv_names;
    o->priors = inv_priors;
    o->walkers = 8;
    o->steps = steps;
    o->burn = 5;
    o->seed = 9;
    o->out = out != NULL ? path(out) : NULL;
    o->identity = " data=test";
    o->workers = workers;
    o->interrupt = &INTERRUPT;
}

/* Data: the model at U = 4e-4, k_df = 2e-4, with a fixed pattern of noise. */
static void make_data(void)
{
    dfle_evaluator ev = {&inv_ops, NULL, NULL};
    model_worker *w;
    dfle_model *m;
    dfle_law *law;
    dfle_run_result res;
    dfle_error err;
    const double *A, *S;
    size_t n;
    assert_ok(mw_open(NULL, 0, (void **)&w, &err), &err);
    assert_ok(steady(w, 4e-4, 2e-4, &m, &law, &res, &err), &err);
    A = dfle_model_field(m, DFLE_FIELD_A, &err);
    S = dfle_model_field(m, DFLE_FIELD_S, &err);
    n = dfle_model_size(m);
    for (size_t i = 0; i < NOBS; i++) {
        size_t k = 1 + i * (n - 3) / (NOBS - 1);
        A_OBS[i] = A[k];
        LNS_OBS[i] = log(S[k]) + 0.1 * sin(2.3 * (double)i);
    }
    dfle_model_free(m);
    dfle_law_free(law);
    mw_close(w);
    (void)ev;
}

/* new + run: the status, the result (a copy of the object's) in *out. */
static int invert(const dfle_invert_opts *o, const dfle_evaluator *ev, dfle_invert **out,
                  dfle_error *err)
{
    int st = dfle_invert_new(o, out, err);
    if (st == DFLE_OK)
        st = dfle_invert_run(*out, ev, err);
    return st;
}

static void invert_the_same_for_any_workers_and_resumes(void **state)
{
    dfle_evaluator ev = {&inv_ops, NULL, NULL};
    dfle_invert_opts o;
    dfle_invert *inv = NULL, *inv2 = NULL;
    const dfle_invert_result *r, *r2;
    dfle_error err;
    char *ref, *got, name[32], *cut;
    size_t len;
    FILE *fp;
    (void)state;
    make_data();
    INTERRUPT = 0;
    INTERRUPT_AFTER = 0;
    inv_opts(&o, "ref.csv", 30, 1);
    assert_ok(invert(&o, &ev, &inv, &err), &err);
    r = dfle_invert_result_of(inv);
    assert_int_equal(r->have, 31);
    assert_int_equal(r->ran, 30);
    assert_true(r->complete);
    assert_int_equal(r->nsamples, 8 * 25);
    assert_true(r->evaluations >= 8 + 30 * 8);
    assert_true(r->acceptance > 0 && r->acceptance < 1);
    for (int j = 0; j < 3; j++)
        assert_true(r->summary[j].lo95 >= inv_priors[j].lo && r->summary[j].hi95 <= inv_priors[j].hi);
    assert_true(r->nwarnings >= 1); /* a chain this short says so */
    assert_msg_contains(r->warnings[0], "too short");
    ref = slurp("ref.csv");
    assert_non_null(strstr(ref, "# dfle.invert v2 seed=9 walkers=8 a=2 params=U:log-uniform[0.0001,"
                                "0.001];k_df:log-uniform[5.0000000000000002e-05,0.001];sigma:"
                                "log-uniform[0.0050000000000000001,2] data=test\n# dfle: "
                                DFLE_VERSION "\n# date: 1970-01-02T00:00:00Z\n# units: index=-, "
                                "step=-, walker=-, log_post=-, log_like=-\nindex,step,walker,"
                                "U,k_df,sigma,log_post,log_like,proposal\n1,0,1,"));
    /* the same chain in memory */
    inv_opts(&o, NULL, 30, 2);
    assert_ok(invert(&o, &ev, &inv2, &err), &err);
    r2 = dfle_invert_result_of(inv2);
    assert_memory_equal(r2->x, r->x, 31 * 8 * 3 * sizeof *r->x);
    assert_memory_equal(r2->log_post, r->log_post, 31 * 8 * sizeof *r->log_post);
    assert_memory_equal(r2->proposal, r->proposal, 31 * 8);
    dfle_invert_free(inv2);
    for (int w = 2; w <= 3; w++) {
        snprintf(name, sizeof name, "w%d.csv", w);
        inv_opts(&o, name, 30, w);
        assert_ok(invert(&o, &ev, &inv2, &err), &err);
    r2 = dfle_invert_result_of(inv2);
        dfle_invert_free(inv2);
        got = slurp(name);
        assert_string_equal(got, ref);
        free(got);
    }
    /* extended: 12 steps, then to 30 on 3 workers */
    inv_opts(&o, "ext.csv", 12, 2);
    assert_ok(invert(&o, &ev, &inv2, &err), &err);
    r2 = dfle_invert_result_of(inv2);
    dfle_invert_free(inv2);
    inv_opts(&o, "ext.csv", 30, 3);
    assert_ok(invert(&o, &ev, &inv2, &err), &err);
    r2 = dfle_invert_result_of(inv2);
    assert_int_equal(r2->ran, 18);
    assert_close(r2->summary[0].median, r->summary[0].median, 0, 0);
    dfle_invert_free(inv2);
    got = slurp("ext.csv");
    assert_string_equal(got, ref);
    free(got);
    /* a killed writer: half a row at the end, resumed */
    len = strlen(ref);
    cut = strdup(ref);
    cut[len - 300] = '\0';
    fp = fopen(path("cut.csv"), "w");
    fputs(cut, fp);
    fclose(fp);
    free(cut);
    inv_opts(&o, "cut.csv", 30, 2);
    assert_ok(invert(&o, &ev, &inv2, &err), &err);
    r2 = dfle_invert_result_of(inv2);
    assert_true(r2->ran >= 1 && r2->ran <= 2);
    dfle_invert_free(inv2);
    got = slurp("cut.csv");
    assert_string_equal(got, ref);
    free(got);
    /* interrupted: whole steps only, then resumed to the same chain */
    for (int w = 1; w <= 3; w++) {
        size_t rows = 0;
        snprintf(name, sizeof name, "int%d.csv", w);
        inv_opts(&o, name, 30, w);
        INTERRUPT = 0;
        atomic_store(&EVALS, 0);
        INTERRUPT_AFTER = 60;
        assert_int_equal(invert(&o, &ev, &inv2, &err), DFLE_ECANCELED);
        r2 = dfle_invert_result_of(inv2);
        assert_true(r2->interrupted);
        assert_true(r2->have >= 2 && r2->have < 31);
        assert_msg_contains(err.msg, "running again resumes it");
        got = slurp(name);
        for (const char *c = got; (c = strchr(c, '\n')) != NULL; c++)
            rows += c[1] >= '1' && c[1] <= '9';
        assert_int_equal(rows, r2->have * 8);
        free(got);
        dfle_invert_free(inv2);
        INTERRUPT = 0;
        INTERRUPT_AFTER = 0;
        assert_ok(invert(&o, &ev, &inv2, &err), &err);
    r2 = dfle_invert_result_of(inv2);
        dfle_invert_free(inv2);
        got = slurp(name);
        assert_string_equal(got, ref);
        free(got);
    }
    /* a finished chain read back: the same result, nothing run */
    inv_opts(&o, "ref.csv", 30, 1);
    o.read_only = 1;
    assert_ok(invert(&o, NULL, &inv2, &err), &err);
    r2 = dfle_invert_result_of(inv2);
    assert_int_equal(r2->ran, 0);
    assert_memory_equal(r2->x, r->x, 31 * 8 * 3 * sizeof *r->x);
    assert_memory_equal(r2->tally, r->tally, sizeof r->tally);
    dfle_invert_free(inv2);
    /* another inversion's chain is refused, naming the difference */
    inv_opts(&o, "ref.csv", 30, 1);
    o.seed = 10;
    assert_int_equal(dfle_invert_new(&o, &inv2, &err), DFLE_EINVAL);
    assert_null(inv2);
    assert_msg_contains(err.msg, "holds another inversion's chain (seed=9 in the file, seed=10 "
                                 "here)");
    /* options checked */
    inv_opts(&o, NULL, 30, 1);
    o.walkers = 5;
    assert_int_equal(dfle_invert_check(&o, &err), DFLE_EINVAL);
    assert_string_equal(err.msg, "invert: walkers must be even and at least twice the 3 free "
                                 "parameters (got 5)");
    o.walkers = 8;
    o.burn = 30;
    assert_int_equal(dfle_invert_check(&o, &err), DFLE_EINVAL);
    assert_msg_contains(err.msg, "burn (30) must be less than steps (30)");
    dfle_invert_free(inv);
    free(ref);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(pool_results_do_not_depend_on_workers),
        cmocka_unit_test(pool_stops_on_errors),
        cmocka_unit_test(pool_interrupts_are_not_results),
        cmocka_unit_test_setup_teardown(ensemble_the_same_for_any_workers_and_resumes,
                                        model_setup, model_teardown),
        cmocka_unit_test_setup_teardown(invert_the_same_for_any_workers_and_resumes, model_setup,
                                        model_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
