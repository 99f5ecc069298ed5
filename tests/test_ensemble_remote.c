/*
 * test_ensemble_remote.c - dfle.ensemble sharing its samples with "other
 * processes" through a remote (dfle/pool.h) given by the host, without
 * MPI: a thread stands in for another rank, opens the evaluator from the
 * key the remote is given (dfle_lua_ensemble_remote, as an MPI rank
 * does: its state replays the script) and takes samples from the task.
 * Checked: the file equals a run alone, the stand-in ran samples and
 * they count; its failure stops the ensemble with its message, rows
 * kept; an interrupt here is passed on as a stop.  (The MPI transport
 * itself is tested by tests/mpi-ensemble.sh; this runs under the
 * sanitizers and valgrind.)
 */
#include "dfle_test.h"

#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <lauxlib.h>
#include <lua.h>
#include <lualib.h>

#include "dfle/lua.h"
#include "dfle/pool.h"
#include "lua/core/dfle_lua.h"
#include "lua/drive/lua_drive.h"
#include "lua/ensemble/lua_ensemble.h"

/* Samples in this process are slowed down (5 ms of CPU) and, through
 * HOLD(), wait until the stand-in has written R.hold_until rows (or has
 * ended): on a loaded machine the stand-in's thread may otherwise not
 * run before this process has done every sample. */
static const char SCRIPT[] =
    "if REMOTE and REMOTE_FAILS then error('the stand-in rank cannot replay') end\n"
    "local ens = dfle.ensemble{\n"
    "  params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3} },\n"
    "  n = 20, seed = 3, out = OUT,\n"
    "  build = function(p)\n"
    "    if not REMOTE then local t = os.clock() + 0.005; while os.clock() < t do end; HOLD() end\n"
    "    return dfle.model{ channel = dfle.channel{ dx = 50 }, U = p.U,\n"
    "                       law = dfle.law.power{ k_df = p.k_df } }\n"
    "  end,\n"
    "  outputs = { \"S_df\", \"A_df\" },\n"
    "}\n"
    "return ens.ran\n";

static char dir[64];

/* The stand-in rank and what the hooks saw. */
static struct standin {
    dfle_lua_host host;  /* the main state's                          */
    dfle_lua_host rhost; /* the stand-in's: its states see REMOTE     */
    dfle_remote remote;
    char out[128];
    int fails;           /* its replay raises                         */
    size_t stop_after;   /* raise the interrupt after this many rows  */
    size_t hold_until;   /* local samples wait for this many of its rows */
    volatile sig_atomic_t interrupt;
    pthread_t tid;
    pthread_mutex_t lock;
    dfle_remote_job job;
    char *key;
    int started, ended, joined, stop, saw_stop, status;
    size_t ran;
    char msg[DFLE_ERROR_MSG_MAX];
} R;

/* HOLD(): returns once the stand-in has written R.hold_until rows or
 * has ended; bounded (30 s), so a broken stand-in fails the test rather
 * than hanging it. */
static int hold(lua_State *L)
{
    (void)L;
    for (int k = 0; k < 30000; k++) {
        int go;
        pthread_mutex_lock(&R.lock);
        go = R.ran >= R.hold_until || R.ended;
        pthread_mutex_unlock(&R.lock);
        if (go)
            return 0;
        nanosleep(&(struct timespec){0, 1000000}, NULL);
    }
    return luaL_error(L, "HOLD: the stand-in wrote no rows in 30 s");
}

/* A state like the main one: libraries, dfle, the globals, the chunk. */
static lua_State *new_state(int remote)
{
    lua_State *L = luaL_newstate();
    assert_non_null(L);
    luaL_openlibs(L);
    luaL_requiref(L, "dfle", luaopen_dfle, 1);
    lua_pop(L, 1);
    lua_pushstring(L, R.out);
    lua_setglobal(L, "OUT");
    lua_pushboolean(L, remote);
    lua_setglobal(L, "REMOTE");
    lua_pushboolean(L, R.fails);
    lua_setglobal(L, "REMOTE_FAILS");
    lua_pushcfunction(L, hold);
    lua_setglobal(L, "HOLD");
    assert_int_equal(luaL_loadbuffer(L, SCRIPT, strlen(SCRIPT), "=script"), LUA_OK);
    return L;
}

