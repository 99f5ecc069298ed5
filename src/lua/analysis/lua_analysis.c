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
#include "dfle/dem.h"
#include "dfle/law_power.h"
#include "dfle/router_empirical.h"

#define DEFAULT_NBINS 100

/* Registry key of the weak table fit -> record of its data (the address
 * is the key): dfle.write_fit and dfle.write_bins say where a fit came
 * from, as it was when fitted. */
static const char sources_key = 's';

static const char *const residual_names[] = {"linear", "log", NULL};

/* The options {nbins = 100, residuals = "linear"} at opts. */
static size_t get_fit_opts(lua_State *L, int opts, const char *fn, dfle_residuals *residuals)
{
    static const char *const other[] = {"residuals", NULL};
    double nbins = DEFAULT_NBINS;
    const dfle_lua_param params[] = {{"nbins", &nbins}};
    dfle_lua_read_params(L, opts, fn, params, 1, other);
    *residuals = DFLE_RESIDUALS_LINEAR;
    if (lua_istable(L, opts) && lua_getfield(L, opts, "residuals") != LUA_TNIL) {
        const char *r = lua_type(L, -1) == LUA_TSTRING
                            ? dfle_lua_check_string(L, -1, fn, "residuals") : NULL;
        int k = -1;
        for (int i = 0; r != NULL && residual_names[i] != NULL; i++)
            if (strcmp(r, residual_names[i]) == 0)
                k = i;
        if (k < 0)
            luaL_error(L, "dfle.%s: parameter 'residuals' must be \"linear\" (in S, the "
                          "paper's) or \"log\" (in log S), got %s", fn,
                       r != NULL ? dfle_lua_shown(L, r, strlen(r)) : dfle_lua_typename(L, -1));
        *residuals = (dfle_residuals)k;
        lua_pop(L, 1);
    }
    return (size_t)dfle_lua_check_whole(L, nbins, fn, "nbins", 1, 1e6);
}

static void set_number(lua_State *L, const char *k, double v)
{
    lua_pushnumber(L, v);
    lua_setfield(L, -2, k);
}

static void push_bins(lua_State *L, const dfle_bins *b)
{
    lua_createtable(L, 0, 11);
    dfle_lua_push_array(L, b->A, b->n), lua_setfield(L, -2, "A");
    dfle_lua_push_array(L, b->A_lo, b->n), lua_setfield(L, -2, "A_lo");
    dfle_lua_push_array(L, b->A_hi, b->n), lua_setfield(L, -2, "A_hi");
    dfle_lua_push_array(L, b->S_mean, b->n), lua_setfield(L, -2, "S");
    dfle_lua_push_array(L, b->S_median, b->n), lua_setfield(L, -2, "S_median");
    dfle_lua_push_array(L, b->S_q25, b->n), lua_setfield(L, -2, "S_q25");
    dfle_lua_push_array(L, b->S_q75, b->n), lua_setfield(L, -2, "S_q75");
    dfle_lua_push_array(L, b->S_geomean, b->n), lua_setfield(L, -2, "S_geomean");
    lua_createtable(L, (int)b->n, 0);
    for (size_t i = 0; i < b->n; i++) {
        lua_pushinteger(L, (lua_Integer)b->count[i]);
        lua_rawseti(L, -2, (lua_Integer)i + 1);
    }
    lua_setfield(L, -2, "count");
    lua_pushinteger(L, (lua_Integer)b->n_empty), lua_setfield(L, -2, "n_empty");
}

/* Push the record of the slope-area data at arg: a model (its
 * components and run), a DEM profile, or a table of n pairs. */
static void push_source_record(lua_State *L, int arg, size_t n)
{
    dfle_record *rec = dfle_lua_push_record(L, NULL);
    if (luaL_testudata(L, arg, DFLE_LUA_MODEL) != NULL) {
        dfle_lua_record_model(L, rec, arg);
    } else if (luaL_testudata(L, arg, "dfle.profile") != NULL) {
        dfle_profile_describe(*(dfle_profile **)lua_touserdata(L, arg), rec);
    } else {
        dfle_record_section(rec, "data", "table");
        dfle_record_number(rec, "pairs", (double)n, NULL);
    }
}

