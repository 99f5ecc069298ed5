/*
 * py_field.c - fields of models and landscapes as numpy arrays.
 *
 * The state and the geometry (a model's x, A, w, z; a landscape's z)
 * come back as read-only views of the object's own memory: they follow
 * the object through runs and set_z, and the array keeps the object
 * alive (its base holds it: close() and the collector free it only when
 * the last view is gone).  Writes are refused, because the object would
 * not see them (set_z is the way in, with its checks).  Every other
 * field is derived from z as of an evaluation that a later run leaves
 * behind, so it comes back as a copy, evaluated when asked: a view of
 * it would go stale without saying so.  Either way the values go from
 * C to numpy without a Lua table in between.
 */
#include "py_dfle.h"

#include <string.h>

#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#define NO_IMPORT_ARRAY
#define PY_ARRAY_UNIQUE_SYMBOL dfpy_ARRAY_API
#include <numpy/arrayobject.h>

/* The array of f: a view based on a holder of the object at idx, or a
 * copy. */
static PyObject *to_array(dfle_bridge *b, int idx, const dfle_bridge_field *f)
{
    npy_intp dims[2];
    int nd = f->ndim == 2 ? 2 : 1;
    PyObject *arr, *holder;

    if (nd == 2) {
        dims[0] = (npy_intp)f->ny;
        dims[1] = (npy_intp)f->nx;
    } else {
        dims[0] = (npy_intp)f->n;
    }
    if (!f->live) {
        arr = PyArray_SimpleNew(nd, dims, NPY_DOUBLE);
        if (arr != NULL && f->n > 0)
            memcpy(PyArray_DATA((PyArrayObject *)arr), f->v, f->n * sizeof *f->v);
        return arr;
    }
    /* A handle of its own, which holds the object until it goes. */
    holder = dfpy_ref_new(b, idx, NULL);
    if (holder == NULL)
        return NULL;
    if (dfle_bridge_hold(b, idx) < 0) {
        Py_DECREF(holder);
        return PyErr_NoMemory();
    }
    ((dfpy_ref *)holder)->held = 1;
    arr = PyArray_New(&PyArray_Type, nd, dims, NPY_DOUBLE, NULL, (void *)f->v, 0,
                      NPY_ARRAY_C_CONTIGUOUS | NPY_ARRAY_ALIGNED, NULL);
    if (arr == NULL) {
        Py_DECREF(holder);
        return NULL;
    }
    if (PyArray_SetBaseObject((PyArrayObject *)arr, holder) < 0) { /* steals holder */
        Py_DECREF(arr);
        return NULL;
    }
    return arr;
}

PyObject *dfpy_ref_field(PyObject *o, PyObject *name)
{
    dfpy_ref *r = (dfpy_ref *)o;
    dfle_bridge *b;
    dfle_bridge_field f;
    PyObject *res = NULL;
    const char *key;
    int top, st;

    if (!PyUnicode_Check(name)) {
        PyErr_Format(PyExc_TypeError, "dfle: a field name is a str (got %s)",
                     Py_TYPE(name)->tp_name);
        return NULL;
    }
    if ((key = PyUnicode_AsUTF8(name)) == NULL || (b = dfpy_bridge()) == NULL)
        return NULL;
    if (r->kind != DFLE_BRIDGE_OBJECT)
        Py_RETURN_NONE;
    dfpy_enter();
    top = dfle_bridge_top(b);
    if (!dfle_bridge_check(b, 8)) {
        PyErr_NoMemory();
        goto done;
    }
    dfle_bridge_push_ref(b, r->ref);
    st = dfle_bridge_get_field(b, top + 1, key, &f);
    if (st < 0)
        dfpy_raise_top(b);
    else if (st == 0)
        res = Py_NewRef(Py_None);
    else
        res = to_array(b, top + 1, &f);
done:
    dfle_bridge_settop(b, top);
    dfpy_leave();
    /* An evaluation may warn (an implausible value it met). */
    return dfpy_finish(res);
}

/* _dfle.attrs(obj): (attributes, crs) as the object's NetCDF files give
 * them (lua_bridge.h: dfle_bridge_push_attrs), or None for an object
 * that has no such files. */
PyObject *dfpy_attrs(PyObject *self, PyObject *o)
{
    dfle_bridge *b;
    PyObject *res = NULL, *attrs, *crs;
    int top, st;
    (void)self;
    if (!PyObject_TypeCheck(o, &dfpy_ref_type)) {
        PyErr_SetString(PyExc_TypeError, "dfle: attrs() takes a dfle object");
        return NULL;
    }
    if ((b = dfpy_bridge()) == NULL)
        return NULL;
    if (((dfpy_ref *)o)->kind != DFLE_BRIDGE_OBJECT)
        Py_RETURN_NONE;
    dfpy_enter();
    top = dfle_bridge_top(b);
    if (!dfle_bridge_check(b, 8)) {
        PyErr_NoMemory();
        goto done;
    }
    dfle_bridge_push_ref(b, ((dfpy_ref *)o)->ref);
    st = dfle_bridge_push_attrs(b, top + 1);
    if (st < 0) {
        dfpy_raise_top(b);
    } else if (st == 0) {
        res = Py_NewRef(Py_None);
    } else {
        attrs = dfpy_to_python(b, top + 2, 0);
        crs = attrs != NULL ? dfpy_to_python(b, top + 3, 0) : NULL;
        if (crs != NULL)
            res = PyTuple_Pack(2, attrs, crs);
        Py_XDECREF(attrs);
        Py_XDECREF(crs);
    }
done:
    dfle_bridge_settop(b, top);
    dfpy_leave();
    return dfpy_finish(res);
}
