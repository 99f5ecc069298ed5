/* test_lua.c - the Lua binding itself, driven from C: every constructor
 * with its defaults, each class of bad argument, __tostring, the
 * version, the progress hooks, and error paths that must not leak (run
 * under valgrind: each test has its own lua_State, closed in teardown).
 *
 * Snippets run as chunk "=snippet", so binding errors must carry the
 * caller's position "snippet:<line>:".
 *
 * Known binding bugs are exercised by the Lua suite (tests/lua, tests
 * named "BUG: ..."); this file only asserts behaviour that holds. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dfle_test.h"

#include <lauxlib.h>
#include <lua.h>
#include <lualib.h>

#include "dfle/lua.h"
#include "lua/core/dfle_lua.h"

#ifndef DFLE_VERSION
#define DFLE_VERSION "unknown"
#endif

/* ---------------------------------------------------------------------
 * Fixtures and helpers
 * ------------------------------------------------------------------- */

static int setup(void **state)
{
    lua_State *L = luaL_newstate();
    if (L == NULL)
        return -1;
    luaL_openlibs(L);
    luaL_requiref(L, "dfle", luaopen_dfle, 1);
    lua_pop(L, 1);
    *state = L;
    return 0;
}

static int teardown(void **state)
{
    lua_close(*state);
    *state = NULL;
    return 0;
}

/* Load and run `code`; leave its first result on the stack (status
 * returned, error message on the stack on failure). */
static int run_snippet(lua_State *L, const char *code)
{
    int st = luaL_loadbuffer(L, code, strlen(code), "=snippet");
    if (st == LUA_OK)
        st = lua_pcall(L, 0, 1, 0);
    return st;
}

#define run_ok(L, code) run_ok_impl((L), (code), __FILE__, __LINE__)
static void run_ok_impl(lua_State *L, const char *code, const char *file, int line)
{
    int top = lua_gettop(L);
    if (run_snippet(L, code) != LUA_OK) {
        print_error("snippet failed: %s\n--- snippet:\n%s\n", lua_tostring(L, -1), code);
        lua_settop(L, top);
        _fail(file, line);
    }
    lua_settop(L, top);
}

/* The snippet must return a number; it is returned. */
#define eval_number(L, code) eval_number_impl((L), (code), __FILE__, __LINE__)
static double eval_number_impl(lua_State *L, const char *code, const char *file, int line)
{
    int top = lua_gettop(L);
    double v;
    if (run_snippet(L, code) != LUA_OK || lua_type(L, -1) != LUA_TNUMBER) {
        print_error("snippet did not return a number: %s\n--- snippet:\n%s\n",
                    lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1)
                                                   : luaL_typename(L, -1),
                    code);
        lua_settop(L, top);
        _fail(file, line);
    }
    v = lua_tonumber(L, -1);
    lua_settop(L, top);
    return v;
}

/* The snippet must return a string; it is copied into buf. */
#define eval_string(L, code, buf) eval_string_impl((L), (code), (buf), sizeof(buf), __FILE__, __LINE__)
static const char *eval_string_impl(lua_State *L, const char *code, char *buf, size_t size,
                                    const char *file, int line)
{
    int top = lua_gettop(L);
    int st = run_snippet(L, code);
    if (st != LUA_OK || lua_type(L, -1) != LUA_TSTRING) {
        print_error("snippet %s: %s\n--- snippet:\n%s\n",
                    st != LUA_OK ? "failed" : "did not return a string",
                    lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1)
                                                   : luaL_typename(L, -1),
                    code);
        lua_settop(L, top);
        _fail(file, line);
    }
    snprintf(buf, size, "%s", lua_tostring(L, -1));
    lua_settop(L, top);
    return buf;
}

/* The snippet must raise a string error that carries the snippet's
 * position and contains both needles (needle2 may be NULL). */
