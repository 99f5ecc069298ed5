/*
 * py_dfle.h - internals of the Python extension dfle._dfle (not installed).
 *
 * The extension drives the Lua binding through lua/bridge/lua_bridge.h:
 * one Lua state per process holds every dfle object, and each Python
 * object of type dfle.LuaRef holds a reference to one value there.
 *
 *  - py_state.c: the state, its lock, calls into it (the GIL released,
 *    SIGINT caught, warnings and callback errors carried back);
 *  - py_convert.c: values between Python and Lua;
 *  - py_ref.c: the LuaRef type (objects, functions, tables with methods);
 *  - py_field.c: fields as numpy arrays (views of the object's memory);
 *  - py_parallel.c: ensembles and inversions on worker states;
 *  - py_gc.c: cycles through Lua made visible to Python's collector;
 *  - py_module.c: the module.
 *
 * Locking: the Lua state is used by one thread at a time, under a
 * recursive lock (callbacks into Python may call dfle again).  A thread
 * never waits for the lock while it holds the GIL, and a callback takes
 * the GIL only while the lock is held, so the two cannot deadlock.
 */
#ifndef DFLE_PY_DFLE_H
#define DFLE_PY_DFLE_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include "lua/bridge/lua_bridge.h"

/* A value in the Lua state: an object, a function (with the object it
 * is a method of), or a table kept as it is (a result with methods or
 * strict fields). */
typedef struct {
    PyObject_HEAD
    int ref;          /* registry reference; LUA_NOREF-like -1 when none */
    int kind;         /* DFLE_BRIDGE_OBJECT, _FUNCTION, _TABLE, ...      */
    PyObject *self;   /* a method's object (a LuaRef), or NULL           */
    PyObject *weak;   /* weak references                                 */
    int held;         /* holds the object for views of its memory        */
} dfpy_ref;

extern PyTypeObject dfpy_ref_type;

/* --- py_state.c --- */
/* The state, created on first use; NULL with an exception set. */
dfle_bridge *dfpy_bridge(void);
/* Take / give back the lock (the GIL held on entry and exit). */
void dfpy_enter(void);
void dfpy_leave(void);
/* Take the lock only if it is free and no call into Lua is running on
 * this thread (the collector's walk); 1 when taken. */
int dfpy_try_enter_idle(void);
/* Let go of a reference from anywhere the GIL is held (a deallocator):
 * at once if the lock is free, else by the next holder; held: the
 * object was held for views (dfle_bridge_hold), unhold it first. */
void dfpy_release_ref(int ref, int held);
/* Call the function pushed at top - nargs with the nargs values above
 * it, the GIL released; the results replace them (count in *nres).
 * Returns 0, or -1 with a Python exception set (dfle.Error with the
 * message, KeyboardInterrupt after SIGINT). */
int dfpy_call(dfle_bridge *b, int nargs, int *nres);
/* Raise dfle.Error(message on top of the stack), popping it; returns -1. */
int dfpy_raise_top(dfle_bridge *b);
/* Warnings the last calls left, issued as dfle.Warning; -1 if one was
 * turned into an exception. */
int dfpy_flush_warnings(void);
/* The classes the Python layer supplies (dfle.Error, dfle.Warning, the
 * result dict, the classes of object types by Lua type name). */
extern PyObject *dfpy_error, *dfpy_warning, *dfpy_table_type, *dfpy_classes;
extern unsigned long dfpy_main_thread;

/* --- py_convert.c --- */
/* Push a Python value; -1 with an exception set if it cannot go. */
int dfpy_push(dfle_bridge *b, PyObject *v, int depth);
/* kwargs as one table of named parameters. */
int dfpy_push_kwargs(dfle_bridge *b, PyObject *kwargs);
/* The value at idx as Python (new reference), or NULL. */
PyObject *dfpy_to_python(dfle_bridge *b, int idx, int depth);
/* The results at first..first+n-1: None, the value, or a tuple; a
 * (nil, message) pair raises dfle.Error(message). */
PyObject *dfpy_results(dfle_bridge *b, int first, int n);

/* --- py_ref.c --- */
/* A new LuaRef of the value at idx (not popped), of the class its Lua
 * type name is registered with; self for a method. */
PyObject *dfpy_ref_new(dfle_bridge *b, int idx, PyObject *self);
/* Call a LuaRef function: positional args, then kwargs as one table. */
PyObject *dfpy_ref_call(PyObject *fn, PyObject *args, PyObject *kwargs);
/* Issue the warnings a call left, keeping an exception it raised. */
PyObject *dfpy_finish(PyObject *res);

/* --- py_gc.c --- */
/* _dfle._gc(phase, info): gc.callbacks' hook; the references Lua holds
 * to Python callables, visited by their owning LuaRef's tp_traverse. */
PyObject *dfpy_gc_phase(PyObject *self, PyObject *args);
int dfpy_gc_visit(int ref, visitproc visit, void *arg);
/* A LuaRef's reference was let go of by tp_clear. */
void dfpy_gc_cleared(void);
/* Python callables pushed to Lua and not yet released. */
extern Py_ssize_t dfpy_live_callbacks;

/* --- py_parallel.c --- */
/* _dfle.parallel(fn, script, spec): fn(spec) with worker states. */
PyObject *dfpy_parallel(PyObject *self, PyObject *args);

/* --- py_field.c --- */
/* o._field(name): the field as a numpy array, or None when the object
 * or the name is not one read this way (the caller asks get()). */
PyObject *dfpy_ref_field(PyObject *o, PyObject *name);
/* _dfle.attrs(obj): (attributes, crs) as the object's NetCDF files say, or None. */
PyObject *dfpy_attrs(PyObject *self, PyObject *o);

#endif
