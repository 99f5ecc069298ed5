/*
 * lua_law_define.c - dfle.law.define{...}: debris-flow erosion laws
 * written in Lua, run by the compiled model like any built-in law.
 *
 *   local law = dfle.law.define{
 *     name = "inertial", params = { k = 1e-6, D = 0.09, rho_s = 2600 },
 *     factor = function(c, p) return c.t_p * p.rho_s * (p.D * c.v / c.h)^2 end,
 *     rate   = function(c, p) return p.k * c.S * c.F end,
 *   }
 *
 * A Lua law is a shell (lua_shell.h): a dfle_law_ops table whose state
 * lives on a Lua thread of the law's own, with the user's functions, the
 * params copy, the node records and the arrays the per-node loops read.
 * The law holds nothing global, so any number of lua_States (one per
 * ensemble worker) may each define their own laws.
 *
 * This file is the top of three layers: it builds the law, and its ops
 * run each call compiled (lua_law_compiled.c) when the function's trace
 * was accepted, else as a protected Lua sweep (lua_law_sweep.c).
 *
 * The Eq. (11) split (doc/laws.md): `factor` runs after each routing,
 * `rate` every landscape step with the slope and the cached factor; a law
 * without `factor` gets the flow fields in `rate` (bulk routers).  For
 * the process-based router the integrand is a built-in form h^a v^b
 * lambda^c (C speed) or, at a documented cost, a Lua function called
 * once per wet cell per flow step.
 *
 * By default each function is first traced (lua_trace.h): a formula
 * becomes a C program, evaluated column by column over the nodes with no
 * Lua call at all, and checked bit for bit against the Lua sweep on its
 * first use.  A function the tracer refuses runs through the sweep, and
 * law:compiled() says why.  The values a program baked in are re-checked
 * whenever the Lua epoch has moved (dfle_lua_epoch), i.e. whenever Lua
 * code may have changed them.
 */
#include "lua/define/lua_law_compiled.h"

#include <math.h>
#include <stdlib.h>

/* law.h's rate_dlnS: forward mode through the compiled programs
 * (lua_law_compiled.c).  Offered only while they can give it
 * (offer_dlnS); a law whose programs cannot (refused, not yet checked,
 * guards moved) has no op, and the solvers difference E instead. */
static int ll_rate_dlnS(void *state, const dfle_law_ctx *ctx, const double *F, const double *E,
                        const dfle_flow_dlnS *d, double *dE, dfle_error *err)
{
    (void)err;
    ll_compiled_rate_dlnS(state, ctx, F, E, d, dE);
    return DFLE_OK;
}

/* The op comes and goes with the programs: set after every call that may
 * have compiled, checked or dropped one. */
static void offer_dlnS(lua_law *ll)
{
    ll->ops.rate_dlnS = ll_compiled_can_dlnS(ll) ? ll_rate_dlnS : NULL;
}

/* One op call: the rate a one-node flow_factor already evaluated (see
 * sweep() in lua_law_sweep.c), else the compiled program if there is
 * one, else the Lua sweep. */
static int run_sweep(lua_law *ll, int op, const dfle_law_ctx *ctx, const double *F_in,
                     double *out, dfle_error *err)
{
    int st;
    if (ctx->n == 0)
        return DFLE_OK;
    if (ll->spec_valid && !ll->busy) {
        ll->spec_valid = 0;
        if (op == OP_RATE && ctx->n == 1 && ctx->S[0] == ll->spec_S && F_in[0] == ll->spec_F &&
            ctx->A[0] == ll->spec_A && ctx->w[0] == ll->spec_w) {
            out[0] = ll->spec_E;
            return DFLE_OK;
        }
    }
    if ((st = dfle_lua_shell_enter(&ll->sh, "functions", err)) != DFLE_OK)
        return st;
    st = TRY_LUA;
    if (ll->compile && ll->cstate[op] >= 0)
        st = ll_compiled_sweep(ll, op, ctx, F_in, out, err);
    if (st == TRY_LUA)
        st = ll_interpreted_sweep(ll, op, ctx, F_in, out, err);
    if (st == DFLE_OK && ll->compile)
        ll_compiled_refresh(ll);
    dfle_lua_shell_leave(&ll->sh);
    offer_dlnS(ll);
    return st;
}

