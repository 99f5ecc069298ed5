/*
 * py_convert.c - values between Python and Lua.
 *
 * Python to Lua: None, bool, int, float, str, bytes as themselves; a
 * numpy array (any shape, read in C order: a (ny, nx) grid becomes the
 * row-major array of nx * ny values the binding takes) or a list or
 * tuple as an array; a dict as a table; a callable as a Lua function
 * calling it; a LuaRef as the value it refers to.
 *
 * Lua to Python: an array of numbers becomes a numpy array (float64,
 * int64 when every value is an integer: a copy, the Lua table is gone
 * when the call returns), another array a list, a plain table a
 * dfle.Table (a dict whose keys read as attributes too), and objects,
 * functions and tables with a metatable (results with methods or strict
 * fields) a LuaRef.
 */
#include "py_dfle.h"

#include <stdint.h>
#include <string.h>

#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#define NO_IMPORT_ARRAY
#define PY_ARRAY_UNIQUE_SYMBOL dfpy_ARRAY_API
#include <numpy/arrayobject.h>

/* Tables nest: a deeper one (a cycle) stays a reference. */
#define MAX_DEPTH 48

/* --- callbacks: a Python callable as a Lua function --- */

void dfpy_keep_callback_error(void);

static void release_callable(void *ud)
{
    PyGILState_STATE g = PyGILState_Ensure();
    dfpy_live_callbacks--;
    Py_DECREF((PyObject *)ud);
    PyGILState_Release(g);
}

static int push_error_text(dfle_bridge *b, PyObject *fn)
{
    /* "<name>: <Type>: <message>", as the Lua caller sees it; the
     * exception itself becomes the cause of the dfle.Error. */
    PyObject *t, *v, *tb, *text = NULL;
    PyErr_Fetch(&t, &v, &tb);
    PyErr_NormalizeException(&t, &v, &tb);
    if (v != NULL) {
        PyObject *qn = PyObject_GetAttrString(fn, "__qualname__");
        if (qn == NULL)
            PyErr_Clear();
        text = PyUnicode_FromFormat("Python function %S raised %s: %S",
                                    qn ? qn : Py_None, Py_TYPE(v)->tp_name, v);
        Py_XDECREF(qn);
        if (text == NULL)
            PyErr_Clear();
    }
    if (tb != NULL && v != NULL)
        PyException_SetTraceback(v, tb);
    PyErr_Restore(t, v, tb);
    dfpy_keep_callback_error();
    if (text != NULL) {
        Py_ssize_t len;
        const char *s = PyUnicode_AsUTF8AndSize(text, &len);
        if (s != NULL)
            dfle_bridge_push_string(b, s, (size_t)len);
        else {
            PyErr_Clear();
            dfle_bridge_push_string(b, "Python function raised", 22);
        }
        Py_DECREF(text);
    } else {
        dfle_bridge_push_string(b, "Python function raised", 22);
    }
    return -1;
}

static int call_callable(dfle_bridge *b, void *ud, int nargs)
{
    PyObject *fn = ud, *args, *res;
    PyGILState_STATE g = PyGILState_Ensure();
    int n = -1;

    args = PyTuple_New(nargs);
    if (args == NULL)
        goto error;
    for (int i = 0; i < nargs; i++) {
        PyObject *a = dfpy_to_python(b, i + 1, 0);
        if (a == NULL) {
            Py_DECREF(args);
            goto error;
        }
        PyTuple_SET_ITEM(args, i, a);
    }
    res = PyObject_Call(fn, args, NULL);
    Py_DECREF(args);
    if (res == NULL)
        goto error;
    dfle_bridge_settop(b, 0);
    if (PyTuple_Check(res)) {
        n = (int)PyTuple_GET_SIZE(res);
        for (int i = 0; i < n; i++)
            if (dfpy_push(b, PyTuple_GET_ITEM(res, i), 0) < 0) {
                Py_DECREF(res);
                goto error;
            }
    } else {
        n = dfpy_push(b, res, 0) < 0 ? -1 : 1;
    }
    Py_DECREF(res);
    if (n < 0)
        goto error;
    PyGILState_Release(g);
    return n;
error:
    dfle_bridge_settop(b, 0);
    n = push_error_text(b, fn);
    PyGILState_Release(g);
    return n;
}

/* --- Python to Lua --- */

