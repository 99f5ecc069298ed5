/*
 * py_state.c - the Lua state behind the extension, its lock, and calls
 * into it: the GIL released while dfle works, SIGINT stopping a run at
 * its next step (the run keeps its state; Python sees KeyboardInterrupt,
 * never the partial result), warnings issued as dfle.Warning.
 */
#include "py_dfle.h"

#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>

PyObject *dfpy_error, *dfpy_warning, *dfpy_table_type, *dfpy_classes;
unsigned long dfpy_main_thread;

static dfle_bridge *bridge;
static pthread_mutex_t lock;
static pthread_once_t lock_once = PTHREAD_ONCE_INIT;
static int calls; /* calls into Lua in progress (nested in callbacks) */

/* References let go of while the lock was held by another thread. */
static pthread_mutex_t pending_lock = PTHREAD_MUTEX_INITIALIZER;
static int *pending;
static size_t npending, cap_pending;

/* Warnings from Lua, kept until the GIL is held again. */
static pthread_mutex_t warn_lock = PTHREAD_MUTEX_INITIALIZER;
static char **warnings;
static size_t nwarnings, cap_warnings;

static volatile sig_atomic_t interrupted;

static void init_lock(void)
{
    pthread_mutexattr_t a;
    pthread_mutexattr_init(&a);
    pthread_mutexattr_settype(&a, PTHREAD_MUTEX_RECURSIVE);
    pthread_mutex_init(&lock, &a);
    pthread_mutexattr_destroy(&a);
}

static void on_warning(void *ud, const char *msg)
{
    char *copy = strdup(msg);
    (void)ud;
    if (copy == NULL)
        return;
    pthread_mutex_lock(&warn_lock);
    if (nwarnings == cap_warnings) {
        size_t cap = cap_warnings ? 2 * cap_warnings : 8;
        char **p = realloc(warnings, cap * sizeof *p);
        if (p == NULL) {
            pthread_mutex_unlock(&warn_lock);
            free(copy);
            return;
        }
        warnings = p;
        cap_warnings = cap;
    }
    warnings[nwarnings++] = copy;
    pthread_mutex_unlock(&warn_lock);
}

/* The stack level of the user's code: the innermost frames that are the
 * package's own Python (a wrapper such as dfle.ensemble's) are skipped,
 * so a warning names the line that called dfle. */
static int user_level(void)
{
    PyFrameObject *f = PyEval_GetFrame();
    int level = 1;
    Py_XINCREF(f);
    while (f != NULL) {
        PyObject *g = PyFrame_GetGlobals(f), *name;
        PyFrameObject *back;
        int ours = 0;
        name = g != NULL ? PyDict_GetItemString(g, "__name__") : NULL;
        if (name != NULL && PyUnicode_Check(name)) {
            const char *s = PyUnicode_AsUTF8(name);
            if (s == NULL)
                PyErr_Clear();
            else
                ours = strcmp(s, "dfle") == 0 || strncmp(s, "dfle.", 5) == 0;
        }
        Py_XDECREF(g);
        if (!ours)
            break;
        level++;
        back = PyFrame_GetBack(f);
        Py_DECREF(f);
        f = back;
    }
    Py_XDECREF(f);
    return level;
}

int dfpy_flush_warnings(void)
{
    int st = 0;
    for (;;) {
        char *msg = NULL;
        pthread_mutex_lock(&warn_lock);
        if (nwarnings > 0) {
            msg = warnings[0];
            memmove(warnings, warnings + 1, (nwarnings - 1) * sizeof *warnings);
            nwarnings--;
        }
        pthread_mutex_unlock(&warn_lock);
        if (msg == NULL)
            return st;
        if (st == 0 && PyErr_WarnEx(dfpy_warning ? dfpy_warning : PyExc_UserWarning, msg,
                                    user_level()) < 0)
            st = -1; /* an error filter: the rest are dropped */
        free(msg);
    }
}

dfle_bridge *dfpy_bridge(void)
{
    if (bridge == NULL) {
        const char *why = NULL;
        pthread_once(&lock_once, init_lock);
        bridge = dfle_bridge_new(&why);
        if (bridge == NULL) {
            PyErr_Format(PyExc_RuntimeError, "dfle: %s", why ? why : "no Lua state");
            return NULL;
        }
        dfle_bridge_set_warn(bridge, on_warning, NULL);
        dfle_bridge_set_interrupt(bridge, &interrupted);
    }
    return bridge;
}

/* Let go of ref (the lock held); unhold what a view held first. */
static void release_now(int ref, int held)
{
    if (held) {
        int top = dfle_bridge_top(bridge);
        if (dfle_bridge_check(bridge, 4)) {
            dfle_bridge_push_ref(bridge, ref);
            dfle_bridge_unhold(bridge, top + 1);
        }
        dfle_bridge_settop(bridge, top);
    }
    dfle_bridge_unref(bridge, ref);
}

static void drain_pending(void)
{
    pthread_mutex_lock(&pending_lock);
    for (size_t i = 0; i < npending; i++) /* negative: a held one */
        release_now(pending[i] < 0 ? -pending[i] : pending[i], pending[i] < 0);
    npending = 0;
    pthread_mutex_unlock(&pending_lock);
}

