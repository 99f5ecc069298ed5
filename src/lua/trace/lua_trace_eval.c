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
        if (t->op > T_K)
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
            if (p->node[k].op == T_K)
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
        if (t->op == T_K)
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

unsigned dfle_trace_inputs(const dfle_trace_prog *p) { return p->inputs; }

void dfle_trace_free(dfle_trace_prog *p)
{
    if (p == NULL)
        return;
    free(p->node);
    free(p->val);
    free(p->col);
    free(p->work);
    free(p);
}

/* ---- guards ------------------------------------------------------------ */

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

int dfle_trace_guards_hold(lua_State *L, int gidx, const dfle_trace_prog *p)
{
    int ok = 1;
    gidx = lua_absindex(L, gidx);
    if (!lua_checkstack(L, 8) || !lua_istable(L, gidx))
        return 0;
    for (int j = 0; ok && j < p->n_guards; j++) {
        int top = lua_gettop(L);
        lua_rawgeti(L, gidx, 4 * j + 1); /* kind      top+1 */
        lua_rawgeti(L, gidx, 4 * j + 2); /* container top+2 */
        lua_rawgeti(L, gidx, 4 * j + 3); /* key       top+3 */
        lua_rawgeti(L, gidx, 4 * j + 4); /* value     top+4 */
        if (lua_tointeger(L, top + 1) == G_FIELD) {
            lua_pushvalue(L, top + 3);
            lua_rawget(L, top + 2);
        } else if (lua_getupvalue(L, top + 2, (int)lua_tointeger(L, top + 3)) == NULL) {
            lua_pushnil(L);
        }
        ok = same_value(L, top + 5, top + 4);
        lua_settop(L, top);
    }
    return ok;
}