static int push_array(dfle_bridge *b, PyObject *v)
{
    PyArrayObject *a;
    int integer = PyArray_ISINTEGER((PyArrayObject *)v) || PyArray_ISBOOL((PyArrayObject *)v);
    a = (PyArrayObject *)PyArray_FROMANY(v, integer ? NPY_LONGLONG : NPY_DOUBLE, 0, 0,
                                         NPY_ARRAY_C_CONTIGUOUS | NPY_ARRAY_ALIGNED |
                                             NPY_ARRAY_FORCECAST);
    if (a == NULL)
        return -1;
    if (PyArray_NDIM(a) == 0) {
        if (integer)
            dfle_bridge_push_integer(b, *(const long long *)PyArray_DATA(a));
        else
            dfle_bridge_push_number(b, *(const double *)PyArray_DATA(a));
    } else if (integer) {
        dfle_bridge_push_integers(b, PyArray_DATA(a), (size_t)PyArray_SIZE(a));
    } else {
        dfle_bridge_push_doubles(b, PyArray_DATA(a), (size_t)PyArray_SIZE(a));
    }
    Py_DECREF(a);
    return 0;
}

static int push_dict(dfle_bridge *b, PyObject *v, int depth)
{
    PyObject *k, *val;
    Py_ssize_t pos = 0;
    int t;
    dfle_bridge_new_table(b, 0, (int)PyDict_Size(v));
    t = dfle_bridge_top(b);
    while (PyDict_Next(v, &pos, &k, &val)) {
        if (dfpy_push(b, val, depth + 1) < 0)
            return -1;
        if (PyUnicode_Check(k)) {
            const char *s = PyUnicode_AsUTF8(k);
            if (s == NULL)
                return -1;
            dfle_bridge_set_field(b, t, s);
        } else if (PyLong_Check(k) && !PyBool_Check(k)) {
            long long i = PyLong_AsLongLong(k);
            if (i == -1 && PyErr_Occurred())
                return -1;
            dfle_bridge_set_index(b, t, i);
        } else {
            PyErr_Format(PyExc_TypeError, "dfle: a key of a table must be a str or an int (got %s)",
                         Py_TYPE(k)->tp_name);
            return -1;
        }
    }
    return 0;
}

static int push_sequence(dfle_bridge *b, PyObject *v, int depth)
{
    PyObject *seq = PySequence_Fast(v, "dfle: not a sequence");
    Py_ssize_t n;
    int t;
    if (seq == NULL)
        return -1;
    n = PySequence_Fast_GET_SIZE(seq);
    dfle_bridge_new_table(b, (int)n, 0);
    t = dfle_bridge_top(b);
    for (Py_ssize_t i = 0; i < n; i++) {
        if (dfpy_push(b, PySequence_Fast_GET_ITEM(seq, i), depth + 1) < 0) {
            Py_DECREF(seq);
            return -1;
        }
        dfle_bridge_set_index(b, t, (long long)i + 1);
    }
    Py_DECREF(seq);
    return 0;
}