static lua_State *open_state(void *ud, int *nargs, dfle_error *err)
{
    (void)ud, (void)err;
    *nargs = 0;
    return new_state(0);
}

static lua_State *open_remote_state(void *ud, int *nargs, dfle_error *err)
{
    (void)ud, (void)err;
    *nargs = 0;
    return new_state(1);
}

static int standin_next(void *ud, size_t *item, double *x)
{
    int stop = 0;
    (void)ud;
    /* Once it has raised the interrupt, the stand-in waits for the stop
     * (bounded: 30 s), as a rank would between its rows: at full speed it
     * could otherwise finish every sample before the interrupt is seen. */
    for (int k = 0; k < 30000; k++) {
        int raised;
        pthread_mutex_lock(&R.lock);
        stop = R.stop;
        raised = R.stop_after > 0 && R.ran >= R.stop_after;
        pthread_mutex_unlock(&R.lock);
        if (stop || !raised)
            break;
        nanosleep(&(struct timespec){0, 1000000}, NULL);
    }
    return !stop && R.job.task->next(R.job.task->ud, item, x);
}

static int standin_done(void *ud, size_t item, const dfle_eval_out *out, dfle_error *err)
{
    int st;
    (void)ud;
    if ((st = R.job.task->done(R.job.task->ud, item, out, err)) != DFLE_OK)
        return st;
    pthread_mutex_lock(&R.lock);
    if (++R.ran == R.stop_after)
        R.interrupt = SIGINT;
    pthread_mutex_unlock(&R.lock);
    return DFLE_OK;
}

/* The stand-in: the evaluator of the key, on a pool of its own (the
 * calling thread, this one, its one worker). */
static void *standin_main(void *arg)
{
    dfle_evaluator *ev = NULL;
    dfle_pool *pool = NULL;
    dfle_pool_opts po;
    dfle_pool_task t = {standin_next, standin_done, NULL, NULL, NULL, NULL, 0};
    dfle_error err = {0}, e2;
    int st;
    (void)arg;
    dfle_pool_opts_default(&po);
    po.ninputs = R.job.ninputs;
    po.noutputs = R.job.noutputs;
    st = dfle_lua_ensemble_remote(&R.rhost, R.key, &ev, &err);
    if (st == DFLE_OK)
        st = dfle_pool_new(ev, &po, &pool, &err);
    if (st == DFLE_OK)
        st = dfle_pool_run(pool, &t, &err);
    if (dfle_pool_free(pool, &e2) != DFLE_OK && st == DFLE_OK) {
        st = e2.code;
        err = e2;
    }
    dfle_lua_ensemble_remote_free(ev);
    pthread_mutex_lock(&R.lock);
    R.status = st;
    snprintf(R.msg, sizeof R.msg, "%s", err.msg);
    R.ended = 1;
    pthread_mutex_unlock(&R.lock);
    return NULL;
}

static int remote_begin(void *ud, const dfle_remote_job *job, dfle_error *err)
{
    (void)ud, (void)err;
    R.job = *job;
    R.key = strdup(job->key);
    assert_int_equal(pthread_create(&R.tid, NULL, standin_main, NULL), 0);
    R.started = 1;
    return 1;
}

static int remote_poll(void *ud, int stop, dfle_error *err)
{
    int ended;
    (void)ud;
    pthread_mutex_lock(&R.lock);
    if (stop)
        R.stop = R.saw_stop = 1;
    ended = R.ended;
    pthread_mutex_unlock(&R.lock);
    if (!ended)
        return 1;
    if (!R.joined) {
        pthread_join(R.tid, NULL);
        R.joined = 1;
    }
    if (R.status != 0)
        return dfle_error_set(err, R.status, "%s", R.msg);
    return 0;
}

static const dfle_remote_ops standin_ops = {DFLE_REMOTE_VERSION, "standin", remote_begin,
                                            remote_poll};

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/dfle-test-remote-XXXXXX");
    if (mkdtemp(dir) == NULL)
        return -1;
    memset(&R, 0, sizeof R);
    pthread_mutex_init(&R.lock, NULL);
    R.remote.ops = &standin_ops;
    R.host.open_state = open_state;
    R.host.remote = &R.remote;
    R.host.workers = 1;
    R.rhost.open_state = open_remote_state;
    R.rhost.workers = 1;
    return 0;
}

