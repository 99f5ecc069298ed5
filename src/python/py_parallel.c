/*
 * py_parallel.c - _dfle.parallel(fn, script, spec): a dfle.ensemble or
 * dfle.invert call on the driver's worker threads, each with a Lua state
 * of its own that runs `script`, the same call written as Lua source
 * (python/dfle/_parallel.py writes it when the spec holds no Python
 * callable).  The workers are set up and the call made under one hold
 * of the lock, so no other thread's call can take them.
 */
#include "py_dfle.h"

PyObject *dfpy_parallel(PyObject *self, PyObject *args)
{
    PyObject *fn, *spec, *res, *call_args;
    const char *script;
    Py_ssize_t len;
    dfle_bridge *b;
    (void)self;
    if (!PyArg_ParseTuple(args, "O!s#O!", &dfpy_ref_type, &fn, &script, &len, &PyDict_Type, &spec))
        return NULL;
    if ((b = dfpy_bridge()) == NULL)
        return NULL;
    call_args = PyTuple_Pack(1, spec);
    if (call_args == NULL)
        return NULL;
    dfpy_enter();
    if (dfle_bridge_begin_parallel(b, script, (size_t)len) < 0) {
        dfpy_leave();
        Py_DECREF(call_args);
        return PyErr_NoMemory();
    }
    res = dfpy_ref_call(fn, call_args, NULL);
    dfle_bridge_end_parallel(b);
    dfpy_leave();
    Py_DECREF(call_args);
    return res;
}
