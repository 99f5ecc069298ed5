/*
 * lsq.c - bounded least squares by Nelder-Mead with a finite-difference
 * covariance at the answer (see dfle/lsq.h for why this combination).
 *
 * GSL's simplex refuses a non-finite value at a starting vertex and
 * only compares values afterwards, so a point with no value (out of
 * bounds, a failed forward run) gets a huge finite value instead, and a
 * starting vertex without a value is moved back towards the start.
 */
#include "dfle/lsq.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <stdio.h>

#include <gsl/gsl_blas.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_matrix.h>
#include <gsl/gsl_multimin.h>
#include <gsl/gsl_vector.h>

#define NO_VALUE 1e300

typedef struct job {
    const dfle_lsq_opts *o;
    dfle_lsq_fn f;
    void *ud;
    double *r;       /* m residuals: scratch                     */
    size_t evals, failed, max_evals;
    int status;      /* a fatal status from f                    */
    dfle_error *err;
} job;

static int inside(const job *jb, const double *u)
{
    for (size_t j = 0; j < jb->o->n; j++) {
        if (!isfinite(u[j]))
            return 0;
        if (jb->o->lo != NULL && u[j] < jb->o->lo[j])
            return 0;
        if (jb->o->hi != NULL && u[j] > jb->o->hi[j])
            return 0;
    }
    return 1;
}

/* Residuals at u into jb->r: 0, or 1 when there is no value there. */
static int residuals(job *jb, const double *u)
{
    int st;
    if (jb->status != DFLE_OK || !inside(jb, u))
        return 1;
    jb->evals++;
    st = jb->f(jb->ud, u, jb->r, jb->err);
    if (st == DFLE_EFIT) {
        jb->failed++;
        return 1;
    }
    if (st != DFLE_OK) {
        jb->status = st;
        return 1;
    }
    for (size_t i = 0; i < jb->o->m; i++)
        if (!isfinite(jb->r[i])) {
            jb->failed++;
            return 1;
        }
    return 0;
}

static double rss_at(job *jb, const double *u)
{
    double s = 0;
    if (residuals(jb, u) != 0)
        return NO_VALUE;
    for (size_t i = 0; i < jb->o->m; i++)
        s += jb->r[i] * jb->r[i];
    return s;
}

static double objective(const gsl_vector *v, void *p)
{
    return rss_at(p, v->data);
}

/* One simplex search from u with steps `step`; the answer into u. */
static int simplex(job *jb, double *u, const double *step, double *fval, int *converged,
                   dfle_error *err)
{
    const size_t n = jb->o->n;
    gsl_multimin_fminimizer *s = gsl_multimin_fminimizer_alloc(gsl_multimin_fminimizer_nmsimplex2, n);
    gsl_vector *x = gsl_vector_alloc(n), *ss = gsl_vector_alloc(n);
    gsl_multimin_function fn;
    double mean_step = 0, *trial = malloc(n * sizeof *trial);
    int st = DFLE_OK, iterated = 0;

    *converged = 0;
    if (s == NULL || x == NULL || ss == NULL || trial == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "lsq: out of memory");
        goto done;
    }
    /* A starting vertex must have a value: try the step backwards, then
     * shorter steps, until it does (or give that direction a tiny step). */
    for (size_t j = 0; j < n; j++) {
        double h = step[j];
        memcpy(trial, u, n * sizeof *trial);
        for (int k = 0; k < 12; k++) {
            trial[j] = u[j] + h;
            if (rss_at(jb, trial) < NO_VALUE)
                break;
            trial[j] = u[j] - h;
            if (rss_at(jb, trial) < NO_VALUE) {
                h = -h;
                break;
            }
            h *= 0.5;
        }
        if (jb->status != DFLE_OK)
            goto fatal;
        gsl_vector_set(ss, j, h);
        mean_step += fabs(h) / (double)n;
        gsl_vector_set(x, j, u[j]);
    }
    fn.f = objective;
    fn.n = n;
    fn.params = jb;
    if (gsl_multimin_fminimizer_set(s, &fn, x, ss) != GSL_SUCCESS) {
        st = dfle_error_set(err, DFLE_EFIT, "lsq: the simplex could not start");
        goto done;
    }
    while (jb->evals < jb->max_evals) {
        int it = gsl_multimin_fminimizer_iterate(s);
        if (jb->status != DFLE_OK)
            goto fatal;
        if (it != GSL_SUCCESS)
            break;
        iterated = 1;
        if (gsl_multimin_test_size(gsl_multimin_fminimizer_size(s),
                                   (jb->o->tol > 0 ? jb->o->tol : 1e-6) * mean_step) ==
            GSL_SUCCESS) {
            *converged = 1;
            break;
        }
    }
    /* GSL sets the minimizer's best point and value in iterate, not in
     * set: with no successful iteration (a simplex that cannot make
     * progress from the start) they are unset, and the start stands. */
    if (iterated) {
        memcpy(u, gsl_multimin_fminimizer_x(s)->data, n * sizeof *u);
        *fval = gsl_multimin_fminimizer_minimum(s);
    } else {
        *fval = rss_at(jb, u);
        if (jb->status != DFLE_OK)
            goto fatal;
    }
    goto done;
fatal:
    st = jb->status;
done:
    gsl_multimin_fminimizer_free(s);
    gsl_vector_free(x);
    gsl_vector_free(ss);
    free(trial);
    return st;
}

/* C = s2 (J^T J)^-1 by central differences (one-sided at a bound or
 * where one side has no value).  Returns 1 on success. */