static int teardown(void **state)
{
    char cmd[128];
    (void)state;
    if (R.started && !R.joined)
        pthread_join(R.tid, NULL);
    free(R.key);
    pthread_mutex_destroy(&R.lock);
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd) != 0;
}

/* Run the script into `name` in a new main state, with the stand-in
 * (remote) or alone; returns the pcall status, the result or the
 * message in *text (malloc'd). */
static int run(const char *name, int remote, char **text)
{
    lua_State *L;
    int st;
    snprintf(R.out, sizeof R.out, "%s/%s", dir, name);
    L = new_state(0);
    if (remote) {
        dfle_lua_set_host(L, &R.host);
        dfle_lua_set_interrupt(L, &R.interrupt);
    }
    st = lua_pcall(L, 0, 1, 0);
    *text = strdup(lua_tostring(L, -1) != NULL ? lua_tostring(L, -1) : "");
    lua_close(L);
    return st;
}

static char *slurp(const char *name)
{
    char p[160];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    return dfle_test_slurp(p);
}

static int has_line(const char *whole, const char *line, size_t len)
{
    for (const char *at = whole; *at != '\0';) {
        const char *e = strchr(at, '\n');
        size_t l = e != NULL ? (size_t)(e - at) : strlen(at);
        if (l == len && memcmp(at, line, len) == 0)
            return 1;
        at += l + (e != NULL);
    }
    return 0;
}

/* Every line of `part` is a line of `whole`; returns how many rows. */
static size_t rows_within(const char *part, const char *whole)
{
    size_t rows = 0;
    for (const char *line = part; *line != '\0';) {
        const char *e = strchr(line, '\n');
        size_t len = e != NULL ? (size_t)(e - line) : strlen(line);
        assert_true(has_line(whole, line, len));
        rows += line[0] != '#' && strncmp(line, "index,", 6) != 0;
        line += len + (e != NULL);
    }
    return rows;
}

static void same_file_as_a_run_alone(void **state)
{
    char *ref, *got, *text;
    (void)state;
    assert_int_equal(run("ref.csv", 0, &text), LUA_OK);
    free(text);
    R.hold_until = 1;
    assert_int_equal(run("shared.csv", 1, &text), LUA_OK);
    assert_string_equal(text, "20"); /* ens.ran counts the stand-in's rows */
    free(text);
    assert_true(R.ran >= 1);
    ref = slurp("ref.csv");
    got = slurp("shared.csv");
    assert_string_equal(got, ref);
    free(ref);
    free(got);
}

static void a_remote_failure_stops_the_ensemble(void **state)
{
    char *ref, *got, *text;
    (void)state;
    assert_int_equal(run("ref.csv", 0, &text), LUA_OK);
    free(text);
    R.fails = 1;
    assert_int_equal(run("failed.csv", 1, &text), LUA_ERRRUN);
    assert_msg_contains(text, "the stand-in rank cannot replay");
    assert_msg_contains(text, "rows written are kept; run again to resume");
    free(text);
    ref = slurp("ref.csv");
    got = slurp("failed.csv");
    rows_within(got, ref);
    free(ref);
    free(got);
}

static void an_interrupt_stops_the_others(void **state)
{
    char *ref, *got, *text;
    (void)state;
    assert_int_equal(run("ref.csv", 0, &text), LUA_OK);
    free(text);
    R.stop_after = R.hold_until = 3;
    assert_int_equal(run("stopped.csv", 1, &text), LUA_ERRRUN);
    assert_msg_contains(text, "interrupted (SIGINT)");
    free(text);
    assert_true(R.saw_stop);
    ref = slurp("ref.csv");
    got = slurp("stopped.csv");
    assert_true(rows_within(got, ref) >= 3);
    free(ref);
    free(got);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(same_file_as_a_run_alone, setup, teardown),
        cmocka_unit_test_setup_teardown(a_remote_failure_stops_the_ensemble, setup, teardown),
        cmocka_unit_test_setup_teardown(an_interrupt_stops_the_others, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
