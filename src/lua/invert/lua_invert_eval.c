/*
 * lua_invert_eval.c - one evaluation in one Lua state: the priors
 * written in Lua, then the forward model (build(p, channel), its steady
 * state, its slopes at the data's areas), then the likelihood (the
 * driver adds the other priors, dfle/invert_run.h).
 *
 * Everything runs protected: a failed forward run is an outcome with a
 * status and a message, counted by the sampler (dfle/invert_run.h) as
 * zero likelihood, never an error that unwinds the chain.  The model
 * built for an evaluation is closed at once: its arrays are C memory the
 * Lua collector does not see, and thousands of evaluations would
 * otherwise pile them up.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "lua/invert/lua_invert_internal.h"

#include "dfle/likelihood.h"

enum { MODE_RESIDUALS, MODE_PREDICT };

typedef struct job {
    inv_run *R;
    const double *x;    /* natural units                        */
    int mode;
    size_t nq;          /* MODE_PREDICT: areas and slopes       */
    const double *Aq;
    double *Sq;
    /* out */
    int status;         /* DFLE_EVAL_*                          */
    double fwd;
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
 * slopes at Aq.  Sets jb->status; raises what build or the run raise. */
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
        jb->status = DFLE_EVAL_NOT_CONVERGED;
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
        jb->status = DFLE_EVAL_INVALID;
        return;
    }
    jb->status = DFLE_EVAL_OK;
}

/* ------------------------------------------------------------------ */
/* The evaluator's sample: ln L and the Lua densities of a proposal.   */

/* sample(ctx, job): runs protected (lua_evaluator.c); a raise is an
 * error of this proposal. */
static int sample(lua_State *L)
{
    const dfle_lua_job *jl = lua_touserdata(L, 2);
    dfle_eval_out *out = jl->out;
    inv_run *R;
    job jb;
    int zero = 0;

    lua_getfield(L, 1, "box");
    R = lua_touserdata(L, -1);
    lua_pop(L, 1);
    /* res.forward_seconds is the forward model's own time: not the
     * priors, the calls into Lua, the collector (0 if it raises) */
    out->seconds = 0;
    /* The priors written in Lua (the driver has checked the others'
     * support): all of them, then the forward model only if none is 0. */
    for (size_t j = 0; j < R->d; j++) {
        double v;
        if (!R->custom[j])
            continue;
        lua_getfield(L, 1, "density");
        lua_getfield(L, 1, "names");
        lua_geti(L, -1, (lua_Integer)j + 1);
        lua_gettable(L, -3);
        lua_pushnumber(L, jl->x[j]);
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
                              dfle_lua_number_text(L, jl->x[j]));
        }
        out->y[1 + j] = v;
        zero |= v == -INFINITY;
    }
    if (zero) {
        out->status = DFLE_EVAL_OUTSIDE;
        dfle_eval_reason(out, "zero prior density");
        return 0;
    }
    memset(&jb, 0, sizeof jb);
    jb.R = R;
    jb.x = jl->x;
    jb.mode = MODE_RESIDUALS;
    {
        double t0 = now();
        forward(L, 1, &jb);
        out->seconds = now() - t0;
    }
    if (jb.status != DFLE_EVAL_OK) {
        out->status = jb.status;
        dfle_eval_reason(out, "%s", jb.msg);
        return 0;
    }
    out->y[0] = dfle_gauss_loglike(R->nobs, R->r, R->sigma_free ? jl->x[R->d - 1] : R->sigma);
    return 0;
}

/* prepare(table): a worker's context. */
static int prepare(lua_State *L)
{
    inv_run *R;
    lua_settop(L, 1);
    inv_read_spec(L, 1, &R);
    return 1;
}

const dfle_lua_kind inv_kind = {
    .kind = DFLE_LUA_PAR_INVERT,
    .name = "lua.invert",
    .prepare = prepare,
    .what = "inversion",
    .sample = sample,
    .raw_numbers = 0,
    .gc_step = 1,
};

/* ------------------------------------------------------------------ */
/* The point estimate's and the predictions' runs, in the main state.  */

/* run_p(ctx, job): runs protected. */
static int run_p(lua_State *L)
{
    job *jb = lua_touserdata(L, 2);
    double t0 = now();
    forward(L, 1, jb);
    jb->fwd += now() - t0;
    return 0;
}

static void run_job(lua_State *L, int ctx, job *jb)
{
    int top = lua_gettop(L);
    ctx = lua_absindex(L, ctx);
    jb->status = DFLE_EVAL_ERROR;
    jb->msg[0] = '\0';
    /* Parallel calls made by build run here, in this state. */
    dfle_lua_par_depth(L, +1);
    lua_pushcfunction(L, run_p);
    lua_pushvalue(L, ctx);
    lua_pushlightuserdata(L, jb);
    if (lua_pcall(L, 2, 0, 0) != LUA_OK) {
        const char *m = lua_tostring(L, -1);
        jb->status = DFLE_EVAL_ERROR;
        snprintf(jb->msg, sizeof jb->msg, "%s", m != NULL ? m : "(error object is not a string)");
    }
    dfle_lua_par_depth(L, -1);
    lua_settop(L, top);
    /* Keep the collector up with the userdata each run leaves behind. */
    lua_gc(L, LUA_GCSTEP, 0);
}

int inv_residuals(lua_State *L, int ctx, inv_run *R, const double *x, double *fwd,
                  dfle_error *err)
{
    job jb;
    memset(&jb, 0, sizeof jb);
    jb.R = R;
    jb.x = x;
    jb.mode = MODE_RESIDUALS;
    run_job(L, ctx, &jb);
    *fwd += jb.fwd;
    if (jb.status != DFLE_EVAL_OK)
        return dfle_error_set(err, DFLE_EFIT, "%s", jb.msg);
    return DFLE_OK;
}

int inv_predict_at(lua_State *L, int ctx, inv_run *R, const double *x, size_t n,
                   const double *Aq, double *Sq)
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
    return jb.status;
}
