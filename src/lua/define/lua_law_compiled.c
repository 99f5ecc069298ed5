/*
 * lua_law_compiled.c - dfle.law.define laws run as compiled programs
 * (lua_law_compiled.h), the layer between the Lua sweep below
 * (lua_law_sweep.c) and the law's ops above (lua_law_define.c).
 *
 * The ops ask here first for every call: each of the law's functions is
 * traced once (lua_trace.h) and, if the tracer accepts it, evaluated in
 * C over all the nodes of the call; the program is checked bit for bit
 * against the Lua sweep on its first use.  Whatever this file cannot do
 * (a refused function, a non-finite value, an area not in the frequency
 * memo yet) it hands back with TRY_LUA, and the Lua sweep does it, with
 * its own error messages.  law:compiled() reports the state.
 *
 * A program comes from the state's cache (lua_trace_cache.c) when an
 * earlier law traced the same function and its guards hold for this law;
 * that program was checked against Lua when it was traced, and is not
 * checked again.  Otherwise the function is traced and checked, and once
 * the check has passed the program goes into the cache.
 *
 * For the node solvers the programs are also differentiated forward
 * (ll_compiled_rate_dlnS, the law's rate_dlnS op while they can be).
 */
#include "lua/define/lua_law_compiled.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The fields the function of `op` may read (bit F_x), as fetch() allows. */
static unsigned op_fields(const lua_law *ll, int op)
{
    if (op == OP_FACTOR)
        return ((1u << N_IN) - 1) & ~(1u << F_F);
    if (ll->has_factor || op == OP_RATE_TR)
        return SPLIT_RATE_FIELDS;
    return (1u << N_IN) - 1;
}

/* The program of the function at fslot for spec: from the cache, or
 * traced now (*fresh = 1: it must be checked against Lua before it is
 * trusted or cached).  Leaves its guard table (or nil) on top of T. */
static dfle_trace_prog *get_program(lua_law *ll, int fslot, const dfle_trace_spec *spec,
                                    int *fresh, char *why, size_t why_len)
{
    lua_State *T = ll->sh.T;
    dfle_trace_prog *p = NULL;
    lua_settop(T, SLOT_COUNT);
    if (ll->cache) {
        if ((p = dfle_trace_cache_find(T, fslot, SLOT_PARAMS, spec)) != NULL) {
            *fresh = 0;
            return p;
        }
        lua_pop(T, 1);
    }
    *fresh = 1;
    return dfle_trace_compile(T, fslot, SLOT_PARAMS, spec, why, why_len);
}

/* A check against Lua has run (counted for the tests and the bench). */
static void count_check(lua_law *ll)
{
    dfle_trace_stats *st = dfle_trace_stats_of(ll->sh.T);
    if (st != NULL)
        st->checked++;
}

/* The spec of op's function (fields it may read; float params as inputs
 * when programs are shared). */
static dfle_trace_spec op_spec(const lua_law *ll, int op)
{
    const dfle_trace_spec spec = {N_IN, ll_field_names, op_fields(ll, op), 0, ll->cache};
    return spec;
}

/* Note what op's program now holds values for (lua_law.fresh); val: its
 * values, NULL when it has none. */
static void mark_fresh(lua_law *ll, int op, const dfle_law_ctx *ctx, const double *F_in,
                       const double *val)
{
    ll->fresh[op] = val != NULL;
    ll->fresh_in[op][0] = op == OP_FACTOR ? (const void *)ctx->flow : (const void *)ctx->S;
    ll->fresh_in[op][1] = op == OP_FACTOR ? NULL : F_in;
    ll->fresh_n[op] = ctx->n;
    ll->fresh_val[op] = val;
}

/* Run `op` through its compiled form, compiling it first if need be.
 * Returns TRY_LUA when the Lua sweep must do it instead: the function
 * cannot be compiled, a value is not finite (so that Lua reports it the
 * usual way), or a frequency(A) is not memoised yet.  A program is
 * checked against the Lua sweep, bit for bit, on its first use. */
