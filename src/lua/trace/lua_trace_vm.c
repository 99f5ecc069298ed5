/*
 * lua_trace_vm.c - the tracer checked against the Lua that runs it, when
 * the module loads.
 *
 * lua_trace_release.c gates on the release this build was compiled for;
 * but dfle.so is loaded by whatever `lua5.4` a user has, which may be
 * another 5.4 release, with other opcode numbers or another chunk layout
 * (lua_trace_bytecode.c reads both to refuse equality tests and upvalue
 * assignments a trace cannot see).  So at load a probe function is
 * compiled by the running Lua and dumped, and its chunk must have the
 * header and the exact opcodes the tracer was written against: every
 * opcode the scan looks for, in the code Lua 5.4.4 gives.  If it differs,
 * nothing compiles (every law runs as Lua, law:compiled() says why), and
 * a warning says so once, when the module loads.
 */
#include "lua/trace/lua_trace_internal.h"

#include <lauxlib.h>
#include <stdio.h>
#include <string.h>

/* The probe: an upvalue assignment and the three equality tests the
 * scan refuses, each once. */
static const char probe_source[] = "local u = 0\n"
                                   "return function(a, b)\n"
                                   "  u = a\n"
                                   "  if a == b then return 1 end\n"
                                   "  if a == \"k\" then return 2 end\n"
                                   "  if a == 3 then return 3 end\n"
                                   "  return 4\n"
                                   "end\n";

/* Its code under Lua 5.4.4 (luac -l): SETUPVAL, EQ JMP LOADI RETURN1,
 * EQK ..., EQI ..., LOADI RETURN1, RETURN0, by lopcodes.h's numbers. */
static const unsigned char probe_ops[] = {10, 57, 56, 1, 72, 60, 56, 1,
                                          72, 61, 56, 1, 72, 1,  72, 71};
static const char *const probe_names[] = {
    "SETUPVAL", "EQ", "JMP", "LOADI", "RETURN1", "EQK", "JMP", "LOADI",
    "RETURN1", "EQI", "JMP", "LOADI", "RETURN1", "LOADI", "RETURN1", "RETURN0"};

static const char verdict_key = 'v'; /* registry: true, or why nothing compiles */

int dfle_trace_vm_check_dump(const char *dump, size_t len, char *why, size_t why_len)
{
    enum { N = sizeof probe_ops };
    unsigned char ops[N + 8];
    size_t n = 0;
    char detail[160];

    if (dfle_trace_chunk_opcodes(dump, len, ops, sizeof ops, &n, detail, sizeof detail) != 0) {
        snprintf(why, why_len, "this Lua is not the one the tracer reads: %s", detail);
        return 0;
    }
    for (size_t k = 0; k < N; k++)
        if (k >= n || ops[k] != probe_ops[k]) {
            if (k < n)
                snprintf(why, why_len, "this Lua's byte code is not the one the tracer reads: "
                                       "%s is opcode %d here, %d in Lua 5.4.4",
                         probe_names[k], ops[k], probe_ops[k]);
            else
                snprintf(why, why_len, "this Lua's byte code is not the one the tracer reads: "
                                       "the probe has %zu instructions, %d in Lua 5.4.4",
                         n, (int)N);
            return 0;
        }
    if (n != N) {
        snprintf(why, why_len, "this Lua's byte code is not the one the tracer reads: the probe "
                               "has %zu instructions, %d in Lua 5.4.4", n, (int)N);
        return 0;
    }
    return 1;
}

void dfle_trace_vm_push_probe(lua_State *L)
{
    if (luaL_loadbufferx(L, probe_source, sizeof probe_source - 1, "=dfle.trace.probe", "t") !=
            LUA_OK ||
        lua_pcall(L, 0, 1, 0) != LUA_OK || !lua_isfunction(L, -1)) {
        lua_pop(L, 1);
        lua_pushnil(L);
        return;
    }
    dfle_trace_push_dump(L, -1);
    lua_remove(L, -2);
}

void dfle_trace_vm_verify(lua_State *L, const char *dump, size_t len)
{
    char why[200];
    int ok;
    if (dump == NULL) {
        dfle_trace_vm_push_probe(L);
        dump = lua_tolstring(L, -1, &len);
        ok = dump != NULL && dfle_trace_vm_check_dump(dump, len, why, sizeof why);
        if (dump == NULL)
            snprintf(why, sizeof why, "this Lua gave no byte code of the tracer's probe");
        lua_pop(L, 1);
    } else {
        ok = dfle_trace_vm_check_dump(dump, len, why, sizeof why);
    }
    if (ok) {
        lua_pushboolean(L, 1);
    } else {
        lua_pushstring(L, why);
        /* said once, when the module loads (or a test feeds a dump) */
        lua_warning(L, "dfle: laws written in Lua are not compiled, they run as plain Lua "
                       "calls: ", 1);
        lua_warning(L, why, 0);
    }
    lua_rawsetp(L, LUA_REGISTRYINDEX, &verdict_key);
}

int dfle_trace_vm_ok(lua_State *L, char *why, size_t why_len)
{
    int ok;
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &verdict_key) == LUA_TSTRING) {
        snprintf(why, why_len, "%s", lua_tostring(L, -1));
        ok = 0;
    } else {
        ok = 1; /* checked at load; a state the module was not opened in trusts its build */
    }
    lua_pop(L, 1);
    return ok;
}