#define run_err(L, code, needle) run_err_impl((L), (code), (needle), NULL, __FILE__, __LINE__)
#define run_err2(L, code, n1, n2) run_err_impl((L), (code), (n1), (n2), __FILE__, __LINE__)
static void run_err_impl(lua_State *L, const char *code, const char *needle,
                         const char *needle2, const char *file, int line)
{
    int top = lua_gettop(L);
    const char *msg;
    if (run_snippet(L, code) == LUA_OK) {
        print_error("snippet succeeded, expected an error with \"%s\"\n--- snippet:\n%s\n",
                    needle, code);
        lua_settop(L, top);
        _fail(file, line);
    }
    msg = lua_tostring(L, -1);
    if (msg == NULL || strstr(msg, "snippet:") != msg || strstr(msg, needle) == NULL ||
        (needle2 != NULL && strstr(msg, needle2) == NULL)) {
        print_error("error \"%s\" should start with \"snippet:\" and contain \"%s\"%s%s%s\n"
                    "--- snippet:\n%s\n",
                    msg != NULL ? msg : "(not a string)", needle,
                    needle2 != NULL ? " and \"" : "", needle2 != NULL ? needle2 : "",
                    needle2 != NULL ? "\"" : "", code);
        lua_settop(L, top);
        _fail(file, line);
    }
    lua_settop(L, top);
}

#define assert_prefix(s, prefix)                                                          \
    do {                                                                                  \
        if (strncmp((s), (prefix), strlen(prefix)) != 0) {                                \
            print_error("\"%s\" does not start with \"%s\"\n", (s), (prefix));            \
            _fail(__FILE__, __LINE__);                                                    \
        }                                                                                 \
    } while (0)

/* A small model (45 nodes) as the global m. */
static const char small_model[] = "m = dfle.model{ channel = dfle.channel{ A_max = 2e5 } }";

/* ---------------------------------------------------------------------
 * Module, version, constructors with defaults, __tostring
 * ------------------------------------------------------------------- */

static void version_is_a_string(void **state)
{
    lua_State *L = *state;
    char buf[64];
    assert_string_equal(eval_string(L, "return type(dfle.version)", buf), "string");
    assert_string_equal(eval_string(L, "return dfle.version", buf), DFLE_VERSION);
    /* The module is also registered in package.loaded by luaL_requiref. */
    assert_true(eval_number(L, "return rawequal(package.loaded.dfle, dfle) and 1 or 0") == 1);
}

static void luaopen_returns_a_module_table(void **state)
{
    lua_State *L = *state;
    int top = lua_gettop(L);
    lua_pushcfunction(L, luaopen_dfle);
    lua_call(L, 0, 1);
    assert_int_equal(lua_type(L, -1), LUA_TTABLE);
    assert_int_equal(lua_getfield(L, -1, "model"), LUA_TFUNCTION);
    lua_pop(L, 1);
    assert_int_equal(lua_getfield(L, -1, "fluvial"), LUA_TTABLE);
    assert_int_equal(lua_getfield(L, -1, "stream_power"), LUA_TFUNCTION);
    lua_pop(L, 2);
    /* A second copy of the module works alongside the first. */
    lua_setglobal(L, "dfle2");
    lua_settop(L, top);
    assert_true(eval_number(L, "return dfle2.model{ channel = dfle2.channel{ A_max = 2e5 } }.n") ==
                45);
    assert_true(eval_number(L, "return dfle.channel{ A_max = 2e5 }.n") == 45);
}

static void channel_defaults(void **state)
{
    lua_State *L = *state;
    char buf[256];
    run_ok(L, "ch = dfle.channel{}");
    assert_true(eval_number(L, "return ch.n") == 403);
    assert_true(eval_number(L, "return #ch") == 403);
    assert_close(eval_number(L, "return ch.dx"), 5.0, 0, 0);
    assert_close(eval_number(L, "return ch.length"), 2010.0, 1e-12, 0);
    assert_close(eval_number(L, "return ch:get('A')[1]"), 1000.0, 1e-12, 0);
    assert_true(eval_number(L, "return ch.A_max") >= 8e6);
    /* No argument at all is the same as {}. */
    assert_true(eval_number(L, "return dfle.channel().n") == 403);
    eval_string(L, "return tostring(ch)", buf);
    assert_prefix(buf, "dfle.channel(n = 403, dx = 5");
    assert_msg_contains(buf, "m^2");
}