int ll_compiled_sweep(lua_law *ll, int op, const dfle_law_ctx *ctx, const double *F_in,
                      double *out, dfle_error *err)
{
    lua_State *T = ll->sh.T;
    const size_t n = ctx->n;
    const double *src[N_IN];
    const double *val;
    double *dst = out;
    const int fslot = op == OP_FACTOR ? SLOT_FACTOR : SLOT_RATE;
    const dfle_trace_spec spec = op_spec(ll, op);
    dfle_trace_prog *p;
    unsigned used;
    int verify = 0;

    ll->op = op, ll->ctx = ctx, ll->F_in = F_in; /* for ll_field_source() */
    if (ll->prog[op] != NULL && ll->seen[op] != *ll->epoch) {
        lua_settop(T, SLOT_COUNT);
        if (!dfle_trace_guards_hold(T, SLOT_GUARDS_FACTOR + op, ll->prog[op])) {
            dfle_trace_free(ll->prog[op]); /* something it read has changed */
            ll->fresh[op] = 0;
            ll->prog[op] = NULL;
        }
        ll->seen[op] = *ll->epoch;
    }
    if (ll->prog[op] == NULL) {
        ll->prog[op] = get_program(ll, fslot, &spec, &ll->unchecked[op], ll->why[op],
                                   sizeof ll->why[op]);
        lua_replace(T, SLOT_GUARDS_FACTOR + op);
        if (ll->prog[op] == NULL) {
            ll->cstate[op] = -1;
            return TRY_LUA;
        }
        ll->cstate[op] = 1;
        ll->seen[op] = *ll->epoch;
    }
    p = ll->prog[op];
    /* A new program is checked on the first call it completes (a call
     * handed to Lua before that, for a value not finite, does not count). */
    verify = ll->unchecked[op];
    if (verify) {
        if (n > ll->scratch_cap) {
            double *s = realloc(ll->scratch, n * sizeof *s);
            if (s == NULL)
                return TRY_LUA;
            ll->scratch = s;
            ll->scratch_cap = n;
        }
        dst = ll->scratch;
    }
    used = dfle_trace_inputs(p);
    for (int f = 0; f < N_IN; f++)
        src[f] = used & (1u << f) ? ll_field_source(ll, f) : NULL;
    val = dfle_trace_eval_n(p, n, src);
    mark_fresh(ll, op, ctx, F_in, val);
    if (val == NULL)
        return TRY_LUA;
    for (size_t i = 0; i < n; i++) {
        double e = val[i];
        size_t at;
        /* No erosion up a reverse slope or without flow: as the driver. */
        if (op != OP_FACTOR && !(ctx->S[i] > 0 && F_in[i] != 0)) {
            dst[i] = 0.0;
            continue;
        }
        if (!isfinite(e))
            return TRY_LUA;
        if (op != OP_FACTOR && ll->has_frequency && e != 0) {
            if (!ll_memo_find(ll, ctx->A[i], &at))
                return TRY_LUA;
            e *= ll->fv[at];
        }
        dst[i] = e;
    }
    if (verify) {
        int st = ll_interpreted_sweep(ll, op, ctx, F_in, out, err);
        size_t i;
        if (st != DFLE_OK) {
            /* No check happened: trace (and check) again next time. */
            dfle_trace_free(p);
            ll->fresh[op] = 0;
            ll->prog[op] = NULL;
            ll->cstate[op] = 0;
            return st;
        }
        count_check(ll);
        for (i = 0; i < n; i++) {
            if (memcmp(&out[i], &dst[i], sizeof *dst) != 0) {
                snprintf(ll->why[op], sizeof ll->why[op],
                         "its compiled form gave %.17g where Lua gives %.17g (node %zu)", dst[i],
                         out[i], i + 1);
                dfle_trace_free(p);
                ll->fresh[op] = 0;
                ll->prog[op] = NULL;
                ll->cstate[op] = -1;
                break;
            }
        }
        ll->unchecked[op] = 0;
        if (i == n && ll->cache) {
            lua_settop(T, SLOT_COUNT);
            dfle_trace_cache_put(T, fslot, SLOT_PARAMS, &spec, p, SLOT_GUARDS_FACTOR + op);
        }
    }
    return DFLE_OK;
}

