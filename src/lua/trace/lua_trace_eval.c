/*
 * lua_trace_eval.c - running a traced program (lua_trace.h): point by
 * point for the integrand, column by column for a sweep over the nodes,
 * with the very operations Lua's VM and lmathlib use, so that the values
 * are Lua's bit for bit; and checking the guards of what it baked in.
 */
#include "lua/trace/lua_trace_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* lmathlib's PI, so deg/rad scale exactly as Lua does. */
#define LUA_PI 3.141592653589793238462643383279502884

const char dfle_trace_nil = 0;

/* ---- evaluation -------------------------------------------------------- */

static double apply(int op, double a, double b)
{
    double m;
    switch (op) {
    case T_ADD: return a + b;
    case T_SUB: return a - b;
    case T_MUL: return a * b;
    case T_DIV: return a / b;
    case T_MOD:
        /* luai_nummod: fmod truncates the quotient, Lua floors it, so a
         * remainder whose sign differs from the divisor's moves by b. */
        m = fmod(a, b);
        if ((m > 0) ? b < 0 : (m < 0 && b > 0))
            m += b;
        return m;
    case T_IDIV: return floor(a / b);
    case T_POW: /* luai_numpow; x^1 is x exactly in any pow within an ulp */
        return b == 2 ? a * a : b == 1 ? a : pow(a, b);
    case T_UNM: return -a;
    case T_SQRT: return sqrt(a);
    case T_EXP: return exp(a);
    case T_LOG: return log(a);
    case T_LOGB: return b == 2.0 ? log2(a) : b == 10.0 ? log10(a) : log(a) / log(b);
    case T_ABS: return fabs(a);
    /* math.floor and math.ceil return an integer where it fits, and an
     * integer has no -0: floor(-0.0) and ceil(-0.5) are 0, not -0.0. */
    case T_FLOOR: m = floor(a); return m == 0 ? 0.0 : m;
    case T_CEIL: m = ceil(a); return m == 0 ? 0.0 : m;
    case T_FMOD: return fmod(a, b);
    case T_MAX: return a < b ? b : a; /* math.max keeps the first of equals */
    case T_MIN: return b < a ? b : a;
    case T_SIN: return sin(a);
    case T_COS: return cos(a);
    case T_TAN: return tan(a);
    case T_ASIN: return asin(a);
    case T_ACOS: return acos(a);
    case T_ATAN: return atan2(a, b);
    case T_DEG: return a * (180.0 / LUA_PI);
    case T_RAD: return a * (LUA_PI / 180.0);
    default: return NAN;
    }
}

double dfle_trace_eval(dfle_trace_prog *p, const double *in)
{
    double *v = p->val;
    for (int f = 0; f < DFLE_TRACE_MAX_INPUTS; f++)
        if (p->in_node[f] >= 0)
            v[p->in_node[f]] = in[f];
    for (int k = 0; k < p->n; k++) {
        const tnode *t = &p->node[k];
        if (t->op > T_PARAM)
            v[k] = apply(t->op, v[t->a], v[t->b]);
    }
    return v[p->result];
}

/* Column by column: each operation runs as one tight loop over the
 * points, which is what makes a whole sweep cost about what a built-in
 * law costs.  K columns are filled when the workspace grows. */