static void fluvial_defaults(void **state)
{
    lua_State *L = *state;
    char buf[256];
    run_ok(L, "fl = dfle.fluvial.stochastic_threshold{}");
    assert_close(eval_number(L, "return fl.K"), 2.4539e-10, 1e-4, 0);
    assert_close(eval_number(L, "return fl.m_s"), 1.4, 1e-4, 0);
    assert_close(eval_number(L, "return fl.n_s"), 2.3333, 1e-4, 0);
    assert_string_equal(eval_string(L, "return fl.name", buf), "stochastic_threshold");
    assert_close(eval_number(L, "return fl:steady_slope(5e-4, 1e6)"), 0.1270, 1e-3, 0);
    eval_string(L, "return tostring(fl)", buf);
    assert_prefix(buf, "dfle.fluvial.stochastic_threshold(K = 2.4539e-10, m_s = 1.4, n_s = 2.3333");
    assert_close(eval_number(L, "return dfle.fluvial.stochastic_threshold().K"), 2.4539e-10, 1e-4, 0);

    run_ok(L, "sp = dfle.fluvial.stream_power{ K = 3e-6, m = 0.45, n = 1.1 }");
    assert_close(eval_number(L, "return sp.K"), 3e-6, 0, 0);
    assert_close(eval_number(L, "return sp.m_s"), 0.45, 0, 0);
    assert_close(eval_number(L, "return sp.n_s"), 1.1, 0, 0);
    eval_string(L, "return tostring(sp)", buf);
    assert_prefix(buf, "dfle.fluvial.stream_power(K = 3e-06, m_s = 0.45, n_s = 1.1");
}

static void router_defaults(void **state)
{
    lua_State *L = *state;
    char buf[256];
    run_ok(L, "rt = dfle.router.empirical{}");
    assert_close(eval_number(L, "return rt.M0"), 3000, 0, 0);
    assert_close(eval_number(L, "return rt.gamma"), 0.5, 0, 0);
    assert_close(eval_number(L, "return rt.mu"), 500, 0, 0);
    assert_close(eval_number(L, "return rt.tau_y"), 300, 0, 0);
    assert_close(eval_number(L, "return rt:params().c2"), 0.78, 0, 0);
    assert_string_equal(eval_string(L, "return rt.name", buf), "empirical");
    eval_string(L, "return tostring(rt)", buf);
    assert_string_equal(buf,
                        "dfle.router.empirical(M0 = 3000 m^(3-2 gamma), gamma = 0.5, mu = 500 Pa s, "
                        "tau_y = 300 Pa, c1 = 0.135, c2 = 0.78, rho_b = 1800 kg/m^3, "
                        "g = 9.81 m/s^2)");
}

static void law_defaults(void **state)
{
    lua_State *L = *state;
    char buf[256];
    run_ok(L, "law = dfle.law.power{}");
    assert_close(eval_number(L, "return law.k_df"), 1e-4, 0, 0);
    assert_close(eval_number(L, "return law.alpha"), 6, 0, 0);
    assert_close(eval_number(L, "return law.beta"), 1, 0, 0);
    assert_string_equal(eval_string(L, "return law.name", buf), "power");
    eval_string(L, "return tostring(law)", buf);
    assert_string_equal(buf, "dfle.law.power(k_df = 0.0001, alpha = 6, beta = 1)");
}

static void model_defaults(void **state)
{
    lua_State *L = *state;
    char buf[256];
    run_ok(L, "m = dfle.model{}");
    assert_true(eval_number(L, "return m.n") == 403);
    assert_close(eval_number(L, "return m.U"), 5e-4, 0, 0);
    assert_close(eval_number(L, "return m.time"), 0, 0, 0);
    assert_string_equal(eval_string(L, "return m.fluvial.name", buf), "stochastic_threshold");
    assert_string_equal(eval_string(L, "return m.router.name", buf), "empirical");
    assert_string_equal(eval_string(L, "return m.law.name", buf), "power");
    assert_true(eval_number(L, "return #m:get('S')") == 403);
    eval_string(L, "return tostring(m)", buf);
    assert_prefix(buf, "dfle.model(n = 403, U = 0.0005 m/yr, t = 0 yr");
    assert_msg_contains(buf, "fluvial = stochastic_threshold");
    assert_msg_contains(buf, "router = empirical");
    /* Switched off. */
    eval_string(L, "return tostring(dfle.model{ channel = dfle.channel{ A_max = 2e5 }, "
                   "router = false, fluvial = false })",
                buf);
    assert_msg_contains(buf, "fluvial = off");
    assert_msg_contains(buf, "router = off");
    /* The default model starts from Eq. (26). */
    assert_close(eval_number(L, "return m:get('S')[1] / m.fluvial:steady_slope(m.U, m:get('A')[1])"),
                 1.0, 1e-9, 0);
}

