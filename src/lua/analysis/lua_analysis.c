/*
 * lua_analysis.c - slope-area fits and the analytical solution from Lua.
 *
 *   local f = dfle.fit_slope_area(m)            -- or {A = {...}, S = {...}}
 *   f.S_df, f.A_df, f.a2, f.r2, f.S_max_minus_S_ch, f.bins.A, ...
 *   local S = dfle.analytical_slope(rt, law, {U = 5e-4, A = 1e4})
 *
 * A fit that fails to converge is an expected outcome for some profiles
 * (ensembles meet them), so it returns nil, message rather than raising.
 */
#include "lua/core/dfle_lua.h"

#include <math.h>
#include <string.h>

#include "dfle/analysis.h"
#include "dfle/analytical.h"
#include "dfle/law_power.h"
#include "dfle/router_empirical.h"

#define DEFAULT_NBINS 100

static size_t get_nbins(lua_State *L, int opts, const char *fn)
{
    double nbins = DEFAULT_NBINS;
    const dfle_lua_param params[] = {{"nbins", &nbins}};
    dfle_lua_read_params(L, opts, fn, params, 1, NULL);
    return (size_t)dfle_lua_check_whole(L, nbins, fn, "nbins", 1, 1e6);
}

static void set_number(lua_State *L, const char *k, double v)
{
    lua_pushnumber(L, v);
    lua_setfield(L, -2, k);
}

static void push_bins(lua_State *L, const dfle_bins *b)
{
    lua_createtable(L, 0, 8);
    dfle_lua_push_array(L, b->A, b->n), lua_setfield(L, -2, "A");
    dfle_lua_push_array(L, b->S_mean, b->n), lua_setfield(L, -2, "S");
    dfle_lua_push_array(L, b->S_median, b->n), lua_setfield(L, -2, "S_median");
    dfle_lua_push_array(L, b->S_q25, b->n), lua_setfield(L, -2, "S_q25");
    dfle_lua_push_array(L, b->S_q75, b->n), lua_setfield(L, -2, "S_q75");
    lua_createtable(L, (int)b->n, 0);
    for (size_t i = 0; i < b->n; i++) {
        lua_pushinteger(L, (lua_Integer)b->count[i]);
        lua_rawseti(L, -2, (lua_Integer)i + 1);
    }
    lua_setfield(L, -2, "count");
    lua_pushinteger(L, (lua_Integer)b->n_empty), lua_setfield(L, -2, "n_empty");
}

/* dfle.fit_slope_area(model | {A=, S=} [, {nbins = 100}]) */
static int l_fit_slope_area(lua_State *L)
{
    const double *A = NULL, *S = NULL;
    size_t nbins, n;
    dfle_bins bins;
    dfle_eq2_fit fit;
    dfle_error err;
    int st;

    lua_settop(L, 2); /* scratch arrays go above the arguments */
    nbins = get_nbins(L, 2, "fit_slope_area");
    n = dfle_lua_slope_area(L, 1, "fit_slope_area", &A, &S);

    memset(&bins, 0, sizeof bins);
    st = dfle_slope_area_fit(n, A, S, nbins, &bins, &fit, &err);
    if (st == DFLE_EFIT) {
        dfle_bins_release(&bins);
        lua_pushnil(L);
        lua_pushfstring(L, "dfle.fit_slope_area: %s", err.msg);
        return 2;
    }
    if (st != DFLE_OK) {
        dfle_bins_release(&bins);
        return luaL_error(L, "dfle.fit_slope_area: %s", err.msg);
    }
    /* Build the table without raising in between: bins are malloc'd. */
    lua_createtable(L, 0, 12);
    set_number(L, "S_df", fit.S_df);
    set_number(L, "A_df", fit.A_df);
    set_number(L, "a2", fit.a2);
    set_number(L, "r2", fit.r2);
    set_number(L, "rmse", fit.rmse);
    set_number(L, "S_max", fit.S_max);
    set_number(L, "S_ch", fit.S_ch);
    set_number(L, "S_max_minus_S_ch", fit.S_max_minus_S_ch);
    lua_pushinteger(L, (lua_Integer)fit.n_points), lua_setfield(L, -2, "n_points");
    lua_pushinteger(L, (lua_Integer)fit.iterations), lua_setfield(L, -2, "iterations");
    push_bins(L, &bins);
    lua_setfield(L, -2, "bins");
    dfle_bins_release(&bins);
    return 1;
}

/* Gather the Eq. (19) parameters from an empirical router, a power law
 * and a table {U =, k_w =, b =}; the channel defaults fill k_w and b. */
