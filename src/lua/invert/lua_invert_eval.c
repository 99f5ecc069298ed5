/*
 * lua_invert_eval.c - one evaluation of the log posterior in one Lua
 * state: the prior, then the forward model (build(p, channel), its steady
 * state, its slopes at the data's areas), then the likelihood.
 *
 * Everything runs protected: a failed forward run is an outcome with a
 * status and a message, counted by the sampler as zero likelihood, never
 * an error that unwinds the chain.  The model built for an evaluation is
 * closed at once: its arrays are C memory the Lua collector does not see,
 * and thousands of evaluations would otherwise pile them up.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "lua/invert/lua_invert_internal.h"

#include "dfle/likelihood.h"

enum { MODE_POSTERIOR, MODE_RESIDUALS, MODE_PREDICT };

typedef struct job {
    inv_run *R;
    const double *x;    /* natural units                        */
    int mode;
    size_t nq;          /* MODE_PREDICT: areas and slopes       */
    const double *Aq;
    double *Sq;
    /* out */
    int status;
    double lp, ll, fwd;
    char msg[INV_MSG];
} job;

/* CPU time of this thread: what the forward model costs, whatever else
 * the machine is doing (wall time on a shared machine is not). */
static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Close the model at idx (its __close frees the C model now). */
static void close_model(lua_State *L, int idx)
{
    if (luaL_getmetafield(L, idx, "__close") != LUA_TNIL) {
        lua_pushvalue(L, idx);
        lua_pushnil(L);
        lua_call(L, 2, 0);
    }
}

/* The forward model at jb->x: p, build, steady state, then residuals or
 * slopes at Aq.  Sets jb->status (INV_ACCEPTED standing for "ok"). */
static void forward(lua_State *L, int ctx, job *jb)
{
    inv_run *R = jb->R;
    int p, m, names;
    dfle_model *mm;
    const double *A, *S;
    dfle_error err;
    size_t n;
    int st;

    lua_newtable(L);
    p = lua_gettop(L);
    lua_getfield(L, ctx, "fixed");
    dfle_lua_copy_table(L, -1, p);
    lua_pop(L, 1);
    lua_getfield(L, ctx, "names");
    names = lua_gettop(L);
    for (size_t j = 0; j < R->nmodel; j++) {
        lua_geti(L, names, (lua_Integer)j + 1);
        lua_pushnumber(L, jb->x[j]);
        lua_rawset(L, p);
    }
    lua_pop(L, 1);
    lua_getfield(L, ctx, "build");
    lua_pushvalue(L, p);
    lua_getfield(L, ctx, "channel");
    lua_call(L, 2, 1);
    m = lua_gettop(L);
    if (luaL_testudata(L, m, DFLE_LUA_MODEL) == NULL)
        luaL_error(L, "build(p, channel) must return a dfle.model, got %s",
                   dfle_lua_typename(L, m));
    lua_getfield(L, m, "run_to_steady");
    lua_pushvalue(L, m);
    lua_getfield(L, ctx, "run");
    lua_call(L, 2, 1);
    if (lua_getfield(L, -1, "converged") != LUA_TBOOLEAN || !lua_toboolean(L, -1)) {
        lua_getfield(L, -2, "reason");
        snprintf(jb->msg, sizeof jb->msg, "no steady state: %s",
                 lua_tostring(L, -1) ? lua_tostring(L, -1) : "?");
        jb->status = INV_NOT_CONVERGED;
        close_model(L, m);
        return;
    }
    mm = dfle_lua_check_model(L, m);
    n = dfle_model_size(mm);
    if ((A = dfle_model_field(mm, DFLE_FIELD_A, &err)) == NULL ||
        (S = dfle_model_field(mm, DFLE_FIELD_S, &err)) == NULL) {
        close_model(L, m);
        luaL_error(L, "%s", err.msg);
    }
    if (jb->mode == MODE_PREDICT)
        st = dfle_slope_at(n, A, S, jb->nq, jb->Aq, jb->Sq, &err);
    else
        st = dfle_log_slope_residuals(n, A, S, R->nobs, R->A_obs, R->lnS_obs, R->r, &err);
    close_model(L, m);
    if (st != DFLE_OK) {
        snprintf(jb->msg, sizeof jb->msg, "%.*s", (int)sizeof jb->msg - 1, err.msg);
        jb->status = INV_INVALID;
        return;
    }
    jb->status = INV_ACCEPTED;
}