/* Calls of a newly compiled integrand checked against Lua. */
#define G_VERIFY_CALLS 64

/* The integrand through its compiled form; TRY_LUA asks for the Lua call
 * (not compilable, or a value that is not finite, which Lua reports). */
int ll_compiled_integrand(lua_law *ll, double h, double v, double lambda, double *g,
                          dfle_error *err)
{
    static const char *const names[] = {"h", "v", "lambda"};
    const dfle_trace_spec spec = {3, names, 7u, 1, ll->cache};
    lua_State *T = ll->sh.T;
    const double in[3] = {h, v, lambda};
    double gc, gl;
    int st, fresh;

    if (ll->gprog != NULL && ll->gseen != *ll->epoch) {
        lua_settop(T, SLOT_COUNT);
        if (!dfle_trace_guards_hold(T, SLOT_GUARDS_G, ll->gprog)) {
            dfle_trace_free(ll->gprog);
            ll->gprog = NULL;
        }
        ll->gseen = *ll->epoch;
    }
    if (ll->gprog == NULL) {
        ll->gprog = get_program(ll, SLOT_INTEGRAND, &spec, &fresh, ll->gwhy, sizeof ll->gwhy);
        lua_replace(T, SLOT_GUARDS_G);
        if (ll->gprog == NULL) {
            ll->gstate = -1;
            return TRY_LUA;
        }
        ll->gstate = 1;
        ll->gseen = *ll->epoch;
        ll->gverify = fresh ? G_VERIFY_CALLS : 0;
    }
    gc = dfle_trace_eval(ll->gprog, in);
    if (!isfinite(gc))
        return TRY_LUA;
    if (ll->gverify == 0) {
        *g = gc;
        return DFLE_OK;
    }
    if ((st = ll_lua_integrand(ll, h, v, lambda, &gl, err)) != DFLE_OK)
        return st; /* this call is not a check: gverify stays */
    ll->gverify--;
    if (memcmp(&gc, &gl, sizeof gc) != 0) {
        snprintf(ll->gwhy, sizeof ll->gwhy,
                 "its compiled form gave %.17g where Lua gives %.17g (h = %g, v = %g, "
                 "lambda = %g)", gc, gl, h, v, lambda);
        dfle_trace_free(ll->gprog);
        ll->gprog = NULL;
        ll->gstate = -1;
    } else if (ll->gverify == 0) {
        count_check(ll); /* all G_VERIFY_CALLS agreed */
        if (ll->cache) {
            lua_settop(T, SLOT_COUNT);
            dfle_trace_cache_put(T, SLOT_INTEGRAND, SLOT_PARAMS, &spec, ll->gprog, SLOT_GUARDS_G);
        }
    }
    *g = gl;
    return DFLE_OK;
}

static void push_status(lua_State *L, const lua_law *ll, int state, const char *why)
{
    if (!ll->compile)
        lua_pushliteral(L, "not compiled: compile = false");
    else if (state > 0)
        lua_pushboolean(L, 1);
    else if (state < 0)
        lua_pushfstring(L, "runs as Lua: %s", why);
    else
        lua_pushboolean(L, 0);
}

