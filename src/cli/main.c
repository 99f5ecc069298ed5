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
/* realpath (XSI) for the documentation path in --help. */
#define _XOPEN_SOURCE 700

#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <lauxlib.h>
#include <lua.h>
#include <lualib.h>

#include <gsl/gsl_errno.h>

#include "dfle/lua.h"
#include "lua/core/dfle_lua.h"
#include "lua/drive/lua_drive.h"       /* ensembles, inversions: -j, --shard, worker states */
#include "cli/progress.h"
#ifdef DFLE_MPI /* the MPI build, `make mpi` (doc/ensembles.md) */
#include "lua/ensemble/lua_ensemble.h" /* the evaluator other ranks open from a key */
#include "mpi/dfle_mpi.h"
#endif

#ifndef DFLE_VERSION
#define DFLE_VERSION "unknown"
#endif

static const char *progname = "dfle";

/* The signal that interrupted the script (SIGINT, SIGTERM), or 0.  The
 * library only reads it: a run in progress stops at its next step and
 * keeps its state, nothing new starts, and the script's own code after
 * the run still writes what it has.  A second signal ends the process
 * at once (the handler restores the default), as users expect of a
 * second Ctrl-C; ensemble rows are whole lines either way. */
static volatile sig_atomic_t interrupted;

#ifdef DFLE_MPI
/* dfle-mpi's rank 0 says at once that it stops and what is kept: mpirun
 * sends SIGTERM to every rank when one has died, and SIGKILL a moment
 * later, often before the script's own last line can be printed. */
static char stop_line[2][320]; /* for SIGINT, SIGTERM; empty: say nothing */
#endif

static void on_interrupt(int sig)
{
    interrupted = sig;
    signal(sig, SIG_DFL);
#ifdef DFLE_MPI
    {
        const char *line = stop_line[sig == SIGTERM];
        ssize_t w = write(STDERR_FILENO, line, strlen(line));
        (void)w;
    }
#endif
}

static void catch_interrupts(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_interrupt;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}

/* Where the documentation is: beside an installed command
 * (PREFIX/bin/dfle -> PREFIX/share/doc/dfle) or in the source tree of a
 * built one (build/dfle -> doc), found from the command's own path so
 * that a staged (DESTDIR) or moved install points to its own copy. */
static const char *doc_dir(char *buf, size_t cap)
{
    static const char *const rel[] = {"/../share/doc/dfle", "/../doc"};
    char exe[4096], probe[4200];
    ssize_t len = readlink("/proc/self/exe", exe, sizeof exe - 1);
    char *slash;
    if (len <= 0)
        return NULL;
    exe[len] = '\0';
    if ((slash = strrchr(exe, '/')) == NULL)
        return NULL;
    *slash = '\0';
    for (size_t k = 0; k < sizeof rel / sizeof rel[0]; k++) {
        snprintf(probe, sizeof probe, "%s%s/lua-api.md", exe, rel[k]);
        if (access(probe, R_OK) == 0) {
            snprintf(probe, sizeof probe, "%s%s", exe, rel[k]);
            if (realpath(probe, buf) != NULL && strlen(buf) < cap)
                return buf;
        }
    }
    return NULL;
}

static void usage(FILE *out)
{
    char dir[PATH_MAX];
    const char *docs = doc_dir(dir, sizeof dir);
    fprintf(out,
            "usage: %s [options] script.lua [args...]\n"
            "Run a dfle experiment script (Lua 5.4 with the dfle module loaded).\n"
            "\n"
            "options:\n"
            "  -q, --quiet    no progress bar, no notes (warnings and errors still show)\n"
            "  --verbose      also say what each run did and each file written\n"
#ifdef DFLE_MPI
            "  -j N           dfle.ensemble workers in each rank (default: the rank's\n"
            "                 share of its node's cores)\n"
#else
            "  -j N           dfle.ensemble workers (default: all cores)\n"
#endif
            "  --shard i/n    run shard i of n of each dfle.ensemble (1 <= i <= n);\n"
            "                 --shard slurm takes i, n from SLURM_ARRAY_TASK_*\n"
#ifdef DFLE_MPI
            "  --rank-timeout S  take a rank silent for S seconds as lost (default 60)\n"
#endif
            "  -h, --help     show this help and exit\n"
            "  -v, --version  show the version and exit\n"
            "  --             stop handling options\n"
            "\n"
            "The script sees its arguments in `arg` (arg[0] = script) and `...`.\n"
            "Use `-` as the script name to read it from standard input.\n"
            "\n"
            "Documentation: man dfle; ",
            progname);
    if (docs != NULL)
        fprintf(out, "%s/tutorial.md (start here), %s/lua-api.md (reference)\n", docs, docs);
    else
        fputs("tutorial.md and lua-api.md in doc/ of the dfle sources\n", out);
}