/* eval_p(ctx, job): runs protected. */
static int eval_p(lua_State *L)
{
    job *jb = lua_touserdata(L, 2);
    inv_run *R = jb->R;
    double lprior = 0, t0;

    jb->lp = jb->ll = -INFINITY;
    if (jb->mode == MODE_POSTERIOR) {
        for (size_t j = 0; j < R->d; j++)
            lprior += dfle_prior_logpdf(&R->prior[j], jb->x[j]);
        if (!(lprior > -INFINITY)) {
            jb->status = INV_OUTSIDE;
            snprintf(jb->msg, sizeof jb->msg, "outside the prior");
            return 0;
        }
        for (size_t j = 0; j < R->d; j++) {
            double v;
            if (!R->custom[j])
                continue;
            lua_getfield(L, 1, "density");
            lua_getfield(L, 1, "names");
            lua_geti(L, -1, (lua_Integer)j + 1);
            lua_gettable(L, -3);
            lua_pushnumber(L, jb->x[j]);
            lua_call(L, 1, 1);
            if (lua_type(L, -1) != LUA_TNUMBER) {
                lua_geti(L, -2, (lua_Integer)j + 1);
                return luaL_error(L, "the prior density of '%s' must return a number (ln p), got "
                                     "%s", lua_tostring(L, -1), luaL_typename(L, -2));
            }
            v = lua_tonumber(L, -1);
            lua_pop(L, 3);
            if (isnan(v) || v == INFINITY) {
                lua_getfield(L, 1, "names");
                lua_geti(L, -1, (lua_Integer)j + 1);
                return luaL_error(L, "the prior density of '%s' returned %s at %s",
                                  lua_tostring(L, -1), dfle_lua_number_text(L, v),
                                  dfle_lua_number_text(L, jb->x[j]));
            }
            lprior += v;
        }
        if (!(lprior > -INFINITY)) {
            jb->status = INV_OUTSIDE;
            snprintf(jb->msg, sizeof jb->msg, "zero prior density");
            return 0;
        }
    }
    t0 = now();
    forward(L, 1, jb);
    jb->fwd += now() - t0;
    if (jb->status != INV_ACCEPTED || jb->mode != MODE_POSTERIOR)
        return 0;
    jb->ll = dfle_gauss_loglike(R->nobs, R->r, R->sigma_free ? jb->x[R->d - 1] : R->sigma);
    if (!(jb->ll > -INFINITY)) {
        jb->status = INV_INVALID;
        snprintf(jb->msg, sizeof jb->msg, "the likelihood is zero or NaN");
        return 0;
    }
    jb->lp = lprior + jb->ll;
    return 0;
}

static void run_job(lua_State *L, int ctx, job *jb)
{
    int top = lua_gettop(L);
    ctx = lua_absindex(L, ctx);
    jb->status = INV_ERROR;
    jb->msg[0] = '\0';
    /* Parallel calls made by build run here, in this state. */
    dfle_lua_par_depth(L, +1);
    lua_pushcfunction(L, eval_p);
    lua_pushvalue(L, ctx);
    lua_pushlightuserdata(L, jb);
    if (lua_pcall(L, 2, 0, 0) != LUA_OK) {
        const char *m = lua_tostring(L, -1);
        jb->status = INV_ERROR;
        jb->lp = jb->ll = -INFINITY;
        snprintf(jb->msg, sizeof jb->msg, "%s", m != NULL ? m : "(error object is not a string)");
    }
    dfle_lua_par_depth(L, -1);
    lua_settop(L, top);
    /* Keep the collector up with the userdata each run leaves behind. */
    lua_gc(L, LUA_GCSTEP, 0);
}

/* A job of `mode` at x, run in L; the job is left for the caller. */
static void run(lua_State *L, int ctx, inv_run *R, const double *x, int mode, job *jb)
{
    memset(jb, 0, sizeof *jb);
    jb->R = R;
    jb->x = x;
    jb->mode = mode;
    run_job(L, ctx, jb);
}

int inv_eval(lua_State *L, int ctx, inv_run *R, const double *x, double *lp, double *ll,
             double *fwd, char *msg, size_t msglen)
{
    job jb;
    run(L, ctx, R, x, MODE_POSTERIOR, &jb);
    *lp = jb.lp;
    *ll = jb.ll;
    *fwd += jb.fwd;
    if (msg != NULL)
        snprintf(msg, msglen, "%s", jb.msg);
    return jb.status;
}

int inv_residuals(lua_State *L, int ctx, inv_run *R, const double *x, double *fwd,
                  dfle_error *err)
{
    job jb;
    run(L, ctx, R, x, MODE_RESIDUALS, &jb);
    *fwd += jb.fwd;
    if (jb.status != INV_ACCEPTED)
        return dfle_error_set(err, DFLE_EFIT, "%s", jb.msg);
    return DFLE_OK;
}

int inv_predict_at(lua_State *L, int ctx, inv_run *R, const double *x, size_t n,
                   const double *Aq, double *Sq, char *msg, size_t msglen)
{
    job jb;
    memset(&jb, 0, sizeof jb);
    jb.R = R;
    jb.x = x;
    jb.mode = MODE_PREDICT;
    jb.nq = n;
    jb.Aq = Aq;
    jb.Sq = Sq;
    run_job(L, ctx, &jb);
    if (msg != NULL)
        snprintf(msg, msglen, "%s", jb.msg);
    return jb.status;
}
