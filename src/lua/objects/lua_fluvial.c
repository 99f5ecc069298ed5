/*
 * lua_fluvial.c - dfle.fluvial.stochastic_threshold{...} and
 * dfle.fluvial.stream_power{K =, m =, n =}.
 *
 * Both return a dfle.fluvial object with read-only fields K, m_s, n_s
 * and name, so a script can print the derived law it is running.
 */
#include "lua/core/dfle_lua.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static dfle_lua_fluvial *new_fluvial(lua_State *L)
{
    return dfle_lua_newobject(L, sizeof(dfle_lua_fluvial), DFLE_LUA_FLUVIAL, 0);
}

static int l_stochastic_threshold(lua_State *L)
{
    dfle_stochastic_threshold_opts o;
    dfle_lua_fluvial *u;
    dfle_error err;
    const dfle_lua_param params[] = {
        {"k_e", &o.k_e},         {"rho_w", &o.rho_w},     {"rho_s", &o.rho_s},
        {"D_eff", &o.D_eff},     {"b", &o.b},             {"k_w", &o.k_w},
        {"a", &o.a},             {"c", &o.c},             {"k", &o.k},
        {"omega_s", &o.omega_s}, {"alpha_f", &o.alpha_f}, {"beta_f", &o.beta_f},
        {"R_c", &o.R_c},         {"n_manning", &o.n_manning}, {"g", &o.g},
        {"tau_c_coef", &o.tau_c_coef}, {"K", &o.K_override},
        {"m_s", &o.m_override},  {"n_s", &o.n_override},
    };

    dfle_stochastic_threshold_opts_default(&o);
    dfle_lua_read_params(L, 1, "fluvial.stochastic_threshold", params,
                         sizeof params / sizeof params[0], NULL);
    /* In C a negative override means "derive"; from Lua an override is
     * only ever a value, so check it like any parameter. */
    if (!lua_isnoneornil(L, 1)) {
        static const struct { const char *key; int zero_ok; } overrides[] = {
            {"K", 1}, {"m_s", 1}, {"n_s", 0}};
        for (int i = 0; i < 3; i++) {
            if (lua_getfield(L, 1, overrides[i].key) == LUA_TNUMBER) {
                double v = lua_tonumber(L, -1);
                if (v < 0 || (v == 0 && !overrides[i].zero_ok))
                    luaL_error(L, "dfle.fluvial.stochastic_threshold: %s must be %s 0 (got %s)",
                               overrides[i].key, overrides[i].zero_ok ? ">=" : ">",
                               dfle_lua_number_text(L, v));
            }
            lua_pop(L, 1);
        }
    }
    u = new_fluvial(L);
    if (dfle_fluvial_new_stochastic_threshold(&o, &u->fl, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

static int l_stream_power(lua_State *L)
{
    double K = -1, m = -1, n = -1;
    dfle_lua_fluvial *u;
    dfle_error err;
    const dfle_lua_param params[] = {{"K", &K}, {"m", &m}, {"n", &n}};

    luaL_checktype(L, 1, LUA_TTABLE);
    dfle_lua_read_params(L, 1, "fluvial.stream_power", params, 3, NULL);
    for (int i = 0; i < 3; i++)
        if (lua_getfield(L, 1, params[i].name) == LUA_TNIL)
            luaL_error(L, "dfle.fluvial.stream_power: parameter '%s' is required",
                       params[i].name);
    u = new_fluvial(L);
    if (dfle_fluvial_new_stream_power(K, m, n, &u->fl, &err) != DFLE_OK)
        return dfle_lua_raise(L, &err);
    return 1;
}

static int l_fluvial_property(lua_State *L)
{
    dfle_fluvial *fl = dfle_lua_check_fluvial(L, 1);
    const char *key = lua_tostring(L, 2);

    if (strcmp(key, "K") == 0)
        lua_pushnumber(L, dfle_fluvial_K(fl));
    else if (strcmp(key, "m_s") == 0 || strcmp(key, "m") == 0)
        lua_pushnumber(L, dfle_fluvial_m(fl));
    else if (strcmp(key, "n_s") == 0 || strcmp(key, "n") == 0)
        lua_pushnumber(L, dfle_fluvial_n(fl));
    else if (strcmp(key, "name") == 0)
        lua_pushstring(L, dfle_fluvial_name(fl));
    else
        return 0; /* not a field: __index says so */
    return 1;
}

/* fl:rate(A, S) -> E_f [m/yr]; fl:steady_slope(U, A) -> Eq. (26). */
/* The number at idx, finite and > 0 (or >= 0): a drainage area, an
 * uplift rate.  A negative area gave NaN (A^m). */
static double check_positive(lua_State *L, int idx, const char *fn, const char *what, int zero_ok)
{
    double v = luaL_checknumber(L, idx);
    if (!(isfinite(v) && (zero_ok ? v >= 0 : v > 0)))
        luaL_error(L, "dfle.%s: %s must be a finite number %s 0, got %s", fn, what,
                   zero_ok ? ">=" : ">", dfle_lua_number_text(L, v));
    return v;
}

static int l_fluvial_rate(lua_State *L)
{
    dfle_fluvial *fl = dfle_lua_check_fluvial(L, 1);
    double A = check_positive(L, 2, "fluvial:rate", "A (drainage area, m^2)", 0);
    double S = luaL_checknumber(L, 3), E;
    if (!isfinite(S))
        luaL_error(L, "dfle.fluvial:rate: S (slope) must be a finite number, got %s",
                   dfle_lua_number_text(L, S));
    /* K A^m_s S^n_s can overflow (or be 0 * inf) for finite A and S: an
     * error, as in a run, not an inf the script computes on with. */
    E = dfle_fluvial_rate(fl, A, S);
    if (!isfinite(E))
        luaL_error(L, "dfle.fluvial:rate: E_f = K A^m_s S^n_s is not finite for A = %s m^2, "
                      "S = %s (K = %s, m_s = %s, n_s = %s)", dfle_lua_number_text(L, A),
                   dfle_lua_number_text(L, S), dfle_lua_number_text(L, dfle_fluvial_K(fl)),
                   dfle_lua_number_text(L, dfle_fluvial_m(fl)),
                   dfle_lua_number_text(L, dfle_fluvial_n(fl)));
    lua_pushnumber(L, E);
    return 1;
}

static int l_fluvial_steady_slope(lua_State *L)
{
    dfle_fluvial *fl = dfle_lua_check_fluvial(L, 1);
    double U = check_positive(L, 2, "fluvial:steady_slope", "U (uplift rate, m/yr)", 0);
    double A = check_positive(L, 3, "fluvial:steady_slope", "A (drainage area, m^2)", 0);
    double S = dfle_fluvial_steady_slope(fl, U, A);
    /* inf means "no fluvial erosion" (K = 0, documented); from overflow
     * it would mean nothing. */
    if (!isfinite(S) && dfle_fluvial_K(fl) > 0)
        luaL_error(L, "dfle.fluvial:steady_slope: S = (U/K)^(1/n_s) A^(-m_s/n_s) is not finite "
                      "for U = %s m/yr, A = %s m^2 (K = %s, m_s = %s, n_s = %s)",
                   dfle_lua_number_text(L, U), dfle_lua_number_text(L, A),
                   dfle_lua_number_text(L, dfle_fluvial_K(fl)),
                   dfle_lua_number_text(L, dfle_fluvial_m(fl)),
                   dfle_lua_number_text(L, dfle_fluvial_n(fl)));
    lua_pushnumber(L, S);
    return 1;
}

static size_t fluvial_params(const void *fl, dfle_param *out, size_t cap)
{
    return dfle_fluvial_params(fl, out, cap);
}

/* fl:params(): Table G1 and the K, m_s, n_s they give, or K, m, n. */
static int l_fluvial_params(lua_State *L)
{
    dfle_lua_push_params(L, 1, fluvial_params, dfle_lua_check_fluvial(L, 1));
    return 1;
}

static void fluvial_describe(lua_State *L, void *obj)
{
    const dfle_fluvial *fl = obj;
    char buf[160];
    snprintf(buf, sizeof buf, "dfle.fluvial.%s(K = %.5g, m_s = %.5g, n_s = %.5g)",
             dfle_fluvial_name(fl), dfle_fluvial_K(fl), dfle_fluvial_m(fl),
             dfle_fluvial_n(fl));
    lua_pushstring(L, buf);
}

static void fluvial_free(void *obj) { dfle_fluvial_free(obj); }

void dfle_lua_open_fluvial(lua_State *L)
{
    static const luaL_Reg methods[] = {
        {"rate", l_fluvial_rate}, {"steady_slope", l_fluvial_steady_slope},
        {"params", l_fluvial_params}, {NULL, NULL}};
    static const dfle_lua_type type = {
        .name = DFLE_LUA_FLUVIAL, .free = fluvial_free, .describe = fluvial_describe,
        .methods = methods, .property = l_fluvial_property,
        .fields = "K, m_s (or m), n_s (or n), name",
    };
    static const luaL_Reg funcs[] = {
        {"stochastic_threshold", l_stochastic_threshold},
        {"stream_power", l_stream_power},
        {NULL, NULL}};
    dfle_lua_register(L, &type);
    lua_newtable(L);
    luaL_setfuncs(L, funcs, 0);
    lua_setfield(L, -2, "fluvial");
}
