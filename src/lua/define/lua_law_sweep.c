/*
 * lua_law_sweep.c - the bottom layer of a dfle.law.define law: its
 * functions run as Lua, node by node (lua_law_sweep.h).
 *
 * Each op call is ONE protected sweep: lua_pcall of a C closure that
 * copies the inputs into Lua arrays and runs a small Lua driver looping
 * over the nodes (so the per-node call and field stores are VM work, not
 * C API calls), then checks every result.  A Lua error (or a wrong
 * return value, which the sweep raises itself) unwinds to that pcall
 * only; it becomes a dfle_error with the user's file:line and a
 * traceback, and the op returns DFLE_ECALLBACK so the model stops cleanly
 * and the binding raises the message.  No malloc'd memory is held across
 * a call that can raise: the heap arrays (shadows, frequency memo) belong
 * to the state and are consistent before and after each call.
 *
 * Only the fields a function has read are copied for it (fetch(),
 * make_driver()).  `frequency(A)` is memoised per drainage area.  The
 * compiled layer (lua_law_compiled.c) checks its programs against this
 * sweep and reads the same field sources and memo.
 */
#include "lua/define/lua_law_sweep.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Inside the sweep the slots are its upvalues. */
#define UP(slot) lua_upvalueindex(slot)

/* Field names, in the order of the ARR_ slots (valid Lua names: the
 * generated drivers use them as local variables). */
const char *const ll_field_names[N_IN] = {"S", "A", "w", "h", "v", "t_p", "tau", "Theta",
                                          "Q", "M", "I", "F"};
static const int op_rec[N_OPS] = {SLOT_REC_FACTOR, SLOT_REC_RATE, SLOT_REC_RATE_TR};
static const int op_drv[N_OPS] = {SLOT_DRV_FACTOR, SLOT_DRV_RATE, SLOT_DRV_RATE_TR};

/* The user's functions, in the order of their slots from SLOT_RATE. */
static const char *const slot_names[] = {"rate", "factor", "integrand", "frequency"};

/* Push "file:line" where the function at index idx is defined. */
static const char *where_defined(lua_State *T, int idx)
{
    lua_Debug ar;
    lua_pushvalue(T, idx);
    if (lua_getinfo(T, ">S", &ar) && ar.linedefined > 0)
        return lua_pushfstring(T, "%s:%d", ar.short_src, ar.linedefined);
    return lua_pushstring(T, ar.short_src);
}

/* Raise: the user's function returned something that is not a usable
 * number (on top of the stack).  Names the law, the function and where
 * it is defined, the node and its slope and area. */
static int bad_return(lua_State *T, const lua_law *ll, int slot, size_t i, const char *why)
{
    const dfle_law_ctx *ctx = ll->ctx;
    const char *what = lua_type(T, -1) == LUA_TNUMBER ? dfle_lua_number_text(T, lua_tonumber(T, -1))
                                                      : dfle_lua_typename(T, -1);
    const char *at = where_defined(T, UP(slot));
    if (ctx->n > 1)
        return luaL_error(T, "law '%s': %s (defined at %s) returned %s, %s, at node %d (S = %f, "
                             "A = %f m^2)", ll->sh.name, slot_names[slot - SLOT_RATE], at, what, why,
                          (int)i + 1, ctx->S[i], ctx->A[i]);
    return luaL_error(T, "law '%s': %s (defined at %s) returned %s, %s, at the node with "
                         "S = %f, A = %f m^2", ll->sh.name, slot_names[slot - SLOT_RATE], at, what, why,
                      ctx->S[i], ctx->A[i]);
}

/* Copy v[0..n) (NULL: zeros) into the Lua array `arr`, skipping values
 * equal to what the array already holds (its C shadow).  Most fields
 * (A, w, and M, Q, t_p for the empirical router) never change, so a
 * sweep writes only the slope-dependent ones. */
static void fill(lua_State *T, lua_law *ll, int arr, const double *v, size_t n)
{
    double *sh = ll->shadow + (size_t)(arr - ARR_S) * ll->cap;
    for (size_t i = 0; i < n; i++) {
        double x = v != NULL ? v[i] : 0.0;
        if (x != sh[i] || signbit(x) != signbit(sh[i])) {
            lua_pushnumber(T, x);
            lua_rawseti(T, UP(arr), (lua_Integer)i + 1);
            sh[i] = x;
        }
    }
}

