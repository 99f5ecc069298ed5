/*
 * lua_trace_hook.c - a test hook: trace a function of two numbers and
 * replay the record at given points, both ways the binding replays one
 * (column by column for a sweep, point by point for an integrand).
 *
 * A law only ever hands the tracer's programs finite flow fields and
 * keeps finite results, so the tests could not otherwise check the
 * replay against Lua where the rules differ most: NaN, infinities, -0.0.
 * The hook is no part of the module's API; it lives in the registry
 * (debug.getregistry()["dfle.trace.replay"]), where only tests look.
 */
#include "lua/core/dfle_lua.h"
#include "lua/trace/lua_trace.h"

/* replay(fn, xs, ys) -> column values, point values; or nil, why when
 * the tracer refuses fn(x, y, p) (p an empty table). */
static int l_replay(lua_State *L)
{
    static const char *const names[] = {"x", "y"};
    const dfle_trace_spec spec = {2, names, 3u, 1};
    size_t n, ny;
    const double *x, *y, *col;
    double *out;
    dfle_trace_prog *prog;
    char why[160];

    luaL_checktype(L, 1, LUA_TFUNCTION);
    lua_settop(L, 3);
    x = dfle_lua_check_array(L, 2, "trace.replay: xs", &n);
    y = dfle_lua_check_array(L, 3, "trace.replay: ys", &ny);
    if (n != ny)
        return luaL_error(L, "dfle.trace.replay: %d xs but %d ys", (int)n, (int)ny);
    out = lua_newuserdatauv(L, (2 * n + 1) * sizeof *out, 0);
    lua_newtable(L); /* p */
    /* From here to dfle_trace_free nothing may raise: prog is malloc'd. */
    prog = dfle_trace_compile(L, 1, -1, &spec, why, sizeof why);
    if (prog == NULL) {
        lua_pushnil(L);
        lua_pushstring(L, why);
        return 2;
    }
    col = dfle_trace_eval_n(prog, n, (const double *const[]){x, y});
    for (size_t i = 0; col != NULL && i < n; i++) {
        out[i] = col[i];
        out[n + i] = dfle_trace_eval(prog, (const double[]){x[i], y[i]});
    }
    dfle_trace_free(prog);
    if (col == NULL)
        return luaL_error(L, "dfle.trace.replay: out of memory");
    dfle_lua_push_array(L, out, n);
    dfle_lua_push_array(L, out + n, n);
    return 2;
}

void dfle_lua_open_trace_hook(lua_State *L)
{
    lua_pushcfunction(L, l_replay);
    lua_setfield(L, LUA_REGISTRYINDEX, "dfle.trace.replay");
}