static void analytical_check_values(void **state)
{
    lua_State *L = *state;
    run_ok(L, "rt = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500 }\n"
              "law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 }");
    assert_close(eval_number(L, "return dfle.analytical_slope(rt, law, { U = 5e-4, A = 1e4 })"),
                 0.73834, 1e-4, 0);
    assert_close(eval_number(L, "return dfle.analytical_exponent(rt, law, { U = 5e-4 })"),
                 -0.024706, 1e-4, 0);
    assert_close(eval_number(L, "return dfle.analytical_slope(rt, law, { U = 5e-4, A = { 1, 1e4 } })[2]"),
                 0.73834, 1e-4, 0);
}

/* ---------------------------------------------------------------------
 * Errors: each class for each constructor
 * ------------------------------------------------------------------- */

typedef struct err_case {
    const char *code;
    const char *needle;
    const char *needle2;
} err_case;

static void run_cases(lua_State *L, const err_case *c, size_t n)
{
    for (size_t i = 0; i < n; i++)
        run_err2(L, c[i].code, c[i].needle, c[i].needle2);
}

static void channel_errors(void **state)
{
    static const err_case cases[] = {
        {"dfle.channel{ bogus = 1 }", "unknown parameter 'bogus'", "dx, A0"},
        {"dfle.channel{ dx = 'five' }", "'dx'", "must be a number, got string"},
        {"dfle.channel{ dx = -5 }", "dx", "> 0"},
        {"dfle.channel{ dx = 0 }", "dx", "> 0"},
        {"dfle.channel{ dx = 0/0 }", "'dx'", "finite"},
        {"dfle.channel{ dx = 1/0 }", "'dx'", "finite"},
        {"dfle.channel('dx = 5')", "dfle.channel", "table"},
        {"dfle.channel{ 5 }", "dfle.channel", "named"},
        {"dfle.channel{ A_max = 1 }", "A_max", NULL},
    };
    run_cases(*state, cases, sizeof cases / sizeof cases[0]);
}

static void fluvial_errors(void **state)
{
    static const err_case cases[] = {
        {"dfle.fluvial.stochastic_threshold{ bogus = 1 }", "unknown parameter 'bogus'", "k_e"},
        {"dfle.fluvial.stochastic_threshold{ k_e = '1' }", "'k_e'", "number"},
        {"dfle.fluvial.stochastic_threshold{ k_e = -1 }", "k_e", "> 0"},
        {"dfle.fluvial.stochastic_threshold{ k_e = 0 }", "k_e", "> 0"},
        {"dfle.fluvial.stochastic_threshold{ k_e = 0/0 }", "'k_e'", "finite"},
        {"dfle.fluvial.stochastic_threshold{ k_e = 1/0 }", "'k_e'", "finite"},
        {"dfle.fluvial.stochastic_threshold(true)", "stochastic_threshold", "table"},
        {"dfle.fluvial.stochastic_threshold{ K = -1 }", "K", ">= 0"},
        {"dfle.fluvial.stream_power{ K = 1, m = 1, n = 1, bogus = 1 }", "unknown parameter 'bogus'",
         "K, m, n"},
        {"dfle.fluvial.stream_power{ K = {}, m = 1, n = 1 }", "'K'", "number"},
        {"dfle.fluvial.stream_power{ K = -1, m = 1, n = 1 }", "K", ">= 0"},
        {"dfle.fluvial.stream_power{ K = 1, m = 1, n = 0 }", "n", "> 0"},
        {"dfle.fluvial.stream_power{ K = 1, m = 0/0, n = 1 }", "'m'", "finite"},
        {"dfle.fluvial.stream_power{ K = 1/0, m = 1, n = 1 }", "'K'", "finite"},
        {"dfle.fluvial.stream_power{ K = 1, m = 1 }", "'n'", "required"},
        {"dfle.fluvial.stream_power(7)", "table", NULL},
    };
    run_cases(*state, cases, sizeof cases / sizeof cases[0]);
}

