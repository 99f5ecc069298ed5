/*
 * lua_trace_release.c - the Lua releases the tracer was checked against.
 *
 * The tracer relies on Lua internals that no API promises: the opcode
 * numbers and the layout of lua_dump's chunks (lua_trace_bytecode.c),
 * and the exact arithmetic of the VM and of lmathlib, which the replay
 * copies (lua_trace_eval.c).  They were read in the sources of the
 * releases listed below and tested there (tests/lua/test_compile.lua).
 * Under any other release nothing compiles: every law runs as Lua, and
 * law:compiled() says why.  To add a release, check lopcodes.h, ldump.c,
 * llimits.h and lvm.c (luai_nummod, luai_numpow, ...) and lmathlib.c of
 * that release against those files, then run the tests under it.
 */
#include "lua/trace/lua_trace.h"

#include <stdio.h>

/* The release this build runs under; a test build pretends another
 * (Makefile: test_trace_release_unchecked). */
#if defined(DFLE_TRACE_ASSUME_RELEASE)
#define RELEASE DFLE_TRACE_ASSUME_RELEASE
#elif defined(LUA_VERSION_RELEASE_NUM)
#define RELEASE LUA_VERSION_RELEASE_NUM
#else
#define RELEASE (LUA_VERSION_NUM * 100L) /* before 5.4: not one of these */
#endif

static const long checked[] = {
    50404, /* Lua 5.4.4, Debian 12's */
};

int dfle_trace_release_checked(long release, char *why, size_t why_len)
{
    for (size_t i = 0; i < sizeof checked / sizeof checked[0]; i++)
        if (release == checked[i])
            return 1;
    snprintf(why, why_len, "the tracer was not checked against Lua %ld.%ld.%ld",
             release / 10000, release / 100 % 100, release % 100);
    return 0;
}

long dfle_trace_release(void) { return RELEASE; }
