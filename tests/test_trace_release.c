/* test_trace_release.c - the tracer's release gate (lua_trace_release.c):
 * laws compile under the Lua releases the tracer was checked against,
 * and under any other every law runs as Lua and law:compiled() says why;
 * and its check of the running Lua (lua_trace_vm.c): the probe's dump is
 * accepted as it is, refused with another header, another opcode or cut
 * short, and a refusal makes every law run as Lua, said once.
 *
 * Built twice (Makefile): as test_trace_release, with this Lua's own
 * release, and as test_trace_release_unchecked, where the gate and this
 * file are compiled as if for Lua 5.4.6 (DFLE_TRACE_ASSUME_RELEASE), so
 * that the refusal is exercised end to end whatever Lua is installed. */
#include <stdlib.h>
#include <string.h>

#include "dfle_test.h"

#include <lauxlib.h>
#include <lua.h>
#include <lualib.h>

#include "dfle/lua.h"
#include "lua/trace/lua_trace.h"

static void gate_lists_checked_releases(void **state)
{
    char why[160];
    (void)state;
    assert_int_equal(dfle_trace_release_checked(50404, why, sizeof why), 1);
    assert_int_equal(dfle_trace_release_checked(50406, why, sizeof why), 0);
    assert_string_equal(why, "the tracer was not checked against Lua 5.4.6");
    assert_int_equal(dfle_trace_release_checked(50403, why, sizeof why), 0);
    assert_string_equal(why, "the tracer was not checked against Lua 5.4.3");
    assert_int_equal(dfle_trace_release_checked(50500, why, sizeof why), 0);
    assert_string_equal(why, "the tracer was not checked against Lua 5.5.0");
}

/* A law and its compile = false twin on the same model; returns the
 * compiled law's status of `rate` ("true" or its reason) in buf, and
 * checks that both gave the same E_df. */
static const char *run_law(lua_State *L, char *buf, size_t len)
{
    static const char code[] =
        "local function law(compile)\n"
        "  return dfle.law.define{ compile = compile, params = { k = 1e-4 },\n"
        "    factor = function(c, p) return c.t_p * c.h * c.Theta end,\n"
        "    rate = function(c, p) return p.k * c.S ^ 6 * c.F end }\n"
        "end\n"
        "local function e_df(l)\n"
        "  local m = dfle.model{ channel = dfle.channel{ A_max = 2e5 }, law = l }\n"
        "  m:init_fluvial_steady()\n"
        "  return m:get('E_df')\n"
        "end\n"
        "local c = law(true)\n"
        "local ec, el = e_df(c), e_df(law(false))\n"
        "for i = 1, #ec do assert(ec[i] == el[i], 'E_df differs at node ' .. i) end\n"
        "assert(c:compiled().factor == c:compiled().rate)\n"
        "return tostring(c:compiled().rate)\n";
    if (luaL_loadbuffer(L, code, sizeof code - 1, "=law") != LUA_OK ||
        lua_pcall(L, 0, 1, 0) != LUA_OK) {
        print_error("%s\n", lua_tostring(L, -1));
        fail();
    }
    snprintf(buf, len, "%s", lua_tostring(L, -1));
    lua_pop(L, 1);
    return buf;
}

static void laws_follow_the_gate(void **state)
{
    lua_State *L = luaL_newstate();
    char why[160], want[200], got[200];
    int checked = dfle_trace_release_checked(dfle_trace_release(), why, sizeof why);
    (void)state;
#ifdef DFLE_TRACE_ASSUME_RELEASE
    assert_int_equal(dfle_trace_release(), DFLE_TRACE_ASSUME_RELEASE);
    assert_int_equal(checked, 0);
#endif
    assert_non_null(L);
    luaL_openlibs(L);
    luaL_requiref(L, "dfle", luaopen_dfle, 1);
    lua_pop(L, 1);
    if (checked)
        snprintf(want, sizeof want, "true");
    else
        snprintf(want, sizeof want, "runs as Lua: %s", why);
    assert_string_equal(run_law(L, got, sizeof got), want);
    lua_close(L);
}

/* Warnings of a state, counted and kept. */
static int nwarnings;
static char warning[400];
static void keep_warning(void *ud, const char *msg, int tocont)
{
    static int cont;
    (void)ud;
    if (!cont) {
        nwarnings++;
        warning[0] = '\0';
    }
    strncat(warning, msg, sizeof warning - strlen(warning) - 1);
    cont = tocont;
}

static void running_lua_is_checked(void **state)
{
    lua_State *L = luaL_newstate();
    char why[300], got[200];
    const char *dump;
    size_t len, at = 0;
    char *bad;
    (void)state;
    assert_non_null(L);
    luaL_openlibs(L);
    lua_setwarnf(L, keep_warning, NULL);
    nwarnings = 0;
    luaL_requiref(L, "dfle", luaopen_dfle, 1);
    lua_pop(L, 1);
    assert_int_equal(nwarnings, 0); /* this Lua is the one the tracer reads */
    dfle_trace_vm_push_probe(L);
    dump = lua_tolstring(L, -1, &len);
    assert_non_null(dump);
    assert_int_equal(dfle_trace_vm_check_dump(dump, len, why, sizeof why), 1);
    /* another release's header */
    bad = malloc(len);
    memcpy(bad, dump, len);
    bad[4] = 0x55;
    assert_int_equal(dfle_trace_vm_check_dump(bad, len, why, sizeof why), 0);
    assert_string_equal(why, "this Lua is not the one the tracer reads: its byte-code header "
                             "differs from Lua 5.4.4's at byte 4");
    /* another number for EQ: SETUPVAL, EQ, JMP are the probe's first
     * instructions (4 bytes each, the opcode in the low 7 bits) */
    memcpy(bad, dump, len);
    while (at + 12 <= len && !((bad[at] & 0x7f) == 10 && (bad[at + 4] & 0x7f) == 57 &&
                               (bad[at + 8] & 0x7f) == 56))
        at++;
    assert_true(at + 12 <= len);
    bad[at + 4] = (char)((bad[at + 4] & 0x80) | 58);
    assert_int_equal(dfle_trace_vm_check_dump(bad, len, why, sizeof why), 0);
    assert_string_equal(why, "this Lua's byte code is not the one the tracer reads: EQ is opcode "
                             "58 here, 57 in Lua 5.4.4");
    /* cut short */
    assert_int_equal(dfle_trace_vm_check_dump(dump, len / 2, why, sizeof why), 0);
    /* A refusal (as the module would meet it loading into another Lua):
     * said once, and laws run as Lua with the reason. */
    dfle_trace_vm_verify(L, bad, len);
    assert_int_equal(nwarnings, 1);
    assert_msg_contains(warning, "laws written in Lua are not compiled, they run as plain Lua "
                                 "calls: this Lua's byte code is not the one the tracer reads");
    assert_int_equal(dfle_trace_vm_ok(L, got, sizeof got), 0);
#ifndef DFLE_TRACE_ASSUME_RELEASE
    snprintf(why, sizeof why, "runs as Lua: %s", got);
    assert_string_equal(run_law(L, got, sizeof got), why);
#endif
    assert_int_equal(nwarnings, 1);
    free(bad);
    lua_close(L);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(gate_lists_checked_releases),
        cmocka_unit_test(laws_follow_the_gate),
        cmocka_unit_test(running_lua_is_checked),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