static void analytical_params(lua_State *L, dfle_analytical_params *p, double *A)
{
    const dfle_empirical_opts *ro = dfle_router_empirical_opts(dfle_lua_check_router(L, 1));
    const dfle_power_law_opts *lo = dfle_law_power_opts(dfle_lua_check_law(L, 2));
    dfle_channel_opts co;
    static const char *const other[] = {"A", NULL};
    dfle_error err;

    if (ro == NULL)
        luaL_argerror(L, 1, "Eq. (19) needs the empirical router");
    if (lo == NULL)
        luaL_argerror(L, 2, "Eq. (19) needs the power law (dfle.law.power)");
    dfle_channel_opts_default(&co);
    p->U = 5e-4;
    p->k_w = co.k_w;
    p->b = co.b;
    {
        const dfle_lua_param params[] = {{"U", &p->U}, {"k_w", &p->k_w}, {"b", &p->b}};
        luaL_checktype(L, 3, LUA_TTABLE);
        dfle_lua_read_params(L, 3, "analytical_slope", params, 3, other);
    }
    p->k_df = lo->k_df;
    p->alpha = lo->alpha;
    p->beta = lo->beta;
    p->M0 = ro->M0;
    p->gamma = ro->gamma;
    p->mu = ro->mu;
    p->c1 = ro->c1;
    p->c2 = ro->c2;
    p->rho_b = ro->rho_b;
    p->g = ro->g;
    if (dfle_analytical_check(p, &err) != DFLE_OK)
        dfle_lua_raise(L, &err);
    if (A != NULL) {
        *A = lua_getfield(L, 3, "A") == LUA_TNUMBER ? lua_tonumber(L, -1) : 0.0;
        lua_pop(L, 1);
    }
}

/* Eq. (19) at one area, raising when it is not finite: parameters that
 * are each valid can overflow the power (U = 1e300, a tiny k_df). */
static double slope_at(lua_State *L, const dfle_analytical_params *p, double A)
{
    double S = dfle_analytical_slope(p, A);
    if (!isfinite(S))
        luaL_error(L, "dfle.analytical_slope: S of Eq. (19) is not finite (%s) at A = %s m^2 "
                      "for U = %s m/yr, k_df = %s, alpha = %s, beta = %s",
                   dfle_lua_number_text(L, S), dfle_lua_number_text(L, A),
                   dfle_lua_number_text(L, p->U), dfle_lua_number_text(L, p->k_df),
                   dfle_lua_number_text(L, p->alpha), dfle_lua_number_text(L, p->beta));
    return S;
}

/* dfle.analytical_slope(rt, law, {U =, A = number | array}) -> S */
static int l_analytical_slope(lua_State *L)
{
    dfle_analytical_params p;
    double A;

    analytical_params(L, &p, &A);
    lua_getfield(L, 3, "A");
    if (lua_type(L, -1) == LUA_TNUMBER) {
        if (!(isfinite(A) && A > 0))
            luaL_error(L, "dfle.analytical_slope: A must be a finite area > 0 m^2 (got %s)",
                       dfle_lua_number_text(L, A));
        lua_pushnumber(L, slope_at(L, &p, A));
        return 1;
    }
    if (lua_istable(L, -1)) {
        size_t n;
        double *a = dfle_lua_check_array(L, -1, "analytical_slope: A", &n);
        for (size_t i = 0; i < n; i++) {
            if (!(isfinite(a[i]) && a[i] > 0))
                luaL_error(L, "dfle.analytical_slope: A[%d] must be a finite area > 0 m^2 (got %s)",
                           (int)i + 1, dfle_lua_number_text(L, a[i]));
            a[i] = slope_at(L, &p, a[i]);
        }
        dfle_lua_push_array(L, a, n);
        return 1;
    }
    return luaL_error(L, "dfle.analytical_slope: parameter 'A' (m^2) must be a number or an "
                         "array of numbers");
}

/* dfle.analytical_exponent(rt, law, {U =, ...}) -> N of Eq. (20) */
static int l_analytical_exponent(lua_State *L)
{
    dfle_analytical_params p;
    double N;
    analytical_params(L, &p, NULL);
    N = dfle_analytical_N(&p);
    if (!isfinite(N))
        luaL_error(L, "dfle.analytical_exponent: N of Eq. (20) is not finite (%s) for alpha = "
                      "%s, beta = %s, b = %s", dfle_lua_number_text(L, N),
                   dfle_lua_number_text(L, p.alpha), dfle_lua_number_text(L, p.beta),
                   dfle_lua_number_text(L, p.b));
    lua_pushnumber(L, N);
    return 1;
}

void dfle_lua_open_analysis(lua_State *L)
{
    static const luaL_Reg funcs[] = {
        {"fit_slope_area", l_fit_slope_area},
        {"analytical_slope", l_analytical_slope},
        {"analytical_exponent", l_analytical_exponent},
        {NULL, NULL}};
    luaL_setfuncs(L, funcs, 0);
}
