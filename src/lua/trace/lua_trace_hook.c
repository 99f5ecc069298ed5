/*
 * lua_trace_hook.c - test hooks: trace a function of two numbers and
 * replay the record at given points, both ways the binding replays one
 * (column by column for a sweep, point by point for an integrand); and
 * the counters of the per-state cache of programs (lua_trace_cache.c).
 *
 * A law only ever hands the tracer's programs finite flow fields and
 * keeps finite results, so the tests could not otherwise check the
 * replay against Lua where the rules differ most: NaN, infinities, -0.0.
 * The hooks are no part of the module's API; they live in the registry
 * (debug.getregistry()["dfle.trace.replay"], ["dfle.trace.stats"],
 * ["dfle.trace.vm"]: the check of the running Lua fed another dump),
 * where only tests and benchmarks look.
 */
#include "lua/core/dfle_lua.h"
#include "lua/trace/lua_trace.h"

/* replay(fn, xs, ys [, p]) -> column values, point values; or nil, why
 * when the tracer refuses fn(x, y, p).  Without p, p is an empty table;
 * with p, its float values are inputs of the program, as a law's are. */
static int l_replay(lua_State *L)
{
    static const char *const names[] = {"x", "y"};
    const dfle_trace_spec spec = {2, names, 3u, 1, !lua_isnoneornil(L, 4)};
    size_t n, ny;
    const double *x, *y, *col;
    double *out;
    dfle_trace_prog *prog;
    char why[160];

    luaL_checktype(L, 1, LUA_TFUNCTION);
    if (spec.params_inputs)
        luaL_checktype(L, 4, LUA_TTABLE);
    lua_settop(L, 4);
    x = dfle_lua_check_array(L, 2, "trace.replay: xs", &n);
    y = dfle_lua_check_array(L, 3, "trace.replay: ys", &ny);
    if (n != ny)
        return luaL_error(L, "dfle.trace.replay: %d xs but %d ys", (int)n, (int)ny);
    out = lua_newuserdatauv(L, (2 * n + 1) * sizeof *out, 0);
    if (spec.params_inputs)
        lua_pushvalue(L, 4); /* p */
    else
        lua_newtable(L);
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

/* stats() -> { traced, found, kept, checked, held, retraced }: what the
 * cache of programs of this state has done so far. */
static int l_stats(lua_State *L)
{
    const dfle_trace_stats *st = dfle_trace_stats_of(L);
    const unsigned long v[] = {st ? st->traced : 0, st ? st->found : 0, st ? st->kept : 0,
                               st ? st->checked : 0, st ? st->held : 0, st ? st->retraced : 0};
    static const char *const k[] = {"traced", "found", "kept", "checked", "held", "retraced"};
    lua_createtable(L, 0, 6);
    for (int i = 0; i < 6; i++) {
        lua_pushinteger(L, (lua_Integer)v[i]);
        lua_setfield(L, -2, k[i]);
    }
    return 1;
}

/* The hooks of the first binding opened in a state stay: a second copy
 * (dfle.so required by a host that has the binding built in) keeps a
 * cache of its own, and the laws of the first are the ones tests watch. */
static void set_hook(lua_State *L, const char *name, lua_CFunction fn)
{
    if (lua_getfield(L, LUA_REGISTRYINDEX, name) == LUA_TNIL) {
        lua_pushcfunction(L, fn);
        lua_setfield(L, LUA_REGISTRYINDEX, name);
    }
    lua_pop(L, 1);
}

/* vm() -> this Lua's dump of the tracer's probe; vm(dump) -> true, or
 * false and why, for that dump; vm(dump, true) also makes it this
 * state's verdict (a test of the refusal). */
static int l_vm(lua_State *L)
{
    size_t len;
    const char *dump;
    char why[200];
    if (lua_isnoneornil(L, 1)) {
        dfle_trace_vm_push_probe(L);
        return 1;
    }
    dump = luaL_checklstring(L, 1, &len);
    if (lua_toboolean(L, 2))
        dfle_trace_vm_verify(L, dump, len);
    if (dfle_trace_vm_check_dump(dump, len, why, sizeof why)) {
        lua_pushboolean(L, 1);
        return 1;
    }
    lua_pushboolean(L, 0);
    lua_pushstring(L, why);
    return 2;
}

void dfle_lua_open_trace_hook(lua_State *L)
{
    char why[8];
    /* The Lua running this state, checked once (the first binding opened
     * in it; its verdict is read by every copy). */
    if (lua_getfield(L, LUA_REGISTRYINDEX, "dfle.trace.vm") == LUA_TNIL &&
        dfle_trace_vm_ok(L, why, sizeof why))
        dfle_trace_vm_verify(L, NULL, 0);
    lua_pop(L, 1);
    dfle_trace_cache_open(L);
    set_hook(L, "dfle.trace.replay", l_replay);
    set_hook(L, "dfle.trace.stats", l_stats);
    set_hook(L, "dfle.trace.vm", l_vm);
}