static void router_and_law_errors(void **state)
{
    static const err_case cases[] = {
        {"dfle.router.empirical{ bogus = 1 }", "unknown parameter 'bogus'", "M0, gamma"},
        {"dfle.router.empirical{ M0 = 'big' }", "'M0'", "number"},
        {"dfle.router.empirical{ M0 = -1 }", "M0", "> 0"},
        {"dfle.router.empirical{ M0 = 0 }", "M0", "> 0"},
        {"dfle.router.empirical{ mu = 0/0 }", "'mu'", "finite"},
        {"dfle.router.empirical{ tau_y = 1/0 }", "'tau_y'", "finite"},
        {"dfle.router.empirical{ tau_y = -1 }", "tau_y", ">= 0"},
        {"dfle.router.empirical('x')", "router.empirical", "table"},
        {"dfle.law.power{ bogus = 1 }", "unknown parameter 'bogus'", "k_df, alpha, beta"},
        {"dfle.law.power{ k_df = false }", "'k_df'", "boolean"},
        {"dfle.law.power{ k_df = -1 }", "k_df", "> 0"},
        {"dfle.law.power{ k_df = 0 }", "k_df", "> 0"},
        {"dfle.law.power{ alpha = 0/0 }", "'alpha'", "finite"},
        {"dfle.law.power{ beta = -1/0 }", "'beta'", "finite"},
        {"dfle.law.power(1)", "law.power", "table"},
    };
    run_cases(*state, cases, sizeof cases / sizeof cases[0]);
}

static void model_errors(void **state)
{
    static const err_case cases[] = {
        {"dfle.model{ bogus = 1 }", "unknown parameter 'bogus'", "channel"},
        {"dfle.model{ U = 'slow' }", "'U'", "number"},
        {"dfle.model{ U = -5e-4 }", "U", "> 0"},
        {"dfle.model{ U = 0 }", "U", "> 0"},
        {"dfle.model{ U = 0/0 }", "'U'", "finite"},
        {"dfle.model{ U = 1/0 }", "'U'", "finite"},
        {"dfle.model('fast')", "table", NULL},
        {"dfle.model{ router = false, law = dfle.law.power{} }", "law", "router"},
        {"dfle.model{ router = dfle.channel{ A_max = 2e5 } }", "'router'", "dfle.router"},
        {"dfle.model{ channel = dfle.router.empirical{} }", "'channel'", "dfle.channel"},
        {"dfle.model{ channel = false }", "'channel'", NULL},
        {"dfle.model{ law = false }", "law", NULL},
        {"dfle.model{ cfl = 2 }", "cfl", NULL},
    };
    run_cases(*state, cases, sizeof cases / sizeof cases[0]);
}