static int covariance(job *jb, const double *u, const double *step, double s2, double *cov,
                      char *why, size_t whylen)
{
    const size_t n = jb->o->n, m = jb->o->m;
    gsl_matrix *J = gsl_matrix_alloc(m, n), *JtJ = gsl_matrix_alloc(n, n);
    double *r0 = malloc(m * sizeof *r0), *rp = malloc(m * sizeof *rp), *t = malloc(n * sizeof *t);
    int ok = 0;

    if (J == NULL || JtJ == NULL || r0 == NULL || rp == NULL || t == NULL) {
        snprintf(why, whylen, "out of memory");
        goto done;
    }
    if (residuals(jb, u) != 0) {
        snprintf(why, whylen, "no value at the answer");
        goto done;
    }
    memcpy(r0, jb->r, m * sizeof *r0);
    for (size_t j = 0; j < n; j++) {
        double h = 1e-3 * step[j], hp, hm;
        int up, down;
        memcpy(t, u, n * sizeof *t);
        t[j] = u[j] + h;
        up = residuals(jb, t) == 0;
        if (up)
            memcpy(rp, jb->r, m * sizeof *rp);
        t[j] = u[j] - h;
        down = residuals(jb, t) == 0;
        hp = up ? h : 0;
        hm = down ? h : 0;
        if (!up && !down) {
            snprintf(why, whylen, "no value on either side of the answer in parameter %zu", j + 1);
            goto done;
        }
        for (size_t i = 0; i < m; i++) {
            double a = up ? rp[i] : r0[i], b = down ? jb->r[i] : r0[i];
            gsl_matrix_set(J, i, j, (a - b) / (hp + hm));
        }
    }
    gsl_blas_dgemm(CblasTrans, CblasNoTrans, 1.0, J, J, 0.0, JtJ);
    if (gsl_linalg_cholesky_decomp1(JtJ) != GSL_SUCCESS ||
        gsl_linalg_cholesky_invert(JtJ) != GSL_SUCCESS) {
        snprintf(why, whylen, "J^T J is singular: the data do not constrain every parameter "
                 "linearly at the answer");
        goto done;
    }
    for (size_t a = 0; a < n; a++)
        for (size_t b = 0; b < n; b++)
            cov[a * n + b] = s2 * gsl_matrix_get(JtJ, a, b);
    ok = 1;
done:
    gsl_matrix_free(J);
    gsl_matrix_free(JtJ);
    free(r0);
    free(rp);
    free(t);
    return ok;
}

int dfle_lsq_fit(const dfle_lsq_opts *o, dfle_lsq_fn f, void *ud, double *u, double *cov,
                 dfle_lsq_info *info, dfle_error *err)
{
    job jb;
    double f1 = NO_VALUE, f2 = NO_VALUE, *u2 = NULL;
    int conv1 = 0, conv2 = 0, st;

    memset(info, 0, sizeof *info);
    if (o->n < 1 || o->m <= o->n)
        return dfle_error_set(err, DFLE_EINVAL, "lsq: need more residuals (%zu) than "
                              "parameters (%zu)", o->m, o->n);
    for (size_t j = 0; j < o->n; j++)
        if (!(o->step[j] > 0) || !isfinite(o->u0[j]))
            return dfle_error_set(err, DFLE_EINVAL, "lsq: parameter %zu needs a finite start and "
                                  "a step > 0 (got %g, %g)", j + 1, o->u0[j], o->step[j]);
    memset(&jb, 0, sizeof jb);
    jb.o = o;
    jb.f = f;
    jb.ud = ud;
    jb.err = err;
    jb.max_evals = o->max_evals > 0 ? o->max_evals : 400 * (o->n + 1);
    jb.r = malloc(o->m * sizeof *jb.r);
    u2 = malloc(o->n * sizeof *u2);
    if (jb.r == NULL || u2 == NULL) {
        st = dfle_error_set(err, DFLE_ENOMEM, "lsq: out of memory");
        goto done;
    }
    memcpy(u, o->u0, o->n * sizeof *u);
    if (rss_at(&jb, u) >= NO_VALUE) {
        st = jb.status != DFLE_OK ? jb.status
                                  : dfle_error_set(err, DFLE_EFIT, "lsq: no value at the start");
        goto done;
    }
    if ((st = simplex(&jb, u, o->step, &f1, &conv1, err)) != DFLE_OK)
        goto done;
    /* The restart: a fresh simplex a tenth the size around the answer. */
    {
        double *s10 = malloc(o->n * sizeof *s10);
        if (s10 == NULL) {
            st = dfle_error_set(err, DFLE_ENOMEM, "lsq: out of memory");
            goto done;
        }
        for (size_t j = 0; j < o->n; j++)
            s10[j] = 0.1 * o->step[j];
        memcpy(u2, u, o->n * sizeof *u2);
        st = simplex(&jb, u2, s10, &f2, &conv2, err);
        free(s10);
        if (st != DFLE_OK)
            goto done;
        if (f2 < f1) {
            memcpy(u, u2, o->n * sizeof *u);
            f1 = f2;
        }
    }
    info->rss = f1;
    info->converged = conv1 && conv2;
    if (!info->converged)
        snprintf(info->why, sizeof info->why, "stopped after %zu evaluations before the simplex "
                 "shrank to tol", jb.evals);
    info->s2 = o->sigma > 0 ? o->sigma * o->sigma : f1 / (double)(o->m - o->n);
    if (cov != NULL) {
        for (size_t k = 0; k < o->n * o->n; k++)
            cov[k] = NAN;
        info->cov_ok = covariance(&jb, u, o->step, info->s2, cov, info->why, sizeof info->why);
        if (jb.status != DFLE_OK) {
            st = jb.status;
            goto done;
        }
    }
    st = DFLE_OK;
done:
    info->evaluations = jb.evals;
    info->failed = jb.failed;
    free(jb.r);
    free(u2);
    return st;
}