/* The C array behind field f for the op in progress (NULL: zeros). */
const double *ll_field_source(const lua_law *ll, int f)
{
    const dfle_law_ctx *ctx = ll->ctx;
    const dfle_flow *fl = ctx->flow;
    switch (f) {
    case F_S: return ctx->S;
    case F_A: return ctx->A;
    case F_W: return ctx->w;
    case F_H: return fl->h;
    case F_V: return fl->v;
    case F_T_P: return fl->t_p;
    case F_TAU: return fl->tau;
    case F_THETA: return fl->Theta;
    case F_Q: return fl->Q;
    case F_M: return fl->M;
    case F_I: return fl->time_resolved ? fl->integral : NULL;
    default: return ll->op != OP_FACTOR ? ll->F_in : NULL;
    }
}

/* __index of a record: a field the driver does not copy (yet).  Returns
 * the value at the driver's node straight from C and marks the field as
 * read, so that the next sweep's driver copies it (the driver is made
 * again, once per newly read field).  Upvalues: the state, the op. */
static int fetch(lua_State *T)
{
    lua_law *ll = lua_touserdata(T, lua_upvalueindex(1));
    const int op = (int)lua_tointeger(T, lua_upvalueindex(2));
    const char *key = lua_tostring(T, 2);
    lua_Integer i;
    int f;

    /* Outside a sweep of this op (a record kept by the script) there is
     * no node: nil, never memory the model may have freed. */
    if (!ll->busy || ll->op != op || key == NULL || lua_type(T, 2) != LUA_TSTRING)
        return 0;
    for (f = 0; f < N_IN; f++)
        if (strcmp(key, ll_field_names[f]) == 0)
            break;
    if (f == N_IN || (f == F_F && op == OP_FACTOR) ||
        (op != OP_FACTOR && (ll->has_factor || op == OP_RATE_TR) &&
         !(SPLIT_RATE_FIELDS & (1u << f))))
        return 0;
    lua_rawgeti(T, lua_upvalueindex(3), 1);
    i = lua_tointeger(T, -1) - 1;
    if (i < 0 || (size_t)i >= ll->ctx->n)
        return 0;
    if (!(ll->used[op] & (1u << f))) {
        ll->used[op] |= 1u << f;
        ll->dirty[op] = 1;
    }
    {
        const double *v = ll_field_source(ll, f);
        lua_pushnumber(T, v != NULL ? v[i] : 0.0);
    }
    return 1;
}

/* Generate the driver of `op`: a Lua loop over the nodes that copies the
 * fields read so far into the record and calls the user's function.
 * Replaces the sweep's upvalue. */
static void make_driver(lua_State *T, lua_law *ll, int op)
{
    luaL_Buffer b;
    const int rec = op_rec[op];

    luaL_buffinit(T, &b);
    luaL_addstring(&b, "local fn, p, c, out, pos");
    for (int f = 0; f < N_IN; f++) {
        luaL_addstring(&b, ", ");
        luaL_addstring(&b, ll_field_names[f]);
    }
    luaL_addstring(&b, " = ...\nreturn function(n)\n  for i = 1, n do\n");
    if (op != OP_FACTOR)
        luaL_addstring(&b, "    local s, f = S[i], F[i]\n    if s > 0 and f ~= 0 then\n");
    else
        luaL_addstring(&b, "    do\n");
    luaL_addstring(&b, "      pos[1] = i\n");
    for (int f = 0; f < N_IN; f++) {
        if (!(ll->used[op] & (1u << f)))
            continue;
        luaL_addstring(&b, "      c.");
        luaL_addstring(&b, ll_field_names[f]);
        luaL_addstring(&b, " = ");
        if (op != OP_FACTOR && (f == F_S || f == F_F)) {
            luaL_addstring(&b, f == F_S ? "s" : "f");
        } else {
            luaL_addstring(&b, ll_field_names[f]);
            luaL_addstring(&b, "[i]");
        }
        luaL_addstring(&b, "\n");
    }
    luaL_addstring(&b, "      out[i] = fn(c, p)\n");
    if (op != OP_FACTOR)
        luaL_addstring(&b, "    else out[i] = 0 end\n");
    else
        luaL_addstring(&b, "    end\n");
    luaL_addstring(&b, "  end\nend\n");
    luaL_pushresult(&b);
    if (luaL_loadbufferx(T, lua_tostring(T, -1), lua_rawlen(T, -1), "=dfle.law.define", "t") !=
        LUA_OK)
        lua_error(T); /* only out of memory: the source is ours */
    lua_pushvalue(T, UP(op == OP_FACTOR ? SLOT_FACTOR : SLOT_RATE));
    lua_pushvalue(T, UP(SLOT_PARAMS));
    lua_pushvalue(T, UP(rec));
    lua_pushvalue(T, UP(ARR_OUT));
    lua_pushvalue(T, UP(SLOT_POS));
    for (int k = ARR_S; k <= ARR_F; k++)
        lua_pushvalue(T, UP(k));
    lua_call(T, 5 + N_IN, 1);
    lua_replace(T, UP(op_drv[op]));
    lua_pop(T, 1); /* the source */
    ll->dirty[op] = 0;
}