const double *dfle_trace_eval_n(dfle_trace_prog *p, size_t n, const double *const *in)
{
    const double **col = p->col;
    if (n > p->cap) {
        size_t cap = n > 2 * p->cap ? n : 2 * p->cap;
        double *w = malloc((size_t)(p->n + 1) * cap * sizeof *w);
        if (w == NULL)
            return NULL;
        free(p->work);
        p->work = w;
        p->cap = cap;
        for (int k = 0; k < p->n; k++)
            if (T_IS_CONST(p->node[k].op))
                for (size_t i = 0; i < cap; i++)
                    w[(size_t)k * cap + i] = p->node[k].k;
        for (size_t i = 0; i < cap; i++)
            w[(size_t)p->n * cap + i] = 0.0; /* the column of an absent input */
    }
    for (int k = 0; k < p->n; k++) {
        const tnode *t = &p->node[k];
        double *r = p->work + (size_t)k * p->cap;
        const double *a, *b;
        if (t->op == T_IN) {
            col[k] = in[t->a] != NULL ? in[t->a] : p->work + (size_t)p->n * p->cap;
            continue;
        }
        col[k] = r;
        if (T_IS_CONST(t->op))
            continue;
        a = col[t->a], b = col[t->b];
        switch (t->op) {
        case T_ADD: for (size_t i = 0; i < n; i++) r[i] = a[i] + b[i]; break;
        case T_SUB: for (size_t i = 0; i < n; i++) r[i] = a[i] - b[i]; break;
        case T_MUL: for (size_t i = 0; i < n; i++) r[i] = a[i] * b[i]; break;
        case T_DIV: for (size_t i = 0; i < n; i++) r[i] = a[i] / b[i]; break;
        default: for (size_t i = 0; i < n; i++) r[i] = apply(t->op, a[i], b[i]); break;
        }
    }
    return col[p->result];
}


/* ---- derivatives ------------------------------------------------------- */

/* The derivative of r = op(a, b) from those of a and b (da, db).  An
 * operand whose derivative is 0 contributes nothing, so a constant one
 * never forms inf * 0 (0^(b-1) with b < 1, a pole of 1/b). */
static double dapply(int op, double a, double b, double r, double da, double db)
{
    double d = 0.0, lb;
    switch (op) {
    case T_ADD: return da + db;
    case T_SUB: return da - db;
    case T_MUL: return (da != 0 ? da * b : 0.0) + (db != 0 ? a * db : 0.0);
    case T_DIV: return (da != 0 ? da / b : 0.0) - (db != 0 ? r * db / b : 0.0);
    /* a - floor(a/b) b and a - trunc(a/b) b: the quotient is flat between
     * its jumps. */
    case T_MOD: return da - (db != 0 ? floor(a / b) * db : 0.0);
    case T_FMOD: return da - (db != 0 ? trunc(a / b) * db : 0.0);
    case T_IDIV: case T_FLOOR: case T_CEIL: return 0.0;
    case T_POW:
        if (da != 0)
            d = b == 1 ? da : b == 2 ? 2.0 * a * da : b * pow(a, b - 1) * da;
        if (db != 0)
            d += r * log(a) * db;
        return d;
    case T_UNM: return -da;
    case T_SQRT: return da != 0 ? da / (2.0 * r) : 0.0;
    case T_EXP: return da != 0 ? r * da : 0.0;
    case T_LOG: return da != 0 ? da / a : 0.0;
    case T_LOGB: /* log(a) / log(b), whichever way apply() forms it */
        lb = log(b);
        return (da != 0 ? da / (a * lb) : 0.0) - (db != 0 ? r * db / (b * lb) : 0.0);
    case T_ABS: return da == 0 ? 0.0 : a > 0 ? da : a < 0 ? -da : NAN; /* kink at 0 */
    case T_MAX: return a < b ? db : da; /* the operand apply() chose */
    case T_MIN: return b < a ? db : da;
    case T_SIN: return da != 0 ? cos(a) * da : 0.0;
    case T_COS: return da != 0 ? -sin(a) * da : 0.0;
    case T_TAN: return da != 0 ? da / (cos(a) * cos(a)) : 0.0;
    case T_ASIN: return da != 0 ? da / sqrt(1.0 - a * a) : 0.0;
    case T_ACOS: return da != 0 ? -da / sqrt(1.0 - a * a) : 0.0;
    case T_ATAN: /* atan2(a, b) */
        return ((da != 0 ? b * da : 0.0) - (db != 0 ? a * db : 0.0)) / (a * a + b * b);
    case T_DEG: return da * (180.0 / LUA_PI);
    case T_RAD: return da * (LUA_PI / 180.0);
    default: return NAN;
    }
}

int dfle_trace_differentiable(const dfle_trace_prog *p)
{
    for (int k = 0; k < p->n; k++) {
        const int op = p->node[k].op;
        /* dapply() has a rule for every operation from T_ADD to T_RAD. */
        if (op > T_PARAM && !(op >= T_ADD && op <= T_RAD))
            return 0;
    }
    return 1;
}

