/*
 * main.c - the dfle command: run an experiment written in Lua.
 *
 *   dfle [options] script.lua [args...]
 *
 * Like the `lua` interpreter: the script's arguments are in the global
 * `arg` (arg[0] is the script) and in `...`; the `dfle` module is
 * preloaded as a global.  All real work happens in the library and its
 * binding; this file only parses options, reports errors with a
 * traceback and owns the terminal (progress bar).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <lauxlib.h>
#include <lua.h>
#include <lualib.h>

#include <gsl/gsl_errno.h>

#include "dfle/lua.h"
#include "lua/dfle_lua.h"
#include "progress.h"

#ifndef DFLE_VERSION
#define DFLE_VERSION "unknown"
#endif

static const char *progname = "dfle";

static void usage(FILE *out)
{
    fprintf(out,
            "usage: %s [options] script.lua [args...]\n"
            "Run a dfle experiment script (Lua 5.4 with the dfle module loaded).\n"
            "\n"
            "options:\n"
            "  -q, --quiet    no progress bar\n"
            "  -h, --help     show this help and exit\n"
            "  -v, --version  show the version and exit\n"
            "  --             stop handling options\n"
            "\n"
            "The script sees its arguments in `arg` (arg[0] = script) and `...`.\n"
            "Use `-` as the script name to read it from standard input.\n"
            "Documentation: doc/lua-api.md, doc/tutorial.md\n",
            progname);
}

typedef struct cli {
    int quiet;
    int load_error; /* the script failed to load (no traceback wanted) */
    int script; /* index of the script in argv */
    int argc;
    char **argv;
    dfle_progress_bar bar;
    dfle_lua_progress hooks;
} cli;

/* Message handler: append a traceback, as lua.c does. */
static cli *current_cli;

static int msghandler(lua_State *L)
{
    const char *msg = lua_tostring(L, 1);
    if (current_cli != NULL && current_cli->load_error && msg != NULL)
        return 1;
    if (msg == NULL) {
        if (luaL_callmeta(L, 1, "__tostring") && lua_type(L, -1) == LUA_TSTRING)
            return 1;
        msg = lua_pushfstring(L, "(error object is a %s value)", luaL_typename(L, 1));
    }
    luaL_traceback(L, L, msg, 1);
    return 1;
}

/* Runs protected: everything that can raise happens here. */
static int pmain(lua_State *L)
{
    cli *c = lua_touserdata(L, 1);
    const char *script = c->argv[c->script];
    int nargs = c->argc - c->script - 1;

    luaL_openlibs(L);
    luaL_requiref(L, "dfle", luaopen_dfle, 1);
    lua_pop(L, 1);
    if (!c->quiet && isatty(STDERR_FILENO)) {
        const char *term = getenv("TERM");
        if (term == NULL || strcmp(term, "dumb") != 0) {
            dfle_progress_bar_init(&c->bar, stderr);
            c->hooks.update = dfle_progress_bar_update;
            c->hooks.finish = dfle_progress_bar_finish;
            c->hooks.ud = &c->bar;
            dfle_lua_set_progress(L, &c->hooks);
        }
    }
    /* arg table: arg[-k] = options and program, arg[0] = script. */
    lua_createtable(L, nargs, c->script + 1);
    for (int i = 0; i < c->argc; i++) {
        lua_pushstring(L, c->argv[i]);
        lua_rawseti(L, -2, i - c->script);
    }
    lua_setglobal(L, "arg");

    if (luaL_loadfile(L, strcmp(script, "-") == 0 ? NULL : script) != LUA_OK) {
        /* A missing file or a syntax error: the message says it all; a
         * traceback would only point into this program. */
        c->load_error = 1;
        return lua_error(L);
    }
    luaL_checkstack(L, nargs, "too many arguments to script");
    for (int i = c->script + 1; i < c->argc; i++)
        lua_pushstring(L, c->argv[i]);
    lua_call(L, nargs, 0);
    return 0;
}

int main(int argc, char **argv)
{
    cli c = {0};
    lua_State *L;
    int i, status;

    if (argc > 0 && argv[0] != NULL && argv[0][0] != '\0') {
        const char *slash = strrchr(argv[0], '/');
        progname = slash != NULL ? slash + 1 : argv[0];
    }
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "-q") == 0 || strcmp(a, "--quiet") == 0) {
            c.quiet = 1;
        } else if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            usage(stdout);
            return EXIT_SUCCESS;
        } else if (strcmp(a, "-v") == 0 || strcmp(a, "--version") == 0) {
            printf("dfle %s (%s)\n", DFLE_VERSION, LUA_RELEASE);
            return EXIT_SUCCESS;
        } else if (strcmp(a, "--") == 0) {
            i++;
            break;
        } else if (a[0] == '-' && a[1] != '\0') {
            fprintf(stderr, "%s: unknown option '%s'\n", progname, a);
            usage(stderr);
            return 2;
        } else {
            break;
        }
    }
    if (i >= argc) {
        fprintf(stderr, "%s: no script given\n", progname);
        usage(stderr);
        return 2;
    }
    c.script = i;
    c.argc = argc;
    c.argv = argv;
    current_cli = &c;

    /* GSL aborts on its errors by default; dfle checks every status instead,
     * so an out-of-memory inside GSL becomes an error message, not a crash. */
    gsl_set_error_handler_off();
    L = luaL_newstate();
    if (L == NULL) {
        fprintf(stderr, "%s: cannot create Lua state: not enough memory\n", progname);
        return EXIT_FAILURE;
    }
    lua_pushcfunction(L, msghandler);
    lua_pushcfunction(L, pmain);
    lua_pushlightuserdata(L, &c);
    status = lua_pcall(L, 1, 0, 1);
    if (status != LUA_OK) {
        const char *msg = lua_tostring(L, -1);
        if (c.hooks.finish != NULL)
            c.hooks.finish(c.hooks.ud);
        fprintf(stderr, "%s: %s\n", progname, msg != NULL ? msg : "(error object is not a string)");
    }
    lua_close(L);
    return status == LUA_OK ? EXIT_SUCCESS : EXIT_FAILURE;
}