static int ll_flow_factor(void *state, const dfle_law_ctx *ctx, double *F, dfle_error *err)
{
    lua_law *ll = state;
    const dfle_flow *fl = ctx->flow;

    ll->time_resolved = fl->time_resolved;
    offer_dlnS(ll); /* which programs count depends on the flow's kind */
    if (ll->has_factor)
        return run_sweep(ll, OP_FACTOR, ctx, NULL, F, err);
    /* No factor: the Eq. (11) sum for a time-resolved flow, else 1 where
     * the flow goes on and 0 where it stops (Theta <= 0). */
    for (size_t i = 0; i < ctx->n; i++)
        F[i] = fl->time_resolved ? fl->integral[i] : fl->Theta[i] > 0 ? 1.0 : 0.0;
    return DFLE_OK;
}

static int ll_rate(void *state, const dfle_law_ctx *ctx, const double *F, double *E,
                   dfle_error *err)
{
    lua_law *ll = state;
    return run_sweep(ll, ll->time_resolved ? OP_RATE_TR : OP_RATE, ctx, F, E, err);
}

/* The Eq. (11) integrand, called by a time-resolved router once per wet
 * cell and flow step. */
static int ll_integrand(void *state, double h, double v, double lambda, double *g,
                        dfle_error *err)
{
    lua_law *ll = state;
    int st;

    if (ll->g_kind == G_POWER) {
        double r = ll->gh != 0 ? pow(h, ll->gh) : 1.0;
        if (ll->gv != 0)
            r *= pow(v, ll->gv);
        if (ll->gl != 0)
            r *= pow(lambda, ll->gl);
        *g = r;
        return DFLE_OK;
    }
    if (ll->g_kind == G_NONE)
        return dfle_error_set(err, DFLE_EINVAL,
                              "%s: the law has no integrand, which a time-resolved router needs: "
                              "give integrand = { h = beta } (h^beta, as the power law) or a "
                              "function", ll->sh.who);
    /* Called from inside its own functions (through another model's
     * routing), it would reset the thread's stack under the running
     * call. */
    if ((st = dfle_lua_shell_enter(&ll->sh, "functions", err)) != DFLE_OK)
        return st;
    st = TRY_LUA;
    if (ll->compile && ll->gstate >= 0)
        st = ll_compiled_integrand(ll, h, v, lambda, g, err);
    if (st == TRY_LUA)
        st = ll_lua_integrand(ll, h, v, lambda, g, err);
    dfle_lua_shell_leave(&ll->sh);
    return st;
}

static void ll_destroy(void *state)
{
    lua_law *ll = state;
    /* ll itself and the thread belong to the law's userdata; the
     * collector takes them (they stay valid while its __gc runs). */
    free(ll->shadow);
    free(ll->fA);
    free(ll->fv);
    free(ll->scratch);
    free(ll->dbuf);
    ll->dbuf = NULL;
    ll->ops.rate_dlnS = NULL;
    ll->shadow = ll->fA = ll->fv = ll->scratch = NULL;
    for (int op = 0; op < N_OPS; op++) {
        dfle_trace_free(ll->prog[op]);
        ll->prog[op] = NULL;
    }
    dfle_trace_free(ll->gprog);
    ll->gprog = NULL;
}

static const dfle_law_ops lua_law_ops = {
    .version = DFLE_LAW_OPS_VERSION,
    .name = "lua",
    .flow_factor = ll_flow_factor,
    .rate = ll_rate,
    .integrand = ll_integrand,
    .destroy = ll_destroy,
};

/* Read an optional function field into the thread slot (nil if absent). */
static void move_function(lua_State *L, lua_State *T, const char *key, int required)
{
    int t = lua_getfield(L, 1, key);
    if (t != LUA_TNIL && t != LUA_TFUNCTION)
        luaL_error(L, "dfle.law.define: '%s' must be a function, got %s", key,
                   dfle_lua_typename(L, -1));
    if (t == LUA_TNIL && required)
        luaL_error(L, "dfle.law.define: '%s' (a function of c, p) is required", key);
    lua_xmove(L, T, 1);
}