void dfpy_enter(void)
{
    pthread_once(&lock_once, init_lock);
    if (pthread_mutex_trylock(&lock) != 0) {
        Py_BEGIN_ALLOW_THREADS
        pthread_mutex_lock(&lock);
        Py_END_ALLOW_THREADS
    }
    if (bridge != NULL)
        drain_pending();
}

void dfpy_leave(void) { pthread_mutex_unlock(&lock); }

int dfpy_try_enter_idle(void)
{
    pthread_once(&lock_once, init_lock);
    if (bridge == NULL || pthread_mutex_trylock(&lock) != 0)
        return 0;
    if (calls > 0) { /* this thread, inside a call: Lua frames are running */
        pthread_mutex_unlock(&lock);
        return 0;
    }
    drain_pending();
    return 1;
}

void dfpy_release_ref(int ref, int held)
{
    if (bridge == NULL || ref <= 0) /* 0: a handle never given a value */
        return;
    pthread_once(&lock_once, init_lock);
    if (pthread_mutex_trylock(&lock) == 0) {
        release_now(ref, held);
        pthread_mutex_unlock(&lock);
        return;
    }
    pthread_mutex_lock(&pending_lock);
    if (npending == cap_pending) {
        size_t cap = cap_pending ? 2 * cap_pending : 64;
        int *p = realloc(pending, cap * sizeof *p);
        if (p == NULL) { /* kept for good: a small leak, not a crash */
            pthread_mutex_unlock(&pending_lock);
            return;
        }
        pending = p;
        cap_pending = cap;
    }
    pending[npending++] = held ? -ref : ref;
    pthread_mutex_unlock(&pending_lock);
}

static void on_sigint(int sig) { interrupted = sig; }

int dfpy_raise_top(dfle_bridge *b)
{
    size_t len = 0;
    const char *msg = dfle_bridge_to_string(b, -1, &len);
    PyObject *cause_t, *cause_v, *cause_tb, *text, *exc = NULL;

    /* A Python callback's own exception, if it caused this one. */
    PyErr_Fetch(&cause_t, &cause_v, &cause_tb);
    text = PyUnicode_DecodeUTF8(msg ? msg : "dfle: error", msg ? (Py_ssize_t)len : 11, "replace");
    if (text != NULL) {
        exc = PyObject_CallOneArg(dfpy_error ? dfpy_error : PyExc_RuntimeError, text);
        Py_DECREF(text);
    }
    if (exc != NULL) {
        if (cause_v != NULL) {
            PyErr_NormalizeException(&cause_t, &cause_v, &cause_tb);
            if (cause_tb != NULL)
                PyException_SetTraceback(cause_v, cause_tb);
            PyException_SetCause(exc, cause_v); /* steals cause_v */
            cause_v = NULL;
        }
        PyErr_SetObject((PyObject *)Py_TYPE(exc), exc);
        Py_DECREF(exc);
    }
    Py_XDECREF(cause_t);
    Py_XDECREF(cause_v);
    Py_XDECREF(cause_tb);
    dfle_bridge_settop(b, dfle_bridge_top(b) - 1);
    return -1;
}

/* The Python exception a callback raised during the current call, kept
 * as the cause of the error Lua reports (py_ref.c sets it). */
static PyObject *cb_type, *cb_value, *cb_tb;

void dfpy_keep_callback_error(void);
void dfpy_keep_callback_error(void)
{
    Py_XDECREF(cb_type);
    Py_XDECREF(cb_value);
    Py_XDECREF(cb_tb);
    PyErr_Fetch(&cb_type, &cb_value, &cb_tb);
}

static void drop_callback_error(void)
{
    Py_CLEAR(cb_type);
    Py_CLEAR(cb_value);
    Py_CLEAR(cb_tb);
}

int dfpy_call(dfle_bridge *b, int nargs, int *nres)
{
    struct sigaction ours, old;
    int catch_sigint = calls == 0 && PyThread_get_thread_ident() == dfpy_main_thread;
    int st;

    if (calls == 0)
        drop_callback_error();
    if (catch_sigint) {
        memset(&ours, 0, sizeof ours);
        ours.sa_handler = on_sigint;
        sigemptyset(&ours.sa_mask);
        if (sigaction(SIGINT, &ours, &old) != 0)
            catch_sigint = 0;
    }
    calls++;
    Py_BEGIN_ALLOW_THREADS
    st = dfle_bridge_call(b, nargs, nres);
    Py_END_ALLOW_THREADS
    calls--;
    if (catch_sigint)
        sigaction(SIGINT, &old, NULL);
    if (calls == 0 && interrupted) {
        /* The run stopped at its next step and kept its state; what it
         * returned is a partial result, which Python never sees. */
        interrupted = 0;
        if (st == 0)
            dfle_bridge_settop(b, dfle_bridge_top(b) - *nres);
        else
            dfle_bridge_settop(b, dfle_bridge_top(b) - 1);
        drop_callback_error();
        PyErr_SetNone(PyExc_KeyboardInterrupt);
        return -1;
    }
    if (st != 0) {
        if (cb_value != NULL) {
            PyErr_Restore(cb_type, cb_value, cb_tb);
            cb_type = cb_value = cb_tb = NULL;
        }
        return dfpy_raise_top(b);
    }
    if (calls == 0)
        drop_callback_error(); /* an error Lua caught (a failed sample) */
    return 0;
}