void ll_push_compiled(lua_State *L, const lua_law *ll)
{
    int r;
    lua_createtable(L, 0, 3);
    if (ll->has_factor) {
        push_status(L, ll, ll->cstate[OP_FACTOR], ll->why[OP_FACTOR]);
        lua_setfield(L, -2, "factor");
    }
    /* rate runs as two ops (bulk and time-resolved flows): a refusal of
     * either is what the user needs to see. */
    r = ll->cstate[OP_RATE] < 0 || (ll->cstate[OP_RATE] > 0 && ll->cstate[OP_RATE_TR] >= 0)
            ? OP_RATE
            : OP_RATE_TR;
    push_status(L, ll, ll->cstate[r], ll->why[r]);
    lua_setfield(L, -2, "rate");
    if (ll->g_kind == G_POWER) {
        lua_pushboolean(L, 1);
        lua_setfield(L, -2, "integrand");
    } else if (ll->g_kind == G_LUA) {
        push_status(L, ll, ll->gstate, ll->gwhy);
        lua_setfield(L, -2, "integrand");
    }
}

/* ---- dE/d ln S ---------------------------------------------------------- */

/* Whether op's program can give derivatives now: compiled, checked
 * against Lua, its guards checked at the current epoch (so it is the
 * program of the function as it stands), and every operation with a
 * rule (dfle_trace_differentiable). */
static int deriv_ready(const lua_law *ll, int op)
{
    const dfle_trace_prog *p = ll->prog[op];
    return ll->compile && p != NULL && ll->cstate[op] > 0 && !ll->unchecked[op] &&
           ll->seen[op] == *ll->epoch && dfle_trace_differentiable(p);
}

/* The check of a new program runs the function as Lua, which moves the
 * epoch: the guards of the programs rate_dlnS needs are checked again
 * here (no Lua runs), so that the op comes as soon as they hold, whether
 * the programs were traced and checked now or found in the cache (the
 * same solver path either way).  A guard that fails is left to the next
 * sweep, which traces again. */
void ll_compiled_refresh(lua_law *ll)
{
    lua_State *T = ll->sh.T;
    const int ops[2] = {ll->time_resolved ? OP_RATE_TR : OP_RATE,
                        ll->has_factor && !ll->time_resolved ? OP_FACTOR : -1};
    for (int k = 0; k < 2; k++) {
        const int op = ops[k];
        if (op < 0 || ll->prog[op] == NULL || ll->cstate[op] <= 0 || ll->unchecked[op] ||
            ll->seen[op] == *ll->epoch)
            continue;
        lua_settop(T, SLOT_COUNT);
        if (dfle_trace_guards_hold(T, SLOT_GUARDS_FACTOR + op, ll->prog[op]))
            ll->seen[op] = *ll->epoch;
    }
}

int ll_compiled_can_dlnS(const lua_law *ll)
{
    /* After a time-resolved routing the factor is the held Eq. (11) sum:
     * only rate's own dependence on S counts. */
    if (ll->time_resolved)
        return deriv_ready(ll, OP_RATE_TR);
    return deriv_ready(ll, OP_RATE) && (!ll->has_factor || deriv_ready(ll, OP_FACTOR));
}

/* Room for the derivative columns of the inputs (N_IN x n). */
static double *deriv_buffer(lua_law *ll, size_t n)
{
    if (n > ll->dcap) {
        double *b = realloc(ll->dbuf, (size_t)N_IN * n * sizeof *b);
        if (b == NULL)
            return NULL;
        ll->dbuf = b;
        ll->dcap = n;
    }
    return ll->dbuf;
}

/* Whether op's program still holds its values for the call in progress
 * (ll->ctx, ll->F_in): rate_dlnS comes right after rate with what rate
 * received (law.h), and the factor it was given must be the one the
 * factor program last gave, to the bit (the same flow: a factor equal
 * by chance would need equal t_p, h and Theta).  Then the derivative
 * needs no second evaluation: a third of a Lua law's node solve. */
static int still_fresh(const lua_law *ll, int op)
{
    const dfle_law_ctx *ctx = ll->ctx;
    if (!ll->fresh[op] || ll->fresh_n[op] != ctx->n)
        return 0;
    if (op != OP_FACTOR)
        return ll->fresh_in[op][0] == (const void *)ctx->S && ll->fresh_in[op][1] == ll->F_in;
    if (ll->fresh_in[op][0] != (const void *)ctx->flow)
        return 0;
    return memcmp(ll->fresh_val[op], ll->F_in, ctx->n * sizeof *ll->F_in) == 0;
}