int dfpy_push(dfle_bridge *b, PyObject *v, int depth)
{
    if (depth > MAX_DEPTH) {
        PyErr_SetString(PyExc_ValueError, "dfle: a value nested too deep (a cycle?)");
        return -1;
    }
    if (!dfle_bridge_check(b, 4)) {
        PyErr_NoMemory();
        return -1;
    }
    if (v == Py_None) {
        dfle_bridge_push_nil(b);
    } else if (PyBool_Check(v)) {
        dfle_bridge_push_boolean(b, v == Py_True);
    } else if (PyLong_Check(v)) {
        int overflow = 0;
        long long i = PyLong_AsLongLongAndOverflow(v, &overflow);
        if (i == -1 && PyErr_Occurred())
            return -1;
        if (overflow != 0) {
            double d = PyLong_AsDouble(v);
            if (d == -1.0 && PyErr_Occurred())
                return -1;
            dfle_bridge_push_number(b, d);
        } else {
            dfle_bridge_push_integer(b, i);
        }
    } else if (PyFloat_Check(v)) {
        dfle_bridge_push_number(b, PyFloat_AS_DOUBLE(v));
    } else if (PyObject_TypeCheck(v, &dfpy_ref_type)) {
        dfle_bridge_push_ref(b, ((dfpy_ref *)v)->ref);
    } else if (PyUnicode_Check(v)) {
        Py_ssize_t len;
        const char *s = PyUnicode_AsUTF8AndSize(v, &len);
        if (s == NULL)
            return -1;
        dfle_bridge_push_string(b, s, (size_t)len);
    } else if (PyBytes_Check(v)) {
        dfle_bridge_push_string(b, PyBytes_AS_STRING(v), (size_t)PyBytes_GET_SIZE(v));
    } else if (PyArray_Check(v) || PyArray_IsScalar(v, Generic)) {
        if (PyArray_IsScalar(v, Generic)) {
            PyObject *item = PyObject_CallMethod(v, "item", NULL);
            int st;
            if (item == NULL)
                return -1;
            st = PyArray_IsScalar(item, Generic) ? -1 : dfpy_push(b, item, depth + 1);
            if (st < 0 && !PyErr_Occurred())
                PyErr_Format(PyExc_TypeError, "dfle: cannot pass a %s to Lua", Py_TYPE(v)->tp_name);
            Py_DECREF(item);
            return st;
        }
        return push_array(b, v);
    } else if (PyDict_Check(v)) {
        return push_dict(b, v, depth);
    } else if (PyList_Check(v) || PyTuple_Check(v)) {
        return push_sequence(b, v, depth);
    } else if (PyCallable_Check(v)) {
        Py_INCREF(v);
        dfpy_live_callbacks++;
        dfle_bridge_push_callback(b, call_callable, v, release_callable);
    } else if (PyMapping_Check(v) && PyObject_HasAttrString(v, "keys")) {
        PyObject *d = PyDict_New();
        int st;
        if (d == NULL || PyDict_Merge(d, v, 1) < 0) {
            Py_XDECREF(d);
            return -1;
        }
        st = push_dict(b, d, depth);
        Py_DECREF(d);
        return st;
    } else if (PySequence_Check(v)) {
        return push_sequence(b, v, depth);
    } else {
        PyErr_Format(PyExc_TypeError, "dfle: cannot pass a %s to Lua", Py_TYPE(v)->tp_name);
        return -1;
    }
    return 0;
}

int dfpy_push_kwargs(dfle_bridge *b, PyObject *kwargs)
{
    return dfpy_push(b, kwargs, 0);
}

/* --- Lua to Python --- */

static PyObject *number_array(dfle_bridge *b, int idx, size_t n)
{
    npy_intp dim = (npy_intp)n;
    PyArrayObject *a = (PyArrayObject *)PyArray_SimpleNew(1, &dim, NPY_DOUBLE);
    int all_int = 0;
    if (a == NULL)
        return NULL;
    if (!dfle_bridge_number_array(b, idx, PyArray_DATA(a), n, &all_int)) {
        Py_DECREF(a);
        Py_RETURN_NONE; /* not an array of numbers: the caller goes on */
    }
    if (all_int) {
        PyObject *ints = PyArray_Cast(a, NPY_INT64);
        Py_DECREF(a);
        return ints;
    }
    return (PyObject *)a;
}

/* Result tables repeat the same keys call after call (a step's status
 * has some thirty): their Python strings are kept, looked up by content,
 * so a key costs a compare, and its str hash is computed once.  Lua keeps
 * one copy of each short string, so its address finds the slot; the
 * compare makes a slot whose string went and whose address came back
 * harmless.  Used with the GIL held. */
#define KEY_CACHE 512
#define KEY_MAX 32
static struct {
    size_t len;
    char s[KEY_MAX];
    PyObject *str;
} key_cache[KEY_CACHE];

static PyObject *key_string(const char *s, size_t len)
{
    size_t h = (size_t)(((uintptr_t)s >> 3) * 2654435761u) % KEY_CACHE;
    PyObject *str;
    if (len >= KEY_MAX)
        return PyUnicode_DecodeUTF8(s, (Py_ssize_t)len, "surrogateescape");
    if (key_cache[h].str != NULL && key_cache[h].len == len && memcmp(key_cache[h].s, s, len) == 0)
        return Py_NewRef(key_cache[h].str);
    str = PyUnicode_DecodeUTF8(s, (Py_ssize_t)len, "surrogateescape");
    if (str == NULL)
        return NULL;
    Py_XSETREF(key_cache[h].str, Py_NewRef(str));
    key_cache[h].len = len;
    memcpy(key_cache[h].s, s, len);
    return str;
}

