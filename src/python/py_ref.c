/*
 * py_ref.c - dfle.LuaRef: a Python handle on a value in the Lua state.
 *
 * Attributes are the Lua object's: m.time reads the property, m.run is
 * the method (called with the object first, as m:run in Lua), and the
 * keyword arguments of a call are the one table of named parameters the
 * Lua API takes: m.run_to_steady(tol=1e-3) is m:run_to_steady{ tol =
 * 1e-3 }.  The handle keeps the value alive; an object closed early
 * (close(), or `with`) raises on use with the Lua message.
 */
#include "py_dfle.h"

#include <stddef.h>
#include <string.h>

PyObject *dfpy_ref_new(dfle_bridge *b, int idx, PyObject *self)
{
    PyTypeObject *cls = &dfpy_ref_type;
    dfpy_ref *r;
    int kind = dfle_bridge_type(b, idx);

    if (idx < 0)
        idx = dfle_bridge_top(b) + idx + 1;
    /* Objects, and results with methods (a table whose metatable has a
     * __name, dfle.ensemble), get the class registered for their type. */
    if ((kind == DFLE_BRIDGE_OBJECT || kind == DFLE_BRIDGE_TABLE) && dfpy_classes != NULL) {
        PyObject *c = PyDict_GetItemString(dfpy_classes, dfle_bridge_typename(b, idx));
        if (c != NULL && PyType_Check(c) && PyType_IsSubtype((PyTypeObject *)c, &dfpy_ref_type))
            cls = (PyTypeObject *)c;
    }
    r = (dfpy_ref *)cls->tp_alloc(cls, 0);
    if (r == NULL)
        return NULL;
    if (!dfle_bridge_check(b, 1)) {
        Py_DECREF(r);
        return PyErr_NoMemory();
    }
    dfle_bridge_push_value(b, idx);
    r->ref = dfle_bridge_ref(b);
    r->kind = kind;
    Py_XINCREF(self);
    r->self = self;
    return (PyObject *)r;
}

static void ref_dealloc(PyObject *o)
{
    dfpy_ref *r = (dfpy_ref *)o;
    PyObject_GC_UnTrack(o);
    if (r->weak != NULL)
        PyObject_ClearWeakRefs(o);
    dfpy_release_ref(r->ref, r->held);
    r->ref = -1;
    Py_CLEAR(r->self);
    Py_TYPE(o)->tp_free(o);
}

/* What the handle holds: its method's object, its type, and the Python
 * callables that only its Lua value keeps alive (py_gc.c). */
static int ref_traverse(PyObject *o, visitproc visit, void *arg)
{
    Py_VISIT(((dfpy_ref *)o)->self);
    Py_VISIT(Py_TYPE(o));
    return dfpy_gc_visit(((dfpy_ref *)o)->ref, visit, arg);
}

/* The collector breaks a cycle here: the Lua value is let go of too
 * (a cycle through Lua ends when Lua collects it). */
static int ref_clear(PyObject *o)
{
    dfpy_ref *r = (dfpy_ref *)o;
    Py_CLEAR(r->self);
    if (r->ref > 0) {
        dfpy_release_ref(r->ref, r->held);
        r->ref = -1;
        r->held = 0;
        dfpy_gc_cleared();
    }
    return 0;
}

/* Issue the warnings the call left, keeping an exception it raised. */
PyObject *dfpy_finish(PyObject *res)
{
    if (res == NULL) {
        PyObject *t, *v, *tb;
        PyErr_Fetch(&t, &v, &tb);
        dfpy_flush_warnings();
        PyErr_Clear();
        PyErr_Restore(t, v, tb);
        return NULL;
    }
    if (dfpy_flush_warnings() < 0) {
        Py_DECREF(res);
        return NULL;
    }
    return res;
}

PyObject *dfpy_ref_call(PyObject *fn, PyObject *args, PyObject *kwargs)
{
    dfpy_ref *r = (dfpy_ref *)fn;
    dfle_bridge *b = dfpy_bridge();
    PyObject *res = NULL;
    Py_ssize_t npos = args ? PyTuple_GET_SIZE(args) : 0;
    int top, nargs = 0, nres = 0;

    if (b == NULL)
        return NULL;
    dfpy_enter();
    top = dfle_bridge_top(b);
    if (!dfle_bridge_check(b, (int)npos + 4)) {
        PyErr_NoMemory();
        goto done;
    }
    dfle_bridge_push_ref(b, r->ref);
    if (r->self != NULL) {
        dfle_bridge_push_ref(b, ((dfpy_ref *)r->self)->ref);
        nargs++;
    }
    for (Py_ssize_t i = 0; i < npos; i++, nargs++)
        if (dfpy_push(b, PyTuple_GET_ITEM(args, i), 0) < 0)
            goto done;
    if (kwargs != NULL && PyDict_Size(kwargs) > 0) {
        if (dfpy_push_kwargs(b, kwargs) < 0)
            goto done;
        nargs++;
    }
    if (dfpy_call(b, nargs, &nres) < 0)
        goto done;
    res = dfpy_results(b, top + 1, nres);
done:
    dfle_bridge_settop(b, top);
    dfpy_leave();
    return dfpy_finish(res);
}