typedef struct cli {
    int quiet;
    int verbosity; /* notes shown: 0 with -q, DFLE_LUA_NOTE, DFLE_LUA_DETAIL with --verbose */
    int warn_off;  /* warn("@off") */
    int warn_cont; /* a warning is being continued (lua_warning tocont) */
    int load_error; /* the script failed to load (no traceback wanted) */
    int usage_error; /* dfle.args refused the script's arguments (exit 2) */
    int script; /* index of the script in argv */
    int argc;
    char **argv;
    dfle_progress_bar bar;
    dfle_lua_progress hooks;
    dfle_lua_host ens;          /* --- ensembles (doc/ensembles.md) --- */
    double rank_timeout;        /* dfle-mpi: --rank-timeout [s]          */
    double ens_last_draw;
    int ens_drawn;
} cli;

/* Message handler: append a traceback, as lua.c does. */
static cli *current_cli;

static int msghandler(lua_State *L)
{
    const char *msg = lua_tostring(L, 1);
    if (current_cli != NULL && current_cli->load_error && msg != NULL)
        return 1;
    if (current_cli != NULL && dfle_lua_is_usage_error(L, msg)) {
        current_cli->usage_error = 1; /* like dfle's own options: no traceback */
        return 1;
    }
    if (msg == NULL) {
        if (luaL_callmeta(L, 1, "__tostring") && lua_type(L, -1) == LUA_TSTRING)
            return 1;
        msg = lua_pushfstring(L, "(error object is a %s value)", luaL_typename(L, 1));
    }
    luaL_traceback(L, L, msg, 1);
    return 1;
}

/* Lua warnings (warn(), and dfle's plausibility warnings) go to stderr as
 * "dfle: warning: ...", on by default: they flag values that run but are
 * almost surely mistakes.  warn("@off") and warn("@on") switch them. */
static void on_warning(void *ud, const char *msg, int tocont)
{
    cli *c = ud;
    if (!c->warn_cont && !tocont && msg[0] == '@') {
        if (strcmp(msg, "@off") == 0)
            c->warn_off = 1;
        else if (strcmp(msg, "@on") == 0)
            c->warn_off = 0;
        return;
    }
    if (!c->warn_off) {
        if (!c->warn_cont) {
            if (c->bar.drawn)
                fputs("\r\033[K", stderr); /* not on top of the progress bar */
            fprintf(stderr, "%s: warning: ", progname);
        }
        fputs(msg, stderr);
        if (!tocont)
            fputc('\n', stderr);
        fflush(stderr);
    }
    c->warn_cont = tocont;
}

/* Ensemble workers replay the script: their warnings would repeat the
 * main state's once per worker. */
static void drop_warning(void *ud, const char *msg, int tocont)
{
    (void)ud;
    (void)msg;
    (void)tocont;
}

/* --- ensembles (doc/ensembles.md): worker states, -j, --shard, the
 * ensemble progress line.  A worker's state is made like the main one
 * (libraries, dfle, `arg`), with the script loaded and its arguments
 * pushed; dfle.ensemble runs it up to its own call. */
static void set_arg_table(lua_State *L, const cli *c)
{
    lua_createtable(L, c->argc - c->script - 1, c->script + 1);
    for (int i = 0; i < c->argc; i++) {
        lua_pushstring(L, c->argv[i]);
        lua_rawseti(L, -2, i - c->script);
    }
    lua_setglobal(L, "arg");
}

static int open_worker_p(lua_State *L)
{
    const cli *c = lua_touserdata(L, 1);
    const char *script = c->argv[c->script];
    luaL_openlibs(L);
    luaL_requiref(L, "dfle", luaopen_dfle, 1);
    lua_pop(L, 1);
    set_arg_table(L, c);
    if (strcmp(script, "-") == 0)
        return luaL_error(L, "a script read from standard input cannot be rerun by ensemble "
                             "workers; save it to a file or use -j 1");
    if (luaL_loadfile(L, script) != LUA_OK)
        return lua_error(L);
    luaL_checkstack(L, c->argc, "too many arguments to script");
    for (int i = c->script + 1; i < c->argc; i++)
        lua_pushstring(L, c->argv[i]);
    return c->argc - c->script;
}