/* Optional boolean `key` of the definition at index 1 (default true). */
static int opt_flag(lua_State *L, const char *key)
{
    int t, v = 1;
    if ((t = lua_getfield(L, 1, key)) != LUA_TNIL) {
        if (t != LUA_TBOOLEAN)
            luaL_error(L, "dfle.law.define: '%s' must be a boolean, got %s", key,
                       dfle_lua_typename(L, -1));
        v = lua_toboolean(L, -1);
    }
    lua_pop(L, 1);
    return v;
}

/* dfle.law.define{ name =, params =, rate =, factor =, integrand =,
 * frequency =, compile =, cache = } -> dfle.law */
static int l_law_define(lua_State *L)
{
    static const char *const keys[] = {"name", "params", "rate", "factor", "integrand",
                                       "frequency", "compile", "cache", NULL};
    static const dfle_lua_shell_def def = {
        .kind = "law", .tname = DFLE_LUA_LAW, .object_size = sizeof(dfle_lua_law),
        .state_size = sizeof(lua_law), .keys = keys, .stack = 2 * SLOT_COUNT,
    };
    lua_law *ll = dfle_lua_shell_new(L, &def);
    lua_State *T = ll->sh.T;
    dfle_error err;
    double g[3] = {0, 0, 0};
    int t;

    ll->compile = opt_flag(L, "compile");
    ll->cache = opt_flag(L, "cache");
    move_function(L, T, "rate", 1);
    move_function(L, T, "factor", 0);
    if ((t = lua_getfield(L, 1, "integrand")) == LUA_TFUNCTION) {
        lua_xmove(L, T, 1);
    } else {
        if (t != LUA_TNIL && t != LUA_TTABLE)
            luaL_error(L, "dfle.law.define: 'integrand' must be a function (h, v, lambda, p) or a "
                          "table of exponents {h =, v =, lambda =}, got %s",
                          dfle_lua_typename(L, -1));
        lua_pop(L, 1);
        lua_pushnil(T);
    }
    move_function(L, T, "frequency", 0);

    ll->g_kind = lua_isnil(T, SLOT_INTEGRAND) ? G_NONE : G_LUA;
    if (lua_getfield(L, 1, "integrand") == LUA_TTABLE) {
        const dfle_lua_param gp[] = {{"h", &g[0]}, {"v", &g[1]}, {"lambda", &g[2]}};
        dfle_lua_read_params(L, -1, "law.define: integrand", gp, 3, NULL);
        ll->g_kind = G_POWER;
    }
    lua_pop(L, 1);
    ll->gh = g[0], ll->gv = g[1], ll->gl = g[2];
    ll->ops = lua_law_ops;
    ll->ops.name = ll->sh.name;
    ll->has_factor = !lua_isnil(T, SLOT_FACTOR);
    ll->has_frequency = !lua_isnil(T, SLOT_FREQUENCY);
    ll->epoch = dfle_lua_epoch(L);
    ll_sweep_slots(T, ll); /* up to SLOT_SWEEP */
    for (int k = SLOT_GUARDS_FACTOR; k <= SLOT_GUARDS_G; k++)
        lua_pushnil(T); /* not compiled yet */
    if (dfle_law_new(&ll->ops, ll, &((dfle_lua_law *)lua_touserdata(L, 2))->law, &err) !=
        DFLE_OK)
        return dfle_lua_raise(L, &err);
    lua_settop(L, 2);
    return 1;
}

void dfle_lua_open_law_define(lua_State *L)
{
    lua_pushcfunction(L, l_law_define);
    lua_setfield(L, -2, "define");
}

int dfle_lua_law_compiled(lua_State *L, dfle_law *law)
{
    /* Only a law of this file has these ops. */
    if (dfle_law_get_ops(law)->flow_factor != ll_flow_factor)
        return 0;
    ll_push_compiled(L, dfle_law_state(law));
    return 1;
}