static PyObject *ref_call(PyObject *o, PyObject *args, PyObject *kwargs)
{
    if (((dfpy_ref *)o)->kind != DFLE_BRIDGE_FUNCTION) {
        /* Objects and tables with __call (dfle.law is one) go through Lua too. */
        if (((dfpy_ref *)o)->kind != DFLE_BRIDGE_TABLE && ((dfpy_ref *)o)->kind != DFLE_BRIDGE_OBJECT) {
            PyErr_Format(PyExc_TypeError, "a Lua %s is not callable", "value");
            return NULL;
        }
    }
    return dfpy_ref_call(o, args, kwargs);
}

/* o[key] in Lua; AttributeError (or KeyError) when it is nil or the
 * object refuses the key, with Lua's message. */
static PyObject *lua_index(PyObject *o, const char *key, PyObject *missing)
{
    dfpy_ref *r = (dfpy_ref *)o;
    dfle_bridge *b = dfpy_bridge();
    PyObject *res = NULL;
    int top, method = 0;

    if (b == NULL)
        return NULL;
    dfpy_enter();
    top = dfle_bridge_top(b);
    if (!dfle_bridge_check(b, 4)) {
        PyErr_NoMemory();
        goto done;
    }
    dfle_bridge_push_ref(b, r->ref);
    if (dfle_bridge_index(b, top + 1, key, &method) < 0) {
        size_t len = 0;
        const char *msg = dfle_bridge_to_string(b, -1, &len);
        PyErr_SetString(missing, msg ? msg : key);
        goto done;
    }
    if (dfle_bridge_type(b, -1) == DFLE_BRIDGE_NIL && r->kind != DFLE_BRIDGE_OBJECT) {
        /* An object's __index refuses unknown keys itself: its nil is a
         * value (a process switched off); a table's is a missing key. */
        PyObject *tn = PyUnicode_FromString(dfle_bridge_typename(b, top + 1));
        PyErr_Format(missing, "%U has no field '%s'", tn, key);
        Py_XDECREF(tn);
        goto done;
    }
    if (dfle_bridge_type(b, -1) == DFLE_BRIDGE_FUNCTION)
        res = dfpy_ref_new(b, -1, method ? o : NULL);
    else
        res = dfpy_to_python(b, -1, 0);
done:
    dfle_bridge_settop(b, top);
    dfpy_leave();
    return dfpy_finish(res);
}

static PyObject *ref_getattro(PyObject *o, PyObject *name)
{
    PyObject *v = PyObject_GenericGetAttr(o, name);
    const char *key;
    if (v != NULL || !PyErr_ExceptionMatches(PyExc_AttributeError))
        return v;
    key = PyUnicode_AsUTF8(name);
    if (key == NULL || (key[0] == '_' && key[1] == '_'))
        return NULL; /* Python's own protocols are not looked up in Lua */
    PyErr_Clear();
    return lua_index(o, key, PyExc_AttributeError);
}

static PyObject *ref_index_method(PyObject *o, PyObject *key)
{
    const char *k = PyUnicode_AsUTF8(key);
    if (k == NULL)
        return NULL;
    return lua_index(o, k, PyExc_AttributeError);
}

static PyObject *ref_getitem(PyObject *o, PyObject *key)
{
    const char *k;
    if (!PyUnicode_Check(key)) {
        PyErr_Format(PyExc_TypeError, "dfle: keys are names (got %s)", Py_TYPE(key)->tp_name);
        return NULL;
    }
    k = PyUnicode_AsUTF8(key);
    return k ? lua_index(o, k, PyExc_KeyError) : NULL;
}

static PyObject *ref_repr(PyObject *o)
{
    dfpy_ref *r = (dfpy_ref *)o;
    dfle_bridge *b = dfpy_bridge();
    PyObject *res = NULL;
    int top;
    if (b == NULL)
        return NULL;
    dfpy_enter();
    top = dfle_bridge_top(b);
    dfle_bridge_check(b, 4);
    dfle_bridge_push_ref(b, r->ref);
    if (dfle_bridge_tostring(b, top + 1) < 0) {
        dfpy_raise_top(b);
    } else {
        size_t len;
        const char *s = dfle_bridge_to_string(b, -1, &len);
        res = PyUnicode_DecodeUTF8(s ? s : "?", s ? (Py_ssize_t)len : 1, "replace");
    }
    dfle_bridge_settop(b, top);
    dfpy_leave();
    return res;
}