/* dfle.fit_slope_area(model | profile | {A=, S=} [, {nbins = 100, residuals = "linear"}]) */
static int l_fit_slope_area(lua_State *L)
{
    const double *A = NULL, *S = NULL;
    size_t nbins, n;
    dfle_residuals residuals;
    dfle_bins bins;
    dfle_eq2_fit fit;
    dfle_error err;
    int st;

    lua_settop(L, 2); /* scratch arrays go above the arguments */
    nbins = get_fit_opts(L, 2, "fit_slope_area", &residuals);
    n = dfle_lua_slope_area(L, 1, "fit_slope_area", &A, &S);

    memset(&bins, 0, sizeof bins);
    st = dfle_slope_area_fit_residuals(n, A, S, nbins, residuals, &bins, &fit, &err);
    if (st == DFLE_EFIT) {
        /* A model that has not run is still at its fluvial start, a pure
         * power law that Eq. (2) cannot fit: say so.  Whether it ran is
         * the model's record of its last run (a direct solve leaves the
         * time at 0), not its time. */
        int unrun = luaL_testudata(L, 1, DFLE_LUA_MODEL) != NULL &&
                    lua_getfield(L, 1, "has_run") == LUA_TBOOLEAN && !lua_toboolean(L, -1);
        dfle_bins_release(&bins);
        lua_pushnil(L);
        lua_pushfstring(L, "dfle.fit_slope_area: %s%s", err.msg,
                        unrun ? " (the model has not been run: its profile is the fluvial "
                                "starting state or one set; run it first, e.g. "
                                "m:run_to_steady{})"
                              : "");
        return 2;
    }
    if (st != DFLE_OK) {
        dfle_bins_release(&bins);
        return luaL_error(L, "dfle.fit_slope_area: %s", err.msg);
    }
    /* Build the table without raising in between: bins are malloc'd. */
    lua_createtable(L, 0, 16);
    set_number(L, "S_df", fit.S_df);
    set_number(L, "A_df", fit.A_df);
    set_number(L, "a2", fit.a2);
    lua_pushstring(L, residual_names[fit.residuals]), lua_setfield(L, -2, "residuals");
    set_number(L, "r2", fit.r2);
    set_number(L, "rmse", fit.rmse);
    set_number(L, "r2_log", fit.r2_log);
    set_number(L, "rmse_log", fit.rmse_log);
    set_number(L, "S_max", fit.S_max);
    set_number(L, "S_ch", fit.S_ch);
    set_number(L, "S_max_minus_S_ch", fit.S_max_minus_S_ch);
    lua_pushinteger(L, (lua_Integer)fit.n_points), lua_setfield(L, -2, "n_points");
    lua_pushinteger(L, (lua_Integer)fit.iterations), lua_setfield(L, -2, "iterations");
    lua_pushinteger(L, (lua_Integer)nbins), lua_setfield(L, -2, "nbins");
    push_bins(L, &bins);
    lua_setfield(L, -2, "bins");
    dfle_bins_release(&bins);
    dfle_lua_strict_table(L, -1, "a fit_slope_area result");
    /* Where the data came from, for the writers. */
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &sources_key) != LUA_TTABLE) {
        lua_pop(L, 1);
        lua_newtable(L);
        lua_createtable(L, 0, 1);
        lua_pushliteral(L, "k");
        lua_setfield(L, -2, "__mode");
        lua_setmetatable(L, -2);
        lua_pushvalue(L, -1);
        lua_rawsetp(L, LUA_REGISTRYINDEX, &sources_key);
    }
    lua_pushvalue(L, -2);
    push_source_record(L, 1, n);
    lua_rawset(L, -3);
    lua_pop(L, 1);
    return 1;
}

/* ---- Writers: dfle.write_fit, dfle.write_bins ------------------------- */

/* Number `key` of the fit table at t (raw: fit tables are strict), or
 * NaN when it has none. */
static double fit_number(lua_State *L, int t, const char *key)
{
    double v;
    lua_pushstring(L, key);
    v = lua_rawget(L, t) == LUA_TNUMBER ? lua_tonumber(L, -1) : NAN;
    lua_pop(L, 1);
    return v;
}