static void method_errors(void **state)
{
    lua_State *L = *state;
    static const err_case cases[] = {
        {"m:run{}", "'years'", "required"},
        {"m:run()", "table", NULL},
        {"m:run{ years = 10, bogus = 1 }", "unknown parameter 'bogus'", "years"},
        {"m:run{ years = 'ten' }", "'years'", "number"},
        {"m:run{ years = 0/0 }", "'years'", "finite"},
        {"m:run{ years = 1/0 }", "'years'", "finite"},
        {"m:run{ years = 10, max_steps = 0 }", "max_steps", NULL},
        {"m:run{ years = 10, progress = 1 }", "'progress'", "boolean"},
        {"m:run_to_steady{ tol = -1 }", "tol", "> 0"},
        {"m:run_to_steady{ tol = 0 }", "tol", "> 0"},
        {"m:run_to_steady{ tol = 0/0 }", "'tol'", "finite"},
        {"m:run_to_steady{ max_time = 1/0 }", "'max_time'", "finite"},
        {"m:run_to_steady{ max_time = -1 }", "max_time", NULL},
        {"m:run_to_steady{ bogus = 1 }", "unknown parameter 'bogus'", "tol, max_time"},
        {"m:run_to_steady('x')", "table", NULL},
        {"m:get('nope')", "'nope'", "x, A, w, z, S"},
        {"m:set_z{ 1, 2, 3 }", "z", "3"},
        {"m:set_z('z')", "z", "array"},
        {"m:set_U(-1)", "U", "> 0"},
        {"m:set_U('x')", "number expected", NULL},
        {"m:write_csv('/nonexistent-dir/x/y.csv')", "/nonexistent-dir/x/y.csv", NULL},
        {"m:init_fluvial_steady(m.router)", "dfle.fluvial", "dfle.router"},
        {"m.get(m.channel, 'S')", "dfle.model", "dfle.channel"},
        {"dfle.fit_slope_area({ A = { 1, 2, 3 }, S = { 1, 2 } }, {})", "A has 3", "S has 2"},
        {"dfle.fit_slope_area(m, { nbins = 0 })", "nbins", NULL},
        {"dfle.fit_slope_area(m, { nbins = 1/0 })", "'nbins'", "finite"},
        {"dfle.fit_slope_area(m, { bogus = 1 })", "unknown parameter 'bogus'", "nbins"},
        {"dfle.fit_slope_area(m.channel)", "dfle.model", NULL},
        {"dfle.analytical_slope(m.channel, m.law, { A = 1 })", "dfle.router", "dfle.channel"},
        {"dfle.analytical_slope(m.router, m.law, { A = -1 })", "A", "> 0"},
        {"dfle.analytical_slope(m.router, m.law, { A = 1, U = 0/0 })", "'U'", "finite"},
        {"dfle.analytical_slope(m.router, m.law, { A = 1, bogus = 1 })", "unknown parameter 'bogus'",
         "U"},
        {"dfle.analytical_exponent(m.router, m.law, { U = -1 })", "U", "> 0"},
        {"dfle.analytical_exponent(m.router, m.law, 'x')", "table", NULL},
        {"dfle.plot.profile(m, 'p.txt')", ".png", NULL},
        {"dfle.plot.slope_area(m, 'p.png', nil, { nbins = 0/0 })", "'nbins'", "finite"},
        {"dfle.plot.slope_area(m, 'p.png', nil, { bogus = 1 })", "unknown parameter 'bogus'",
         "nbins"},
        {"dfle.plot.xy{ path = 'p.png', series = {}, bogus = 1 }", "unknown parameter 'bogus'",
         "path"},
        {"dfle.plot.xy{ path = 'p.png', series = { { x = { 1, 2 }, y = { 1 } } } }", "series[1]",
         NULL},
    };
    run_ok(L, small_model);
    run_cases(L, cases, sizeof cases / sizeof cases[0]);
    /* Nothing was simulated by the failed calls, nor U changed. */
    assert_close(eval_number(L, "return m.time"), 0, 0, 0);
    assert_close(eval_number(L, "return m.U"), 5e-4, 0, 0);
}

static void error_position_is_the_callers_line(void **state)
{
    lua_State *L = *state;
    int top = lua_gettop(L);
    assert_int_not_equal(run_snippet(L, "local a = 1\n\nlocal ch = dfle.channel{ dx = -1 }\n"),
                         LUA_OK);
    assert_prefix(lua_tostring(L, -1), "snippet:3: dfle.channel: ");
    lua_settop(L, top);
    /* Also from inside a Lua function. */
    assert_int_not_equal(run_snippet(L, "local function f(o)\n  return dfle.law.power(o)\nend\n"
                                        "f{ alpha = 'six' }\n"),
                         LUA_OK);
    assert_prefix(lua_tostring(L, -1), "snippet:2: dfle.law.power: ");
    lua_settop(L, top);
}

/* ---------------------------------------------------------------------
 * Lifetime: <close>, garbage collection, the registry copy of the module
 * ------------------------------------------------------------------- */

static void closed_model_raises(void **state)
{
    lua_State *L = *state;
    run_ok(L, "m = dfle.model{ channel = dfle.channel{ A_max = 2e5 } }\n"
              "do local c <close> = m end");
    run_err(L, "return m:get('S')", "closed");
    run_err(L, "return m:run{ years = 1 }", "closed");
    run_err(L, "return m.time", "closed");
    run_err(L, "return dfle.plot.profile(m, 'x.png')", "closed");
    /* The finalizer after __close must be harmless. */
    run_ok(L, "m = nil; collectgarbage(); collectgarbage()");
}

