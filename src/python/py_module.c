/*
 * py_module.c - dfle._dfle, the extension module under the Python
 * package dfle (python/dfle/__init__.py gives it its Pythonic face).
 */
#include "py_dfle.h"

#include "dfle/record.h"

#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#define PY_ARRAY_UNIQUE_SYMBOL dfpy_ARRAY_API
#include <numpy/arrayobject.h>

/* _dfle.module(): the dfle Lua module table, as a LuaRef. */
static PyObject *mod_module(PyObject *self, PyObject *unused)
{
    dfle_bridge *b = dfpy_bridge();
    PyObject *res;
    int top;
    (void)self;
    (void)unused;
    if (b == NULL)
        return NULL;
    dfpy_enter();
    top = dfle_bridge_top(b);
    dfle_bridge_check(b, 2);
    dfle_bridge_push_module(b);
    res = dfpy_ref_new(b, -1, NULL);
    dfle_bridge_settop(b, top);
    dfpy_leave();
    return res;
}

/* _dfle.lua(source, name): the Lua function `source` evaluates to. */
static PyObject *mod_lua(PyObject *self, PyObject *args)
{
    const char *src, *name = "=lua";
    Py_ssize_t len;
    dfle_bridge *b;
    PyObject *res = NULL;
    int top;
    (void)self;
    if (!PyArg_ParseTuple(args, "s#|s", &src, &len, &name))
        return NULL;
    b = dfpy_bridge();
    if (b == NULL)
        return NULL;
    dfpy_enter();
    top = dfle_bridge_top(b);
    dfle_bridge_check(b, 4);
    if (dfle_bridge_load(b, src, (size_t)len, name) < 0)
        dfpy_raise_top(b);
    else
        res = dfpy_ref_new(b, -1, NULL);
    dfle_bridge_settop(b, top);
    dfpy_leave();
    return res;
}

/* _dfle.known_unit(name): the unit dfle's files give name, or None. */
static PyObject *mod_known_unit(PyObject *self, PyObject *arg)
{
    const char *name = PyUnicode_AsUTF8(arg), *unit;
    (void)self;
    if (name == NULL)
        return NULL;
    unit = dfle_bridge_known_unit(name);
    if (unit == NULL)
        Py_RETURN_NONE;
    return PyUnicode_FromString(unit);
}

/* _dfle.udunits(unit): the unit as UDUNITS reads it (what dfle's NetCDF
 * files write as `units`), or None when UDUNITS has no syntax for it. */
static PyObject *mod_udunits(PyObject *self, PyObject *arg)
{
    const char *unit = PyUnicode_AsUTF8(arg);
    char buf[128];
    (void)self;
    if (unit == NULL)
        return NULL;
    if (!dfle_units_udunits(unit, buf, sizeof buf))
        Py_RETURN_NONE;
    return PyUnicode_FromString(buf);
}

/* _dfle.field_label(landscape, name): (units, dfle_units, long_name,
 * standard_name) as dfle's NetCDF files label the field: the unit in
 * UDUNITS's syntax as units, or, where UDUNITS has none, as dfle writes
 * it as dfle_units (the other None); None for a name that is no field. */
static PyObject *mod_field_label(PyObject *self, PyObject *args)
{
    const char *name, *unit, *long_name, *standard_name;
    int landscape;
    char buf[128];
    (void)self;
    if (!PyArg_ParseTuple(args, "ps", &landscape, &name))
        return NULL;
    if (!dfle_bridge_field_label(landscape, name, &unit, &long_name, &standard_name))
        Py_RETURN_NONE;
    if (unit != NULL && dfle_units_udunits(unit, buf, sizeof buf))
        return Py_BuildValue("(szzz)", buf, NULL, long_name, standard_name);
    return Py_BuildValue("(zzzz)", NULL, unit, long_name, standard_name);
}

/* _dfle._setup(Error, Warning, Table, classes, main_thread_ident) */
static PyObject *mod_setup(PyObject *self, PyObject *args)
{
    PyObject *err, *warn, *table, *classes;
    unsigned long main_ident;
    (void)self;
    if (!PyArg_ParseTuple(args, "OOOO!k", &err, &warn, &table, &PyDict_Type, &classes, &main_ident))
        return NULL;
    Py_XSETREF(dfpy_error, Py_NewRef(err));
    Py_XSETREF(dfpy_warning, Py_NewRef(warn));
    Py_XSETREF(dfpy_table_type, Py_NewRef(table));
    Py_XSETREF(dfpy_classes, Py_NewRef(classes));
    dfpy_main_thread = main_ident;
    Py_RETURN_NONE;
}

static PyMethodDef mod_methods[] = {
    {"module", mod_module, METH_NOARGS, "The dfle Lua module table."},
    {"lua", mod_lua, METH_VARARGS, "lua(source, name='=lua'): a Lua function from its source."},
    {"known_unit", mod_known_unit, METH_O, "known_unit(name): the unit dfle's files give name, or None."},
    {"udunits", mod_udunits, METH_O, "udunits(unit): the unit as dfle's NetCDF files write it, or None."},
    {"attrs", dfpy_attrs, METH_O,
     "attrs(obj): (attributes, crs) as a model's or landscape's NetCDF files give them, or None."},
    {"field_label", mod_field_label, METH_VARARGS,
     "field_label(landscape, name): (units, dfle_units, long_name, standard_name) as dfle's files give them."},
    {"parallel", dfpy_parallel, METH_VARARGS,
     "parallel(fn, script, spec): fn(spec) with worker states that run script."},
    {"_gc", dfpy_gc_phase, METH_VARARGS, "gc.callbacks' hook: cycles through Lua."},
    {"_setup", mod_setup, METH_VARARGS, NULL},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef mod_def = {
    PyModuleDef_HEAD_INIT, "_dfle",
    "The dfle engine (the C library and its Lua binding) for Python.", -1, mod_methods,
    NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__dfle(void);
PyMODINIT_FUNC PyInit__dfle(void)
{
    PyObject *m;
    import_array();
    if (PyType_Ready(&dfpy_ref_type) < 0)
        return NULL;
    m = PyModule_Create(&mod_def);
    if (m == NULL)
        return NULL;
    if (PyModule_AddObjectRef(m, "LuaRef", (PyObject *)&dfpy_ref_type) < 0 ||
        PyModule_AddStringConstant(m, "version", DFLE_VERSION) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