/* Check the fit at 1, the path at 2 and the options at 3; push the
 * record (the data's, as when fitted, stamped now, with the fit's
 * options) and the JSON record's path (or nil).  Returns the record. */
static dfle_record *begin_fit_output(lua_State *L, const char *fn, const char *about,
                                     const char **path, const char **jpath)
{
    static const char *const keys[] = {"record", NULL};
    dfle_record *rec;
    luaL_checktype(L, 1, LUA_TTABLE);
    *path = dfle_lua_check_string(L, 2, fn, "the path");
    lua_settop(L, 3);
    if (!lua_isnil(L, 3)) {
        luaL_checktype(L, 3, LUA_TTABLE);
        dfle_lua_read_params(L, 3, fn, NULL, 0, keys);
    }
    if (!(isfinite(fit_number(L, 1, "S_df")) && isfinite(fit_number(L, 1, "A_df")) &&
          isfinite(fit_number(L, 1, "a2"))))
        luaL_error(L, "dfle.%s: the fit must be a dfle.fit_slope_area result (a table with "
                      "numbers S_df, A_df and a2)", fn);
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &sources_key) == LUA_TTABLE) {
        lua_pushvalue(L, 1);
        lua_rawget(L, -2);
        lua_remove(L, -2);
    }
    if (lua_isuserdata(L, -1)) {
        rec = *(dfle_record **)lua_touserdata(L, -1);
        dfle_record_stamp(rec); /* the date of this file */
    } else {
        lua_pop(L, 1);
        rec = dfle_lua_push_record(L, NULL);
        dfle_record_section(rec, "data", "unknown"); /* a fit made by hand */
    }
    dfle_record_section(rec, NULL, NULL);
    dfle_record_text(rec, "about", about);
    dfle_record_section(rec, "fit", "eq2");
    if (lua_getfield(L, 1, "residuals") == LUA_TSTRING)
        dfle_record_param_text(rec, "residuals", lua_tostring(L, -1));
    lua_pop(L, 1);
    if (isfinite(fit_number(L, 1, "nbins")))
        dfle_record_param_number(rec, "nbins", fit_number(L, 1, "nbins"), NULL);
    *jpath = dfle_lua_record_path(L, rec, 3, *path, fn);
    return rec;
}

static void end_fit_output(lua_State *L, dfle_record *rec, int st, const dfle_error *err,
                           const char *path, const char *jpath)
{
    if (st != DFLE_OK)
        dfle_lua_raise(L, err);
    dfle_lua_record_done(L, rec, path, jpath);
    lua_settop(L, 1);
}

/* dfle.write_fit(fit, path [, {record =}]): one row of the fitted values. */
static int l_write_fit(lua_State *L)
{
    static const struct { const char *key, *unit; } num[] = {
        {"S_df", "-"}, {"A_df", "m^2"}, {"a2", "-"}, {"r2", "-"}, {"r2_log", "-"},
        {"rmse", "-"}, {"rmse_log", "-"}, {"S_max", "-"}, {"S_ch", "-"},
        {"S_max_minus_S_ch", "-"}, {"n_points", NULL}, {"iterations", NULL}, {"nbins", NULL}};
    enum { NNUM = sizeof num / sizeof num[0] };
    double v[NNUM];
    const char *residuals[1], *path, *jpath;
    dfle_column cols[NNUM + 1];
    dfle_record *rec;
    dfle_error err;
    int st;

    rec = begin_fit_output(L, "write_fit", "slope-area fit of Eq. (2), S = S_df / (1 + "
                           "(A/A_df)^a2): the fitted values", &path, &jpath);
    lua_getfield(L, 1, "residuals");
    residuals[0] = lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1) : NULL;
    for (size_t k = 0, j = 0; k < NNUM; k++, j++) {
        if (k == 3) /* the space the residuals were taken in, before R^2 */
            cols[j++] = (dfle_column){"residuals", NULL, NULL, residuals};
        v[k] = fit_number(L, 1, num[k].key);
        cols[j] = (dfle_column){num[k].key, num[k].unit, &v[k], NULL};
    }
    st = dfle_table_write(path, "write_fit", rec, cols, NNUM + 1, 1, 0, &err);
    end_fit_output(L, rec, st, &err, path, jpath);
    return 1;
}