/* Where drainage area A is, or would go, in the frequency(A) memo; 1 if
 * it is there. */
int ll_memo_find(const lua_law *ll, double A, size_t *at)
{
    size_t lo = 0, hi = ll->nf;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (ll->fA[mid] < A)
            lo = mid + 1;
        else
            hi = mid;
    }
    *at = lo;
    return lo < ll->nf && ll->fA[lo] == A;
}

/* frequency(A) from the memo, calling the user's function on a miss. */
static double frequency_of(lua_State *T, lua_law *ll, size_t i)
{
    const double A = ll->ctx->A[i];
    size_t lo;
    double f;

    if (ll_memo_find(ll, A, &lo))
        return ll->fv[lo];
    lua_pushvalue(T, UP(SLOT_FREQUENCY));
    lua_pushnumber(T, A);
    lua_pushvalue(T, UP(SLOT_PARAMS));
    lua_call(T, 2, 1);
    if (lua_type(T, -1) != LUA_TNUMBER)
        bad_return(T, ll, SLOT_FREQUENCY, i, "expected a number");
    f = lua_tonumber(T, -1);
    if (!(isfinite(f) && f >= 0))
        bad_return(T, ll, SLOT_FREQUENCY, i, "expected a finite number >= 0");
    lua_pop(T, 1);
    if (ll->nf == ll->capf) {
        /* Grown in place: the state owns both arrays whatever happens. */
        size_t cap = ll->capf ? 2 * ll->capf : 64;
        double *a = realloc(ll->fA, cap * sizeof *a), *v;
        if (a == NULL)
            return luaL_error(T, "law '%s': out of memory", ll->sh.name);
        ll->fA = a;
        if ((v = realloc(ll->fv, cap * sizeof *v)) == NULL)
            return luaL_error(T, "law '%s': out of memory", ll->sh.name);
        ll->fv = v;
        ll->capf = cap;
    }
    memmove(ll->fA + lo + 1, ll->fA + lo, (ll->nf - lo) * sizeof *ll->fA);
    memmove(ll->fv + lo + 1, ll->fv + lo, (ll->nf - lo) * sizeof *ll->fv);
    ll->fA[lo] = A;
    ll->fv[lo] = f;
    ll->nf++;
    return f;
}

/* The protected sweep over the nodes of the op in progress: a C closure
 * whose upvalues are the slots (created once per law, so an op call
 * costs one lua_pcall), called with the state as its argument.  It
 * fills the arrays of the fields read so far, runs the Lua driver loop,
 * then checks every result. */
static void sweep_op(lua_State *T, lua_law *ll, int op)
{
    const dfle_law_ctx *ctx = ll->ctx;
    const size_t n = ctx->n;
    const int slot = op == OP_FACTOR ? SLOT_FACTOR : SLOT_RATE;
    unsigned need = ll->used[op];

    if (ll->dirty[op])
        make_driver(T, ll, op);
    if (op != OP_FACTOR)
        need |= (1u << F_S) | (1u << F_F); /* the driver's guard reads them */
    for (int f = 0; f < N_IN; f++)
        if (need & (1u << f))
            fill(T, ll, ARR_S + f, ll_field_source(ll, f), n);
    lua_pushvalue(T, UP(op_drv[op]));
    lua_pushinteger(T, (lua_Integer)n);
    lua_call(T, 1, 0);
    for (size_t i = 0; i < n; i++) {
        double e;
        if (lua_rawgeti(T, UP(ARR_OUT), (lua_Integer)i + 1) != LUA_TNUMBER)
            bad_return(T, ll, slot, i, "expected a number");
        e = lua_tonumber(T, -1);
        if (!isfinite(e))
            bad_return(T, ll, slot, i, "expected a finite number");
        lua_pop(T, 1);
        /* The driver wrote 0 without asking rate() where S <= 0 or F = 0:
         * no erosion up a reverse slope (model.h) nor where there is no
         * flow or it stops; the user's function never has to guard. */
        if (op != OP_FACTOR && ll->has_frequency && e != 0)
            e *= frequency_of(T, ll, i);
        ll->out[i] = e;
    }
}