/* The keys of a table kept as a reference, raw (as pairs() without
 * __pairs). */
static PyObject *ref_keys(PyObject *o, PyObject *unused)
{
    dfpy_ref *r = (dfpy_ref *)o;
    dfle_bridge *b = dfpy_bridge();
    PyObject *list;
    int top;
    (void)unused;
    if (b == NULL)
        return NULL;
    if (r->kind != DFLE_BRIDGE_TABLE)
        return PyList_New(0);
    list = PyList_New(0);
    if (list == NULL)
        return NULL;
    dfpy_enter();
    top = dfle_bridge_top(b);
    dfle_bridge_check(b, 4);
    dfle_bridge_push_ref(b, r->ref);
    dfle_bridge_push_nil(b);
    while (dfle_bridge_next(b, top + 1)) {
        PyObject *k = dfpy_to_python(b, -2, 0);
        dfle_bridge_settop(b, dfle_bridge_top(b) - 1);
        if (k == NULL || PyList_Append(list, k) < 0) {
            Py_XDECREF(k);
            Py_CLEAR(list);
            break;
        }
        Py_DECREF(k);
    }
    dfle_bridge_settop(b, top);
    dfpy_leave();
    if (list != NULL && PyList_Sort(list) < 0)
        PyErr_Clear(); /* keys of mixed types stay in table order */
    return list;
}

static PyObject *ref_close(PyObject *o, PyObject *unused)
{
    dfpy_ref *r = (dfpy_ref *)o;
    dfle_bridge *b = dfpy_bridge();
    int top, st;
    (void)unused;
    if (b == NULL)
        return NULL;
    dfpy_enter();
    top = dfle_bridge_top(b);
    dfle_bridge_check(b, 4);
    dfle_bridge_push_ref(b, r->ref);
    st = dfle_bridge_close(b, top + 1);
    if (st < 0)
        dfpy_raise_top(b);
    dfle_bridge_settop(b, top);
    dfpy_leave();
    if (st < 0)
        return NULL;
    Py_RETURN_NONE;
}

static PyObject *ref_enter(PyObject *o, PyObject *unused)
{
    (void)unused;
    Py_INCREF(o);
    return o;
}

static PyObject *ref_exit(PyObject *o, PyObject *args)
{
    (void)args;
    return ref_close(o, NULL);
}

static PyObject *ref_lua_type(PyObject *o, void *closure)
{
    dfpy_ref *r = (dfpy_ref *)o;
    dfle_bridge *b = dfpy_bridge();
    PyObject *res;
    int top;
    (void)closure;
    if (b == NULL)
        return NULL;
    dfpy_enter();
    top = dfle_bridge_top(b);
    dfle_bridge_check(b, 2);
    dfle_bridge_push_ref(b, r->ref);
    res = PyUnicode_FromString(dfle_bridge_typename(b, -1));
    dfle_bridge_settop(b, top);
    dfpy_leave();
    return res;
}

static PyMethodDef ref_methods[] = {
    {"_index", ref_index_method, METH_O, "The Lua value o[key] (methods bound to o)."},
    {"_field", dfpy_ref_field, METH_O, "The field of a model or landscape as numpy (None: ask get)."},
    {"keys", ref_keys, METH_NOARGS, "The keys of a Lua table."},
    {"close", ref_close, METH_NOARGS, "Free the object now (Lua's __close)."},
    {"__enter__", ref_enter, METH_NOARGS, NULL},
    {"__exit__", ref_exit, METH_VARARGS, NULL},
    {NULL, NULL, 0, NULL}};

static PyGetSetDef ref_getset[] = {
    {"lua_type", ref_lua_type, NULL, "The Lua type name (\"dfle.model\", \"table\", ...).", NULL},
    {NULL, NULL, NULL, NULL, NULL}};

static PyMappingMethods ref_mapping = {.mp_subscript = ref_getitem};

PyTypeObject dfpy_ref_type = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "dfle.LuaRef",
    .tp_doc = "A dfle object, function or result living in the Lua state.",
    .tp_basicsize = sizeof(dfpy_ref),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_BASETYPE | Py_TPFLAGS_HAVE_GC,
    .tp_dealloc = ref_dealloc,
    .tp_traverse = ref_traverse,
    .tp_clear = ref_clear,
    .tp_getattro = ref_getattro,
    .tp_call = ref_call,
    .tp_repr = ref_repr,
    .tp_as_mapping = &ref_mapping,
    .tp_methods = ref_methods,
    .tp_getset = ref_getset,
    .tp_weaklistoffset = offsetof(dfpy_ref, weak),
};