static PyObject *table_to_python(dfle_bridge *b, int idx, int depth)
{
    size_t n = dfle_bridge_len(b, idx);
    PyObject *d;
    Py_ssize_t count = 0;

    if (n > 0) {
        PyObject *arr = number_array(b, idx, n);
        if (arr != Py_None)
            return arr;
        Py_DECREF(arr);
    }
    /* Filled in place (a dfle.Table is a dict): no second dict to copy. */
    d = dfpy_table_type != NULL ? PyObject_CallNoArgs(dfpy_table_type) : PyDict_New();
    if (d == NULL)
        return NULL;
    dfle_bridge_push_nil(b);
    while (dfle_bridge_next(b, idx)) {
        int top = dfle_bridge_top(b);
        PyObject *k, *v;
        if (dfle_bridge_type(b, top - 1) == DFLE_BRIDGE_STRING) {
            size_t len;
            const char *s = dfle_bridge_to_string(b, top - 1, &len);
            k = key_string(s, len);
        } else {
            k = dfpy_to_python(b, top - 1, depth + 1);
        }
        v = k ? dfpy_to_python(b, top, depth + 1) : NULL;
        if (v == NULL || PyDict_SetItem(d, k, v) < 0) {
            Py_XDECREF(k);
            Py_XDECREF(v);
            Py_DECREF(d);
            dfle_bridge_settop(b, top - 2);
            return NULL;
        }
        Py_DECREF(k);
        Py_DECREF(v);
        count++;
        dfle_bridge_settop(b, top - 1);
    }
    if ((size_t)count == n) { /* an array of other values: a list */
        PyObject *list = PyList_New(count);
        if (list == NULL) {
            Py_DECREF(d);
            return NULL;
        }
        for (Py_ssize_t i = 0; i < count; i++) {
            PyObject *key = PyLong_FromSsize_t(i + 1), *v;
            v = key ? PyDict_GetItemWithError(d, key) : NULL;
            Py_XDECREF(key);
            if (v == NULL) {
                Py_DECREF(list);
                Py_DECREF(d);
                if (!PyErr_Occurred())
                    PyErr_SetString(PyExc_RuntimeError, "dfle: an array with a hole");
                return NULL;
            }
            Py_INCREF(v);
            PyList_SET_ITEM(list, i, v);
        }
        Py_DECREF(d);
        return list;
    }
    return d;
}

PyObject *dfpy_to_python(dfle_bridge *b, int idx, int depth)
{
    if (idx < 0)
        idx = dfle_bridge_top(b) + idx + 1;
    if (!dfle_bridge_check(b, 4))
        return PyErr_NoMemory();
    switch (dfle_bridge_type(b, idx)) {
    case DFLE_BRIDGE_NIL:
        Py_RETURN_NONE;
    case DFLE_BRIDGE_BOOLEAN:
        return PyBool_FromLong(dfle_bridge_to_boolean(b, idx));
    case DFLE_BRIDGE_NUMBER:
        if (dfle_bridge_is_integer(b, idx))
            return PyLong_FromLongLong(dfle_bridge_to_integer(b, idx));
        return PyFloat_FromDouble(dfle_bridge_to_number(b, idx));
    case DFLE_BRIDGE_STRING: {
        size_t len;
        const char *s = dfle_bridge_to_string(b, idx, &len);
        return PyUnicode_DecodeUTF8(s, (Py_ssize_t)len, "surrogateescape");
    }
    case DFLE_BRIDGE_TABLE:
        if (depth <= MAX_DEPTH && !dfle_bridge_has_metatable(b, idx))
            return table_to_python(b, idx, depth);
        return dfpy_ref_new(b, idx, NULL);
    default:
        return dfpy_ref_new(b, idx, NULL);
    }
}

PyObject *dfpy_results(dfle_bridge *b, int first, int n)
{
    PyObject *t;
    if (n == 0)
        Py_RETURN_NONE;
    if (n == 2 && dfle_bridge_type(b, first) == DFLE_BRIDGE_NIL &&
        dfle_bridge_type(b, first + 1) == DFLE_BRIDGE_STRING) {
        /* An expected failure (a fit that does not converge): Lua
         * returns nil and the reason; Python raises it. */
        dfle_bridge_settop(b, first + 1);
        dfpy_raise_top(b);
        return NULL;
    }
    if (n == 1)
        return dfpy_to_python(b, first, 0);
    t = PyTuple_New(n);
    if (t == NULL)
        return NULL;
    for (int i = 0; i < n; i++) {
        PyObject *v = dfpy_to_python(b, first + i, 0);
        if (v == NULL) {
            Py_DECREF(t);
            return NULL;
        }
        PyTuple_SET_ITEM(t, i, v);
    }
    return t;
}