/* Forward mode, column by column like dfle_trace_eval_n, whose value
 * columns (p->col) it reads.  A node none of whose operands moves keeps
 * the column of zeros: its derivative is exactly 0, whatever its value. */
const double *dfle_trace_deriv_n(dfle_trace_prog *p, size_t n, const double *const *din)
{
    const double **col = p->col, **dcol;
    const double *zero;
    if (p->dcol == NULL && (p->dcol = malloc((size_t)p->n * sizeof *p->dcol)) == NULL)
        return NULL;
    if (n > p->dcap) {
        size_t cap = n > 2 * p->dcap ? n : 2 * p->dcap;
        double *w = malloc((size_t)(p->n + 1) * cap * sizeof *w);
        if (w == NULL)
            return NULL;
        free(p->dwork);
        p->dwork = w;
        p->dcap = cap;
        for (size_t i = 0; i < cap; i++)
            w[(size_t)p->n * cap + i] = 0.0;
    }
    dcol = p->dcol;
    zero = p->dwork + (size_t)p->n * p->dcap;
    for (int k = 0; k < p->n; k++) {
        const tnode *t = &p->node[k];
        double *r = p->dwork + (size_t)k * p->dcap;
        const double *a, *b, *da, *db, *v;
        if (t->op == T_IN) {
            dcol[k] = din[t->a] != NULL ? din[t->a] : zero;
            continue;
        }
        if (T_IS_CONST(t->op) || (dcol[t->a] == zero && dcol[t->b] == zero)) {
            dcol[k] = zero;
            continue;
        }
        dcol[k] = r;
        a = col[t->a], b = col[t->b], v = col[k], da = dcol[t->a], db = dcol[t->b];
        switch (t->op) {
        case T_ADD: for (size_t i = 0; i < n; i++) r[i] = da[i] + db[i]; break;
        case T_SUB: for (size_t i = 0; i < n; i++) r[i] = da[i] - db[i]; break;
        default:
            for (size_t i = 0; i < n; i++)
                r[i] = dapply(t->op, a[i], b[i], v[i], da[i], db[i]);
            break;
        }
    }
    return dcol[p->result];
}

unsigned dfle_trace_inputs(const dfle_trace_prog *p) { return p->inputs; }

dfle_trace_prog *dfle_trace_clone(const dfle_trace_prog *src)
{
    dfle_trace_prog *p = calloc(1, sizeof *p);
    if (p == NULL)
        return NULL;
    p->node = malloc((size_t)src->n * sizeof *p->node);
    p->val = malloc((size_t)src->n * sizeof *p->val);
    p->col = malloc((size_t)src->n * sizeof *p->col);
    if (p->node == NULL || p->val == NULL || p->col == NULL) {
        dfle_trace_free(p);
        return NULL;
    }
    p->n = src->n;
    p->result = src->result;
    p->n_guards = src->n_guards;
    p->inputs = src->inputs;
    memcpy(p->in_node, src->in_node, sizeof p->in_node);
    memcpy(p->node, src->node, (size_t)src->n * sizeof *p->node);
    memcpy(p->val, src->val, (size_t)src->n * sizeof *p->val);
    return p; /* workspace (work, cap) made on first use */
}

void dfle_trace_free(dfle_trace_prog *p)
{
    if (p == NULL)
        return;
    free(p->node);
    free(p->val);
    free(p->col);
    free(p->work);
    free(p->dcol);
    free(p->dwork);
    free(p);
}

/* ---- guards ------------------------------------------------------------ */

const char dfle_trace_root = 0, dfle_trace_params = 0;

/* Same value, as a compiled program sees it: numbers must agree in
 * subtype and bits (NaN equals itself), others must be the same object. */