static void model_keeps_components_alive(void **state)
{
    lua_State *L = *state;
    run_ok(L, "m = dfle.model{ channel = dfle.channel{ A_max = 2e5 },\n"
              "  fluvial = dfle.fluvial.stream_power{ K = 1e-5, m = 0.5, n = 1 },\n"
              "  router = dfle.router.empirical{ tau_y = 100 }, law = dfle.law.power{ alpha = 5 } }\n"
              "collectgarbage(); collectgarbage()");
    run_ok(L, "assert(m:run{ years = 500 }.reason == 'time')");
    assert_close(eval_number(L, "return m.router.tau_y"), 100, 0, 0);
    assert_close(eval_number(L, "return m.law.alpha"), 5, 0, 0);
    assert_close(eval_number(L, "return m.fluvial.K"), 1e-5, 0, 0);
    assert_true(eval_number(L, "return m.channel.n") == 45);
}

static void module_found_without_globals(void **state)
{
    lua_State *L = *state;
    /* Defaults are built through the registry's module table. */
    run_ok(L, "local d = dfle\n"
              "dfle = nil; package.loaded.dfle = nil\n"
              "m = d.model{ channel = d.channel{ A_max = 2e5 } }");
    assert_true(eval_number(L, "return m.n") == 45);
    assert_true(eval_number(L, "return m:run{ years = 10 }.time") == 10);
}

/* ---------------------------------------------------------------------
 * Error paths that must not leak (valgrind checks)
 * ------------------------------------------------------------------- */

static void errors_during_runs_do_not_leak(void **state)
{
    lua_State *L = *state;
    run_ok(L, small_model);
    /* Options rejected at the start of a run, repeatedly. */
    run_ok(L, "for i = 1, 20 do\n"
              "  assert(not pcall(m.run_to_steady, m, { tol = -1 }))\n"
              "  assert(not pcall(m.run_to_steady, m, { max_time = 1, bogus = true }))\n"
              "  assert(not pcall(m.run, m, { years = 10, max_steps = 0 }))\n"
              "end");
    /* A numeric blow-up inside dfle_solver_run: the error is raised after
     * the run has started stepping. */
    run_ok(L, "bad = dfle.model{ channel = dfle.channel{ A_max = 2e5 }, router = false,\n"
              "  fluvial = dfle.fluvial.stream_power{ K = 1e-3, m = 0, n = 200 } }");
    run_ok(L, "local z = {}\n"
              "for i = 1, bad.n do z[i] = (bad.n - i) * 1e4 end\n"
              "bad:set_z(z)");
    run_err2(L, "return bad:run{ years = 100 }", "not finite", "node");
    run_ok(L, "local p = os.tmpname()\n"
              "local ok, e = pcall(bad.write_csv, bad, p)\n"
              "os.remove(p)\n"
              "assert(not ok and e:find('not finite'), tostring(e))");
    /* Errors with scratch arrays and bins allocated before the raise. */
    run_ok(L, "for i = 1, 20 do\n"
              "  assert(not pcall(dfle.fit_slope_area, { A = { 1, 2, 3, 4 }, S = { 1, 2, 'x', 4 } }, {}))\n"
              "  assert(not pcall(dfle.analytical_slope, m.router, m.law, { A = { 1, 2, -3 } }))\n"
              "  assert(not pcall(m.set_z, m, { 1, 2 }))\n"
              "  assert(not pcall(dfle.plot.slope_area, m, 'x.txt'))\n"
              "  assert(not pcall(dfle.plot.xy, { path = 'x.png', series = { { x = { 1 }, y = { 1 } },\n"
              "                                  { x = { 1, 2 }, y = { 1 } } } }))\n"
              "  assert(not pcall(dfle.channel, { dx = -1 }))\n"
              "  assert(not pcall(dfle.model, { channel = m.channel, U = -1 }))\n"
              "end");
    /* A fit that cannot converge returns nil, message (bins released). */
    run_ok(L, "local A, S = {}, {}\n"
              "for i = 1, 200 do A[i] = 10 ^ (3 + 4 * (i - 1) / 199); S[i] = 3 * A[i] ^ -0.5 end\n"
              "for i = 1, 5 do\n"
              "  local f, msg = dfle.fit_slope_area({ A = A, S = S }, {})\n"
              "  assert(f == nil and type(msg) == 'string', tostring(msg))\n"
              "end");
    /* The good model still works after all that. */
    assert_true(eval_number(L, "return m:run{ years = 100 }.time") == 100);
}

