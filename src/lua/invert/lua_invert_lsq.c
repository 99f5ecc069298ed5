/*
 * lua_invert_lsq.c - dfle.invert's least-squares point estimate: the
 * residuals of the forward model minimised by the library's bounded
 * Nelder-Mead (dfle/lsq.h) in the sampler's coordinates, in the main
 * state, one run at a time, and the table res.lsq.
 *
 * Kept apart from the sampling loop: it shares the forward model
 * (lua_invert_eval.c) but nothing of the chain.
 */
#include <math.h>
#include <string.h>

#include "lua/invert/lua_invert_internal.h"

#include "dfle/lsq.h"

/* ------------------------------------------------------------------ */
/* The least-squares point estimate (main state, one run at a time).   */

typedef struct lsq_job {
    lua_State *L;
    int ctx;
    inv_run *R;
    double *x;
} lsq_job;

static int lsq_residuals(void *ud, const double *u, double *r, dfle_error *err)
{
    lsq_job *jb = ud;
    inv_run *R = jb->R;
    for (size_t j = 0; j < R->nmodel; j++) {
        jb->x[j] = R->logs[j] ? exp(u[j]) : u[j];
        if (!(dfle_prior_logpdf(&R->prior[j], jb->x[j]) > -INFINITY))
            return DFLE_EFIT;
    }
    if (inv_residuals(jb->L, jb->ctx, R, jb->x, &R->lsq_seconds, err) != DFLE_OK)
        return DFLE_EFIT;
    R->lsq_evaluations++;
    memcpy(r, R->r, R->nobs * sizeof *r);
    return DFLE_OK;
}

static void set_named(lua_State *L, int names, size_t j, double v)
{
    lua_geti(L, names, (lua_Integer)j + 1);
    lua_pushnumber(L, v);
    lua_settable(L, -3);
}

/* Push the point estimate's table (never raises on a failed fit: the
 * table says why). */
void inv_push_lsq(lua_State *L, int ctx, inv_run *R)
{
    const size_t n = R->nmodel;
    double *u0, *step, *lo, *hi, *u, *cov, *x;
    dfle_lsq_opts o;
    dfle_lsq_info info;
    dfle_error err;
    lsq_job jb;
    int st, names, t;

    u0 = lua_newuserdatauv(L, 7 * n * sizeof *u0 + n * n * sizeof *u0, 0);
    step = u0 + n;
    lo = step + n;
    hi = lo + n;
    u = hi + n;
    x = u + n;
    cov = x + 2 * n;
    for (size_t j = 0; j < n; j++) {
        u0[j] = dfle_prior_center(&R->prior[j]);
        step[j] = dfle_prior_width(&R->prior[j]);
        dfle_prior_bounds(&R->prior[j], &lo[j], &hi[j]);
    }
    memset(&o, 0, sizeof o);
    o.n = n;
    o.m = R->nobs;
    o.u0 = u0;
    o.step = step;
    o.lo = lo;
    o.hi = hi;
    o.sigma = R->sigma_free ? 0 : R->sigma;
    jb.L = L;
    jb.ctx = ctx;
    jb.R = R;
    jb.x = x;
    lua_getfield(L, ctx, "names");
    names = lua_gettop(L);
    st = dfle_lsq_fit(&o, lsq_residuals, &jb, u, cov, &info, &err);
    lua_createtable(L, 0, 12);
    t = lua_gettop(L);
    lua_pushboolean(L, st == DFLE_OK && info.converged), lua_setfield(L, t, "converged");
    lua_pushinteger(L, (lua_Integer)info.evaluations), lua_setfield(L, t, "evaluations");
    lua_pushinteger(L, (lua_Integer)info.failed), lua_setfield(L, t, "failed");
    if (st != DFLE_OK) {
        lua_pushstring(L, err.msg), lua_setfield(L, t, "why");
        lua_remove(L, names);
        lua_remove(L, t - 2); /* the scratch */
        return;
    }
    if (info.why[0] != '\0')
        lua_pushstring(L, info.why), lua_setfield(L, t, "why");
    lua_pushnumber(L, info.rss), lua_setfield(L, t, "rss");
    lua_pushnumber(L, sqrt(info.rss / (double)(R->nobs - n))), lua_setfield(L, t, "sigma");
    lua_pushboolean(L, info.cov_ok), lua_setfield(L, t, "cov_ok");
    /* values, sd (delta method for log-scaled ones) and 95 % intervals */
    {
        const char *keys[5] = {"values", "sd", "lo95", "hi95", "log_scale"};
        for (int k = 0; k < 5; k++) {
            lua_createtable(L, 0, (int)n);
            for (size_t j = 0; j < n; j++) {
                double sdu = sqrt(cov[j * n + j]), v = R->logs[j] ? exp(u[j]) : u[j];
                if (k == 4) {
                    lua_geti(L, names, (lua_Integer)j + 1);
                    lua_pushboolean(L, R->logs[j]);
                    lua_settable(L, -3);
                    continue;
                }
                set_named(L, names, j,
                          k == 0   ? v
                          : k == 1 ? (R->logs[j] ? v * sdu : sdu)
                          : k == 2 ? (R->logs[j] ? exp(u[j] - 1.96 * sdu) : u[j] - 1.96 * sdu)
                                   : (R->logs[j] ? exp(u[j] + 1.96 * sdu) : u[j] + 1.96 * sdu));
            }
            lua_setfield(L, t, keys[k]);
        }
    }
    /* covariance and correlation in the sampler's coordinates (ln x for
     * log-scaled parameters), rows in the order of `names` */
    for (int k = 0; k < 2; k++) {
        lua_createtable(L, (int)n, 0);
        for (size_t a = 0; a < n; a++) {
            lua_createtable(L, (int)n, 0);
            for (size_t b = 0; b < n; b++) {
                double c = cov[a * n + b];
                if (k == 1)
                    c /= sqrt(cov[a * n + a] * cov[b * n + b]);
                lua_pushnumber(L, c);
                lua_rawseti(L, -2, (lua_Integer)b + 1);
            }
            lua_rawseti(L, -2, (lua_Integer)a + 1);
        }
        lua_setfield(L, t, k == 0 ? "cov" : "corr");
    }
    lua_remove(L, names);
    lua_remove(L, t - 2); /* the scratch */
}