static int sweep(lua_State *T)
{
    lua_law *ll = lua_touserdata(T, 1);
    const dfle_law_ctx *ctx = ll->ctx;
    double *F = ll->out;

    sweep_op(T, ll, ll->op);
    /* The implicit and direct solvers evaluate one node at a time, and
     * call rate right after flow_factor for the same node and slope:
     * evaluate it now, inside the same protected call, and keep it for
     * that rate call (run_sweep), which then costs no lua_pcall. */
    if (ll->op == OP_FACTOR && ctx->n == 1 && !ll->time_resolved &&
        !(ll->compile && ll->cstate[OP_RATE] >= 0)) {
        ll->op = OP_RATE;
        ll->F_in = F;
        ll->out = &ll->spec_E;
        sweep_op(T, ll, OP_RATE);
        ll->spec_S = ctx->S[0], ll->spec_F = F[0], ll->spec_A = ctx->A[0], ll->spec_w = ctx->w[0];
        ll->spec_valid = 1;
        ll->op = OP_FACTOR;
        ll->F_in = NULL;
        ll->out = F;
    }
    return 0;
}

/* Room for n values in the shadows (new ones NaN: never equal, so the
 * next fill writes them). */
static int reserve(lua_law *ll, size_t n, dfle_error *err)
{
    double *sh;
    if (n <= ll->cap)
        return DFLE_OK;
    sh = malloc((size_t)N_IN * n * sizeof *sh);
    if (sh == NULL)
        return dfle_error_set(err, DFLE_ENOMEM, "law.%s: out of memory for %zu nodes", ll->sh.name, n);
    for (size_t k = 0; k < (size_t)N_IN * n; k++)
        sh[k] = NAN;
    free(ll->shadow);
    ll->shadow = sh;
    ll->cap = n;
    return DFLE_OK;
}

/* Run one op as a protected sweep of the user's Lua function; convert a
 * failure to a dfle_error. */
int ll_interpreted_sweep(lua_law *ll, int op, const dfle_law_ctx *ctx, const double *F_in,
                         double *out, dfle_error *err)
{
    int st;
    if ((st = reserve(ll, ctx->n, err)) != DFLE_OK)
        return st;
    ll->busy = 1;
    ll->op = op;
    ll->ctx = ctx;
    ll->F_in = F_in;
    ll->out = out;
    st = dfle_lua_shell_sweep(&ll->sh, SLOT_COUNT, SLOT_SWEEP, "error in a Lua function", err);
    ll->busy = 0;
    return st;
}

/* The integrand through the user's Lua function: one protected call. */
int ll_lua_integrand(lua_law *ll, double h, double v, double lambda, double *g,
                     dfle_error *err)
{
    lua_State *T = ll->sh.T;
    int st;

    lua_settop(T, SLOT_COUNT);
    lua_pushvalue(T, SLOT_INTEGRAND);
    lua_pushnumber(T, h);
    lua_pushnumber(T, v);
    lua_pushnumber(T, lambda);
    lua_pushvalue(T, SLOT_PARAMS);
    if ((st = dfle_lua_shell_call(&ll->sh, SLOT_COUNT, 4, 1, "error in integrand", err)) !=
        DFLE_OK)
        return st;
    *g = lua_type(T, -1) == LUA_TNUMBER ? lua_tonumber(T, -1) : NAN;
    if (!isfinite(*g)) {
        const char *what = lua_type(T, -1) == LUA_TNUMBER ? dfle_lua_number_text(T, *g)
                                                          : dfle_lua_typename(T, -1);
        const char *at = where_defined(T, SLOT_INTEGRAND);
        dfle_error_set(err, DFLE_ECALLBACK,
                       "%s: integrand (defined at %s) returned %s, expected a finite number "
                       "(h = %g m, v = %g m/s, lambda = %g)", ll->sh.who, at, what, h, v, lambda);
        lua_settop(T, SLOT_COUNT);
        return DFLE_ECALLBACK;
    }
    lua_settop(T, SLOT_COUNT);
    return DFLE_OK;
}

/* The sweep's slots (lua_law_sweep.h), up to its closure. */
void ll_sweep_slots(lua_State *T, lua_law *ll)
{
    for (int k = ARR_S; k <= ARR_OUT; k++)
        lua_createtable(T, 0, 0);
    /* The records, whose __index is fetch() for their op. */
    for (int op = 0; op < N_OPS; op++)
        lua_createtable(T, 0, 0);
    lua_createtable(T, 1, 0); /* SLOT_POS */
    for (int op = 0; op < N_OPS; op++) {
        lua_createtable(T, 0, 1);
        lua_pushlightuserdata(T, ll);
        lua_pushinteger(T, op);
        lua_pushvalue(T, SLOT_POS);
        lua_pushcclosure(T, fetch, 3);
        lua_setfield(T, -2, "__index");
        lua_setmetatable(T, op_rec[op]);
    }
    for (int op = 0; op < N_OPS; op++) {
        lua_pushnil(T); /* SLOT_DRV_*: made on first use */
        ll->dirty[op] = 1;
    }
    dfle_lua_shell_close(T, sweep); /* SLOT_SWEEP */
}