static lua_State *open_worker(void *ud, int *nargs, dfle_error *err)
{
    lua_State *L = luaL_newstate();
    int n;
    if (L == NULL) {
        dfle_error_set(err, DFLE_ENOMEM, "cannot create a worker's Lua state: not enough memory");
        return NULL;
    }
    lua_setwarnf(L, drop_warning, NULL);
    lua_pushcfunction(L, open_worker_p);
    lua_pushlightuserdata(L, ud);
    if (lua_pcall(L, 1, LUA_MULTRET, 0) != LUA_OK) {
        dfle_error_set(err, DFLE_ECALLBACK, "%s",
                       lua_tostring(L, -1) ? lua_tostring(L, -1) : "worker failed");
        lua_close(L);
        return NULL;
    }
    n = lua_gettop(L);
    *nargs = n - 1; /* chunk, then the script's arguments */
    return L;
}

static double mono_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void ens_progress(void *ud, size_t done, size_t total, size_t failed, double elapsed)
{
    cli *c = ud;
    double t = mono_now(), rate = elapsed > 0 ? (double)done / elapsed : 0;
    double f = total > 0 ? (double)done / (double)total : 1;
    int filled = (int)(f * 24 + 0.5);
    if (c->ens_drawn && t - c->ens_last_draw < 0.1 && done < total)
        return;
    c->ens_last_draw = t;
    fputs("\r[", stderr);
    for (int i = 0; i < 24; i++)
        fputc(i < filled ? '#' : '.', stderr);
    fprintf(stderr, "] %zu/%zu runs  %.1f runs/s", done, total, rate);
    if (failed > 0)
        fprintf(stderr, "  %zu failed", failed);
    if (done > 0 && done < total)
        fprintf(stderr, "  ETA %.0f s", (double)(total - done) / rate);
    fputs("\033[K", stderr);
    fflush(stderr);
    c->ens_drawn = 1;
}

static void ens_progress_end(void *ud)
{
    cli *c = ud;
    if (c->ens_drawn) {
        fputs("\r\033[K", stderr);
        fflush(stderr);
    }
    c->ens_drawn = 0;
}


/* "i/n" with 1 <= i <= n, or "slurm": SLURM_ARRAY_TASK_ID (from
 * SLURM_ARRAY_TASK_MIN) of SLURM_ARRAY_TASK_COUNT. */
static int parse_shard(const char *s, size_t *i, size_t *n)
{
    char *end;
    unsigned long a, b;
    if (strcmp(s, "slurm") == 0) {
        const char *id = getenv("SLURM_ARRAY_TASK_ID"), *cnt = getenv("SLURM_ARRAY_TASK_COUNT");
        const char *min = getenv("SLURM_ARRAY_TASK_MIN");
        unsigned long m = min != NULL ? strtoul(min, NULL, 10) : 0;
        if (id == NULL || cnt == NULL)
            return 0;
        a = strtoul(id, NULL, 10) - m + 1;
        b = strtoul(cnt, NULL, 10);
    } else {
        a = strtoul(s, &end, 10);
        if (end == s || *end != '/')
            return 0;
        s = end + 1;
        b = strtoul(s, &end, 10);
        if (end == s || *end != '\0')
            return 0;
    }
    if (b < 1 || a < 1 || a > b)
        return 0;
    *i = a;
    *n = b;
    return 1;
}
/* --- end ensembles --- */

/* The run's hooks: the bar when one is drawn, and notes on stderr. */
static int cli_update(void *ud, const dfle_run_status *st)
{
    return dfle_progress_bar_update(&((cli *)ud)->bar, st);
}

static void cli_finish(void *ud)
{
    dfle_progress_bar_finish(&((cli *)ud)->bar);
}

static void cli_note(void *ud, int level, const char *line)
{
    cli *c = ud;
    if (level > c->verbosity)
        return;
    if (c->bar.drawn || c->ens_drawn)
        fputs("\r\033[K", stderr); /* the bar is drawn again at its next update */
    fprintf(stderr, "%s: %s\n", progname, line);
    fflush(stderr);
}