/* The values of the program of op for the call in progress (ll->ctx,
 * ll->F_in), then its derivative for the input derivatives din. */
static const double *program_deriv(lua_law *ll, int op, size_t n, const double *const *din)
{
    dfle_trace_prog *p = ll->prog[op];
    const unsigned used = dfle_trace_inputs(p);
    const double *src[N_IN];
    ll->op = op;
    if (!still_fresh(ll, op)) {
        const double *val;
        for (int f = 0; f < N_IN; f++)
            src[f] = used & (1u << f) ? ll_field_source(ll, f) : NULL;
        val = dfle_trace_eval_n(p, n, src);
        mark_fresh(ll, op, ll->ctx, ll->F_in, val);
        if (val == NULL)
            return NULL;
    }
    return dfle_trace_deriv_n(p, n, din);
}

/* Forward mode through the programs (law.h's rate_dlnS).  The inputs
 * move with ln S as the router says: dS = S, dX = X d ln X for the
 * positive flow fields, dTheta as given, A and w not at all; with a
 * factor, dF is the factor program's derivative for those, and rate's
 * then carries dS and dF on.  A held flow (d NULL) or a time-resolved
 * one (its factor the Eq. (11) sum) moves S alone.  frequency(A) is a
 * constant in S: it scales E and dE alike. */
void ll_compiled_rate_dlnS(lua_law *ll, const dfle_law_ctx *ctx, const double *F,
                           const double *E, const dfle_flow_dlnS *d, double *dE)
{
    const size_t n = ctx->n;
    const int moving = d != NULL && !ll->time_resolved;
    const double *din[N_IN] = {NULL}, *dv = NULL;
    double *buf = deriv_buffer(ll, n);

    ll->ctx = ctx, ll->F_in = F; /* for ll_field_source() */
    if (buf != NULL && ll_compiled_can_dlnS(ll)) {
        din[F_S] = ctx->S;
        if (moving) {
            static const int field[] = {F_H, F_V, F_T_P, F_TAU, F_Q, F_M, F_THETA};
            const dfle_flow *fl = ctx->flow;
            for (size_t i = 0; i < n; i++) {
                buf[F_H * n + i] = fl->h[i] * d[i].h;
                buf[F_V * n + i] = fl->v[i] * d[i].v;
                buf[F_T_P * n + i] = fl->t_p[i] * d[i].t_p;
                buf[F_TAU * n + i] = fl->tau[i] * d[i].tau;
                buf[F_Q * n + i] = fl->Q[i] * d[i].Q;
                buf[F_M * n + i] = fl->M[i] * d[i].M;
                buf[F_THETA * n + i] = d[i].Theta;
            }
            for (size_t k = 0; k < sizeof field / sizeof field[0]; k++)
                din[field[k]] = buf + (size_t)field[k] * n;
            if (ll->has_factor) {
                const double *dF = program_deriv(ll, OP_FACTOR, n, din);
                if (dF != NULL) {
                    memcpy(buf + (size_t)F_F * n, dF, n * sizeof *dF);
                    din[F_F] = buf + (size_t)F_F * n;
                }
            }
        }
        if (!moving || !ll->has_factor || din[F_F] != NULL)
            dv = program_deriv(ll, ll->time_resolved ? OP_RATE_TR : OP_RATE, n, din);
    }
    for (size_t i = 0; i < n; i++) {
        size_t at;
        if (E[i] == 0)
            dE[i] = 0.0; /* no erosion by the rate's own rules */
        else if (dv == NULL || (ll->has_frequency && !ll_memo_find(ll, ctx->A[i], &at)))
            dE[i] = NAN; /* none to give: the solvers then do without */
        else
            dE[i] = ll->has_frequency ? dv[i] * ll->fv[at] : dv[i];
    }
}