static int same_value(lua_State *L, int a, int b)
{
    if (lua_type(L, a) == LUA_TNUMBER && lua_type(L, b) == LUA_TNUMBER) {
        double x, y;
        if (lua_isinteger(L, a) != lua_isinteger(L, b))
            return 0;
        if (lua_isinteger(L, a))
            return lua_tointeger(L, a) == lua_tointeger(L, b);
        x = lua_tonumber(L, a), y = lua_tonumber(L, b);
        return memcmp(&x, &y, sizeof x) == 0;
    }
    if (lua_touserdata(L, b) == (void *)&dfle_trace_nil)
        return lua_isnil(L, a);
    return lua_rawequal(L, a, b);
}

/* In a template, replace the mark at idx by what it stands for. */
static void resolve_mark(lua_State *L, int idx, int fidx, int pidx)
{
    const void *u = lua_touserdata(L, idx);
    if (fidx != 0 && u == (const void *)&dfle_trace_root) {
        lua_pushvalue(L, fidx);
        lua_replace(L, idx);
    } else if (pidx != 0 && u == (const void *)&dfle_trace_params) {
        lua_pushvalue(L, pidx);
        lua_replace(L, idx);
    }
}

/* One guard at stack slots top+1 .. top+4 (kind, container, key, value). */
static int guard_holds(lua_State *L, int top, const dfle_trace_prog *p, int template)
{
    const int kind = (int)lua_tointeger(L, top + 1);
    double x, k;
    if (kind == G_UPVALUE) {
        if (lua_type(L, top + 2) != LUA_TFUNCTION)
            return 0;
        if (lua_getupvalue(L, top + 2, (int)lua_tointeger(L, top + 3)) == NULL)
            lua_pushnil(L);
        return same_value(L, top + 5, top + 4);
    }
    if (!lua_istable(L, top + 2))
        return 0;
    lua_pushvalue(L, top + 3);
    lua_rawget(L, top + 2); /* top+5 */
    if (kind == G_PARAM) {
        /* Read as an input: any float serves a template; the law's own
         * program holds its value in the param's node. */
        int idx = (int)lua_tointeger(L, top + 4);
        if (lua_type(L, top + 5) != LUA_TNUMBER || lua_isinteger(L, top + 5))
            return 0;
        if (template)
            return 1;
        if (p == NULL || idx < 0 || idx >= p->n || p->node[idx].op != T_PARAM)
            return 0;
        x = lua_tonumber(L, top + 5), k = p->node[idx].k;
        return memcmp(&x, &k, sizeof x) == 0;
    }
    /* The trace read a field that was not set only from a table without
     * a metatable (lua_trace.c refuses the rest): one given a metatable
     * since may answer with __index. */
    if (lua_isnil(L, top + 5) && lua_getmetatable(L, top + 2)) {
        lua_pop(L, 1);
        return 0;
    }
    return same_value(L, top + 5, top + 4);
}

int dfle_trace_guards_check(lua_State *L, int gidx, const dfle_trace_prog *p, int fidx, int pidx)
{
    const int template = fidx != 0 || pidx != 0;
    int ok = 1, n;
    gidx = lua_absindex(L, gidx);
    fidx = fidx != 0 ? lua_absindex(L, fidx) : 0;
    pidx = pidx != 0 ? lua_absindex(L, pidx) : 0;
    if (!lua_checkstack(L, 8) || !lua_istable(L, gidx))
        return 0;
    n = (int)(lua_rawlen(L, gidx) / 4);
    if (p != NULL && n != p->n_guards)
        return 0;
    for (int j = 0; ok && j < n; j++) {
        int top = lua_gettop(L);
        lua_rawgeti(L, gidx, 4 * j + 1); /* kind      top+1 */
        lua_rawgeti(L, gidx, 4 * j + 2); /* container top+2 */
        lua_rawgeti(L, gidx, 4 * j + 3); /* key       top+3 */
        lua_rawgeti(L, gidx, 4 * j + 4); /* value     top+4 */
        if (template)
            for (int e = 2; e <= 4; e++)
                resolve_mark(L, top + e, fidx, pidx);
        ok = guard_holds(L, top, p, template);
        lua_settop(L, top);
    }
    return ok;
}

int dfle_trace_guards_hold(lua_State *L, int gidx, const dfle_trace_prog *p)
{
    return dfle_trace_guards_check(L, gidx, p, 0, 0);
}