/* The array `key` of the bins table at b, as n numbers in a scratch
 * userdata left on the stack (NaN where a value is missing). */
static const double *bins_column(lua_State *L, int b, const char *key, size_t n)
{
    double *v = lua_newuserdatauv(L, (n ? n : 1) * sizeof *v, 0);
    int t = lua_getfield(L, b, key);
    for (size_t i = 0; i < n; i++) {
        v[i] = NAN;
        if (t == LUA_TTABLE && lua_rawgeti(L, -1, (lua_Integer)i + 1) == LUA_TNUMBER)
            v[i] = lua_tonumber(L, -1);
        if (t == LUA_TTABLE)
            lua_pop(L, 1);
    }
    lua_pop(L, 1);
    return v;
}

/* dfle.write_bins(fit, path [, {record =}]): one row per bin. */
static int l_write_bins(lua_State *L)
{
    static const struct { const char *key, *unit; } keys[] = {
        {"A_lo", "m^2"}, {"A_hi", "m^2"}, {"A", "m^2"}, {"count", NULL}, {"S", "-"},
        {"S_median", "-"}, {"S_q25", "-"}, {"S_q75", "-"}, {"S_geomean", "-"}};
    enum { NK = sizeof keys / sizeof keys[0] };
    dfle_column cols[NK + 2];
    const char *path, *jpath;
    double S_df, A_df, a2, *S_fit, *used;
    int bins, is_log;
    dfle_record *rec;
    dfle_error err;
    size_t n;
    int st;

    rec = begin_fit_output(L, "write_bins", "slope-area bins: one row per non-empty "
                           "logarithmic area bin, with Eq. (2) as fitted (S_fit) and whether "
                           "the bin was fitted (used)", &path, &jpath);
    lua_pushliteral(L, "bins");
    if (lua_rawget(L, 1) != LUA_TTABLE)
        luaL_error(L, "dfle.write_bins: the fit has no bins (a dfle.fit_slope_area result "
                      "has them)");
    bins = lua_gettop(L);
    lua_getfield(L, bins, "A");
    n = lua_istable(L, -1) ? (size_t)lua_rawlen(L, -1) : 0;
    lua_pop(L, 1);
    S_df = fit_number(L, 1, "S_df");
    A_df = fit_number(L, 1, "A_df");
    a2 = fit_number(L, 1, "a2");
    lua_getfield(L, 1, "residuals");
    is_log = lua_type(L, -1) == LUA_TSTRING && strcmp(lua_tostring(L, -1), "log") == 0;
    lua_pop(L, 1);
    for (size_t k = 0; k < NK; k++)
        cols[k] = (dfle_column){keys[k].key, keys[k].unit, bins_column(L, bins, keys[k].key, n),
                                NULL};
    S_fit = lua_newuserdatauv(L, 2 * (n ? n : 1) * sizeof *S_fit, 0);
    used = S_fit + n;
    for (size_t i = 0; i < n; i++) {
        /* The fit's own rule: a positive mean, or a geometric mean. */
        S_fit[i] = dfle_eq2_eval(S_df, A_df, a2, cols[2].num[i]);
        used[i] = (is_log ? cols[8].num[i] : cols[4].num[i]) > 0;
    }
    cols[NK] = (dfle_column){"S_fit", "-", S_fit, NULL};
    cols[NK + 1] = (dfle_column){"used", NULL, used, NULL};
    st = dfle_table_write(path, "write_bins", rec, cols, NK + 2, n, 0, &err);
    end_fit_output(L, rec, st, &err, path, jpath);
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
        {"write_fit", l_write_fit},
        {"write_bins", l_write_bins},
        {"analytical_slope", l_analytical_slope},
        {"analytical_exponent", l_analytical_exponent},
        {NULL, NULL}};
    luaL_setfuncs(L, funcs, 0);
}