#ifdef DFLE_MPI
/* A rank > 0's evaluator of rank 0's key: the Lua binding's, whose
 * workers replay the script (rank 0 ran it) up to the call. */
static int mpi_make_evaluator(void *ud, const char *key, dfle_evaluator **ev, dfle_error *err)
{
    cli *c = ud;
    return dfle_lua_ensemble_remote(&c->ens, key, ev, err);
}

static void mpi_free_evaluator(void *ud, dfle_evaluator *ev)
{
    (void)ud;
    dfle_lua_ensemble_remote_free(ev);
}

/* dfle-mpi's lines: warnings (a rank lost) always shown, like Lua's;
 * notes (what each rank ran) with --verbose. */
static void mpi_tell(void *ud, int warning, const char *line)
{
    cli *c = ud;
    if (!warning) {
        cli_note(c, DFLE_LUA_DETAIL, line);
        return;
    }
    if (c->bar.drawn || c->ens_drawn)
        fputs("\r\033[K", stderr);
    fprintf(stderr, "%s: warning: %s\n", progname, line);
    fflush(stderr);
}
#endif

/* Runs protected: everything that can raise happens here. */
static int pmain(lua_State *L)
{
    cli *c = lua_touserdata(L, 1);
    const char *script = c->argv[c->script];
    int nargs = c->argc - c->script - 1;

    luaL_openlibs(L);
    luaL_requiref(L, "dfle", luaopen_dfle, 1);
    lua_pop(L, 1);
    dfle_progress_bar_init(&c->bar, stderr);
    c->hooks.note = cli_note;
    c->hooks.ud = c;
    dfle_lua_set_progress(L, &c->hooks);
    if (!c->quiet && isatty(STDERR_FILENO)) {
        const char *term = getenv("TERM");
        if (term == NULL || strcmp(term, "dumb") != 0) {
            c->hooks.update = cli_update;
            c->hooks.finish = cli_finish;
            c->ens.progress = ens_progress; /* ensembles */
            c->ens.progress_end = ens_progress_end;
        }
    }
    c->ens.open_state = open_worker; /* ensembles */
    c->ens.ud = c;
    dfle_lua_set_host(L, &c->ens);
    dfle_lua_set_interrupt(L, &interrupted);
    /* arg table: arg[-k] = options and program, arg[0] = script. */
    set_arg_table(L, c);
    dfle_lua_set_command(L, c->argv, c->argc, c->script); /* for records */

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
    c.verbosity = DFLE_LUA_NOTE;
    lua_State *L;
    int i, status;

    /* Past a file-size limit (ulimit -f) a write should fail with EFBIG,
     * which dfle reports, not end the process without a word. */
    signal(SIGXFSZ, SIG_IGN);
    if (argc > 0 && argv[0] != NULL && argv[0][0] != '\0') {
        const char *slash = strrchr(argv[0], '/');
        progname = slash != NULL ? slash + 1 : argv[0];
    }
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "-q") == 0 || strcmp(a, "--quiet") == 0) {
            c.quiet = 1;
            c.verbosity = 0;
        } else if (strcmp(a, "--verbose") == 0) {
            c.quiet = 0;
            c.verbosity = DFLE_LUA_DETAIL;
        } else if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            usage(stdout);
            return EXIT_SUCCESS;
        } else if (strcmp(a, "-v") == 0 || strcmp(a, "--version") == 0) {
            printf("dfle %s (%s)\n", DFLE_VERSION, LUA_RELEASE);
            return EXIT_SUCCESS;
        } else if (strncmp(a, "-j", 2) == 0) { /* ensembles: -j N or -jN */
            const char *v = a[2] != '\0' ? a + 2 : (i + 1 < argc ? argv[++i] : "");
            char *end;
            long j = strtol(v, &end, 10);
            if (end == v || *end != '\0' || j < 1 || j > 4096) {
                fprintf(stderr, "%s: -j needs a number of workers >= 1 (got '%s')\n", progname, v);
                return 2;
            }
            c.ens.workers = (int)j;
        } else if (strcmp(a, "--shard") == 0) { /* ensembles */
            const char *v = i + 1 < argc ? argv[++i] : "";
            if (!parse_shard(v, &c.ens.shard_i, &c.ens.shard_n)) {
                fprintf(stderr, "%s: --shard needs i/n with 1 <= i <= n, or 'slurm' with "
                                "SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT set (got '%s')\n",
                        progname, v);
                return 2;
            }
#ifdef DFLE_MPI
        } else if (strcmp(a, "--rank-timeout") == 0) {
            const char *v = i + 1 < argc ? argv[++i] : "";
            char *end;
            double t = strtod(v, &end);
            if (end == v || *end != '\0' || !(t >= 1 && t <= 1e6)) {
                fprintf(stderr, "%s: --rank-timeout needs a number of seconds, 1 to 1e6 (got '%s')\n",
                        progname, v);
                return 2;
            }
            c.rank_timeout = t;
#endif
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

#ifdef DFLE_MPI /* ranks > 0 serve ensembles; rank 0 runs the script */
    {
        dfle_error err = {0};
        int size = 1, rank = 0, cores = 0;
        if (dfle_mpi_init(c.rank_timeout, &rank, &size, &cores, &err) != DFLE_OK) {
            if (rank == 0)
                fprintf(stderr, "%s: %s\n", progname, err.msg);
            dfle_mpi_finish(0);
            return EXIT_FAILURE;
        }
        c.ens.open_state = open_worker;
        c.ens.ud = &c;
        c.ens.cores = cores; /* this rank's share of its node */
        if (rank > 0) {
            dfle_mpi_worker w = {mpi_make_evaluator, mpi_free_evaluator, &c, c.ens.workers,
                                 cores};
            gsl_set_error_handler_off();
            status = dfle_mpi_worker_loop(&w);
            dfle_mpi_finish(0);
            return status;
        }
        if (size > 1 && dfle_mpi_serve(&c.ens.remote, mpi_tell, &c, &err) != DFLE_OK) {
            fprintf(stderr, "%s: %s\n", progname, err.msg);
            dfle_mpi_finish(0);
            return EXIT_FAILURE;
        }
        for (int k = 0; k < 2 && size > 1; k++)
            snprintf(stop_line[k], sizeof stop_line[k],
                     "%s: rank 0 got %s (mpirun sends it to every rank when one has died, "
                     "and on Ctrl-C): stopping; the ensemble rows written so far are kept, "
                     "whole, and running the script again resumes\n",
                     progname, k ? "SIGTERM" : "SIGINT");
    }
#endif
    /* GSL aborts on its errors by default; dfle checks every status instead,
     * so an out-of-memory inside GSL becomes an error message, not a crash. */
    gsl_set_error_handler_off();
    L = luaL_newstate();
    if (L == NULL) {
        fprintf(stderr, "%s: cannot create Lua state: not enough memory\n", progname);
#ifdef DFLE_MPI
        dfle_mpi_finish(0);
#endif
        return EXIT_FAILURE;
    }
    lua_setwarnf(L, on_warning, &c);
    catch_interrupts();
    lua_pushcfunction(L, msghandler);
    lua_pushcfunction(L, pmain);
    lua_pushlightuserdata(L, &c);
    status = lua_pcall(L, 1, 0, 1);
    if (c.hooks.finish != NULL)
        c.hooks.finish(c.hooks.ud); /* no bar left on the line */
    if (interrupted) {
        /* One line: what stopped, and what was kept.  The error that
         * ended the script, if any, is the interruption itself. */
        const char *note = dfle_lua_interrupt_note(L);
        const char *msg = status != LUA_OK ? lua_tostring(L, -1) : NULL;
        if (msg != NULL && strstr(msg, "interrupted (") == NULL)
            fprintf(stderr, "%s: %s\n", progname, msg); /* another error, after it */
        fprintf(stderr, "%s: interrupted by %s: %s; files written before are complete (dfle "
                        "writes whole files or none)\n",
                progname, interrupted == SIGTERM ? "SIGTERM" : "SIGINT",
                note != NULL ? note : "nothing was running");
        status = 128 + interrupted;
    } else if (status != LUA_OK) {
        const char *msg = lua_tostring(L, -1);
        fprintf(stderr, "%s: %s\n", progname, msg != NULL ? msg : "(error object is not a string)");
        status = c.usage_error ? 2 : EXIT_FAILURE;
    } else {
        status = EXIT_SUCCESS;
    }
    lua_close(L);
#ifdef DFLE_MPI
    dfle_mpi_finish(interrupted != 0);
#endif
    return status;
}