/* ---------------------------------------------------------------------
 * Progress hooks (installed by the CLI; library users get none)
 * ------------------------------------------------------------------- */

typedef struct progress_count {
    int updates, finishes, cancel_after;
    double last_time;
} progress_count;

static int count_update(void *ud, const dfle_run_status *st)
{
    progress_count *c = ud;
    c->updates++;
    c->last_time = st->time;
    return c->cancel_after > 0 && c->updates >= c->cancel_after;
}

static void count_finish(void *ud)
{
    ((progress_count *)ud)->finishes++;
}

static void progress_hooks(void **state)
{
    lua_State *L = *state;
    progress_count c = {0, 0, 0, 0.0};
    dfle_lua_progress hooks = {.update = count_update, .finish = count_finish, .ud = &c};

    assert_null(dfle_lua_get_progress(L));
    dfle_lua_set_progress(L, &hooks);
    assert_ptr_equal(dfle_lua_get_progress(L), &hooks);
    run_ok(L, small_model);

    /* dt <= dt_max = 1000 yr: 1e6 yr take at least 1000 steps. */
    run_ok(L, "assert(m:run{ years = 1e6 }.reason == 'time')");
    assert_true(c.updates >= 1);
    assert_int_equal(c.finishes, 1);
    assert_true(c.last_time > 0 && c.last_time <= 1e6);

    /* progress = false: no hook for this run. */
    c.updates = c.finishes = 0;
    run_ok(L, "m:run{ years = 1e6, progress = false }");
    assert_int_equal(c.updates, 0);
    assert_int_equal(c.finishes, 0);

    /* A hook that cancels: the run raises, and finish is still called. */
    c.cancel_after = 1;
    run_err(L, "m:run{ years = 1e6 }", "progress");
    assert_int_equal(c.updates, 1);
    assert_int_equal(c.finishes, 1);

    dfle_lua_set_progress(L, NULL);
    assert_null(dfle_lua_get_progress(L));
    c.updates = 0;
    run_ok(L, "m:run{ years = 1e6 }");
    assert_int_equal(c.updates, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(version_is_a_string, setup, teardown),
        cmocka_unit_test_setup_teardown(luaopen_returns_a_module_table, setup, teardown),
        cmocka_unit_test_setup_teardown(channel_defaults, setup, teardown),
        cmocka_unit_test_setup_teardown(fluvial_defaults, setup, teardown),
        cmocka_unit_test_setup_teardown(router_defaults, setup, teardown),
        cmocka_unit_test_setup_teardown(law_defaults, setup, teardown),
        cmocka_unit_test_setup_teardown(model_defaults, setup, teardown),
        cmocka_unit_test_setup_teardown(analytical_check_values, setup, teardown),
        cmocka_unit_test_setup_teardown(channel_errors, setup, teardown),
        cmocka_unit_test_setup_teardown(fluvial_errors, setup, teardown),
        cmocka_unit_test_setup_teardown(router_and_law_errors, setup, teardown),
        cmocka_unit_test_setup_teardown(model_errors, setup, teardown),
        cmocka_unit_test_setup_teardown(method_errors, setup, teardown),
        cmocka_unit_test_setup_teardown(error_position_is_the_callers_line, setup, teardown),
        cmocka_unit_test_setup_teardown(closed_model_raises, setup, teardown),
        cmocka_unit_test_setup_teardown(model_keeps_components_alive, setup, teardown),
        cmocka_unit_test_setup_teardown(module_found_without_globals, setup, teardown),
        cmocka_unit_test_setup_teardown(errors_during_runs_do_not_leak, setup, teardown),
        cmocka_unit_test_setup_teardown(progress_hooks, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
