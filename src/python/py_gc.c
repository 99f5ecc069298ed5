/*
 * py_gc.c - reference cycles through Lua, made visible to Python's
 * collector.
 *
 * A Python callable handed to Lua (a landscape's U(x, y), a build) is
 * held by Lua; if it refers to the object that uses it, the cycle runs
 * through the Lua state, where Python's collector cannot look.  At the
 * start of every full collection (generation 2, what gc.collect() runs)
 * the bridge walks the Lua state and says which callables only one
 * LuaRef's reference keeps alive (lua_bridge.h:
 * dfle_bridge_owned_callbacks); those LuaRefs' tp_traverse then visit
 * them, once each, as if they held them themselves, and their tp_clear
 * lets the reference go, so that a full Lua collection at the end
 * releases them.  Lua holds one reference to a callable however many
 * handles reach it: one reached by n handles is given n - 1 more for
 * the collection, so that every visit stands for a reference (the
 * collector's counts stay exact), and they go at the end.
 * From start to stop the lock is held and Lua's collector paused, so
 * what the walk said stays true.  A callable the walk cannot vouch for
 * (reachable from Lua, a walk inside a running call) is visited by
 * nobody: it stays, as before.
 */
#include "py_dfle.h"

#include <stdlib.h>
#include <string.h>

Py_ssize_t dfpy_live_callbacks;

typedef struct {
    int ref;
    PyObject *callable; /* borrowed: Lua holds it (its collector paused) */
} owned_cb;

static owned_cb *owned;
static size_t nowned, cap_owned;
/* The references lent for the collection (a callable once per extra owner). */
static PyObject **lent;
static size_t nlent, cap_lent;
static int collecting; /* the lock is held from "start" to "stop" */
static int cleared;    /* references tp_clear let go of meanwhile */

static int grow(void **p, size_t *cap, size_t need, size_t size)
{
    void *q;
    size_t c = *cap ? *cap : 16;
    if (need <= *cap)
        return 0;
    while (c < need)
        c *= 2;
    if ((q = realloc(*p, c * size)) == NULL)
        return -1;
    *p = q;
    *cap = c;
    return 0;
}

static int failed; /* out of memory while listing: nothing is anyone's */

static void on_owned(void *ud, const int *owners, int n, void *callable)
{
    PyObject *cb = callable;
    (void)ud;
    if (failed || grow((void **)&owned, &cap_owned, nowned + (size_t)n, sizeof *owned) < 0 ||
        grow((void **)&lent, &cap_lent, nlent + (size_t)n, sizeof *lent) < 0) {
        failed = 1;
        return;
    }
    for (int i = 0; i < n; i++) {
        owned[nowned].ref = owners[i];
        owned[nowned].callable = cb;
        nowned++;
        if (i > 0) {
            Py_INCREF(cb);
            lent[nlent++] = cb;
        }
    }
}

static int by_ref(const void *a, const void *b)
{
    int x = ((const owned_cb *)a)->ref, y = ((const owned_cb *)b)->ref;
    return (x > y) - (x < y);
}

static void start(int generation)
{
    dfle_bridge *b;
    if (generation < 2 || dfpy_live_callbacks <= 0 || !dfpy_try_enter_idle())
        return;
    b = dfpy_bridge();
    collecting = 1;
    cleared = 0;
    nowned = 0;
    nlent = 0;
    failed = 0;
    dfle_bridge_gc_pause(b, 1);
    if (dfle_bridge_owned_callbacks(b, on_owned, NULL) < 0 || failed)
        nowned = 0; /* what was lent goes back at stop */
    if (nowned > 1)
        qsort(owned, nowned, sizeof *owned, by_ref);
}

static void stop(void)
{
    dfle_bridge *b;
    if (!collecting)
        return;
    b = dfpy_bridge();
    nowned = 0;
    collecting = 0;
    for (size_t i = 0; i < nlent; i++) /* Lua's own reference still holds each */
        Py_DECREF(lent[i]);
    nlent = 0;
    dfle_bridge_gc_pause(b, 0);
    if (cleared > 0)
        dfle_bridge_collect(b); /* the callables go: their cycles are broken */
    cleared = 0;
    dfpy_leave();
}

PyObject *dfpy_gc_phase(PyObject *self, PyObject *args)
{
    const char *phase;
    PyObject *info, *gen;
    long generation = 0;
    (void)self;
    if (!PyArg_ParseTuple(args, "sO", &phase, &info))
        return NULL;
    if (strcmp(phase, "start") == 0) {
        gen = PyDict_Check(info) ? PyDict_GetItemString(info, "generation") : NULL;
        if (gen != NULL)
            generation = PyLong_AsLong(gen);
        if (generation == -1 && PyErr_Occurred())
            return NULL;
        start((int)generation);
    } else if (strcmp(phase, "stop") == 0) {
        stop();
    }
    Py_RETURN_NONE;
}

int dfpy_gc_visit(int ref, visitproc visit, void *arg)
{
    size_t lo = 0, hi = nowned;
    if (!collecting || ref <= 0)
        return 0;
    while (lo < hi) { /* the first pair of ref */
        size_t mid = lo + (hi - lo) / 2;
        if (owned[mid].ref < ref)
            lo = mid + 1;
        else
            hi = mid;
    }
    for (; lo < nowned && owned[lo].ref == ref; lo++)
        Py_VISIT(owned[lo].callable);
    return 0;
}

void dfpy_gc_cleared(void)
{
    if (collecting)
        cleared++;
}
