/* The body FMU's per-step FMI calls without a Python frame (a CPython extension).
 *
 * pythonfmu calls the slave's methods do_step, set_real and get_real by name, once per
 * FMI call. While the compiled step runs (native.FastBody), the adapter
 * (contact_fmu/fmu/slave.py, ContactSlave._fast_enable) puts the methods of a Binding
 * on the instance in their place. Each does what the adapter's Python does on the
 * common path and hands everything else to the adapter's own method, unchanged:
 *
 *   do_step(t, h)        no input held bad, 0 < h < inf, t the FMU's time (relative
 *                        tolerance rtol of max(|t|, |time|): cf_core.h), cf_body_step
 *                        OK: the FMU's time advanced, outputs marked stale, True.
 *                        Otherwise the Python step.
 *   set_real(vrs, vals)  a float, finite and in the declared range of a Real input
 *                        (cf_core.h's cf_value_check):
 *                        stored in the CallState's values and inputs, cleared from
 *                        bad, written to the struct if the step reads it, dirty set.
 *                        Otherwise that value goes through the adapter's set_real.
 *   get_real(vrs)        outputs of the struct only: a list of its doubles.
 *                        Otherwise the adapter's get_real.
 *
 * The adapter's state of the calls is one object, its CallState (fmu/call_state.py: time,
 * values, inputs, bad, dirty, out_stale), bound here and read and written through those
 * attributes on every call (no copy kept here), so whatever the adapter reassigns stays
 * the truth; nothing else of the adapter is read. The checks are
 * the native FMU's (instance.c): the value's range and the time's in cf_core.h, the step's
 * caps, load limit and outputs in stepper.c's cf_body_step; each is slave.py's rule,
 * and test_fmu_slave compares the two paths bit for bit.
 *
 * The GIL stays held through the compiled step (about a microsecond): released, taking
 * it back could wait for another thread's switch interval (5 ms), far longer. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stddef.h>

#include "cf_core.h"

typedef int (*step_fn)(void *, void *, void *, double);

typedef struct {
    PyObject *name;   /* the input's name (a str, key of values, inputs, bad) */
    double lo, hi;    /* declared range */
    int open_lo;      /* lo excluded */
    double *dst;      /* its place in the struct, or NULL */
} slot;

typedef struct {
    PyObject_HEAD
    PyObject *shared;            /* the adapter's CallState (fmu/call_state.py) */
    PyObject *owner;             /* the FastBody: keeps the structs alive */
    PyObject *py_step, *py_set, *py_get; /* the adapter's own methods */
    step_fn step;
    void *params, *state, *io;
    const double *out;
    double rtol;
    Py_ssize_t n_vr;
    int *slot_of_vr, *out_of_vr; /* by value reference: index or -1 */
    slot *slots;
    Py_ssize_t n_slots;
    unsigned long long steps;   /* steps taken here */
    PyObject *weakrefs;
} Binding;

static PyObject *s_time, *s_bad, *s_values, *s_in, *s_dirty, *s_stale;

static int traverse(Binding *b, visitproc visit, void *arg) {
    Py_VISIT(b->shared);
    Py_VISIT(b->owner);
    Py_VISIT(b->py_step);
    Py_VISIT(b->py_set);
    Py_VISIT(b->py_get);
    return 0;
}

static int clear(Binding *b) {
    Py_CLEAR(b->shared);
    Py_CLEAR(b->owner);
    Py_CLEAR(b->py_step);
    Py_CLEAR(b->py_set);
    Py_CLEAR(b->py_get);
    return 0;
}

static void dealloc(Binding *b) {
    PyObject_GC_UnTrack(b);
    if (b->weakrefs != NULL) PyObject_ClearWeakRefs((PyObject *)b);
    clear(b);
    for (Py_ssize_t i = 0; i < b->n_slots; i++) Py_XDECREF(b->slots[i].name);
    PyMem_Free(b->slots);
    PyMem_Free(b->slot_of_vr);
    PyMem_Free(b->out_of_vr);
    Py_TYPE(b)->tp_free((PyObject *)b);
}

/* the length of a dict attribute of the adapter, -1 on error */
static Py_ssize_t dict_len(PyObject *shared, PyObject *attr) {
    PyObject *d = PyObject_GetAttr(shared, attr);
    if (d == NULL) return -1;
    Py_ssize_t n = PyDict_Check(d) ? PyDict_GET_SIZE(d) : PyObject_Length(d);
    Py_DECREF(d);
    return n;
}

static PyObject *do_step(Binding *b, PyObject *const *args, Py_ssize_t nargs) {
    if (nargs != 2) return PyObject_Vectorcall(b->py_step, args, nargs, NULL);
    double t = PyFloat_AsDouble(args[0]), h = PyFloat_AsDouble(args[1]);
    if (PyErr_Occurred()) {
        PyErr_Clear();
        return PyObject_Vectorcall(b->py_step, args, nargs, NULL);
    }
    Py_ssize_t bad = dict_len(b->shared, s_bad);
    if (bad < 0) return NULL;
    PyObject *now = PyObject_GetAttr(b->shared, s_time);
    if (now == NULL) return NULL;
    double time = PyFloat_AsDouble(now);
    Py_DECREF(now);
    if (time == -1.0 && PyErr_Occurred()) return NULL;
    if (bad == 0 && cf_step_size_ok(h) && cf_time_ok(t, time, b->rtol) &&
        b->step(b->params, b->state, b->io, h) == 0) {
        PyObject *next = PyFloat_FromDouble(t + h);
        if (next == NULL) return NULL;
        int err = PyObject_SetAttr(b->shared, s_time, next);
        Py_DECREF(next);
        if (err || PyObject_SetAttr(b->shared, s_dirty, Py_False) ||
            PyObject_SetAttr(b->shared, s_stale, Py_True))
            return NULL;
        b->steps++;
        Py_RETURN_TRUE;
    }
    return PyObject_Vectorcall(b->py_step, args, nargs, NULL);
}

/* the adapter's set_real for one value */
static int set_one(Binding *b, PyObject *vr, PyObject *value) {
    PyObject *vrs = PyList_New(1), *vals = PyList_New(1);
    if (vrs == NULL || vals == NULL) {
        Py_XDECREF(vrs);
        Py_XDECREF(vals);
        return -1;
    }
    Py_INCREF(vr);
    Py_INCREF(value);
    PyList_SET_ITEM(vrs, 0, vr);
    PyList_SET_ITEM(vals, 0, value);
    PyObject *r = PyObject_CallFunctionObjArgs(b->py_set, vrs, vals, NULL);
    Py_DECREF(vrs);
    Py_DECREF(vals);
    if (r == NULL) return -1;
    Py_DECREF(r);
    return 0;
}

/* a slot's admissible float into the adapter's dicts and the struct */
static int store(Binding *b, const slot *s, PyObject *value, double v) {
    PyObject *values = PyObject_GetAttr(b->shared, s_values);
    PyObject *in = PyObject_GetAttr(b->shared, s_in);
    PyObject *bad = PyObject_GetAttr(b->shared, s_bad);
    int err = values == NULL || in == NULL || bad == NULL ||
              PyObject_SetItem(values, s->name, value) || PyObject_SetItem(in, s->name, value);
    if (!err && PyDict_Check(bad) && PyDict_Contains(bad, s->name) == 1)
        err = PyDict_DelItem(bad, s->name);
    Py_XDECREF(values);
    Py_XDECREF(in);
    Py_XDECREF(bad);
    if (err) return -1;
    if (s->dst != NULL) *s->dst = v;
    return 0;
}

static PyObject *set_real(Binding *b, PyObject *const *args, Py_ssize_t nargs) {
    if (nargs != 2 || !PyList_Check(args[0]) || !PyList_Check(args[1]) ||
        PyList_GET_SIZE(args[0]) != PyList_GET_SIZE(args[1]))
        return PyObject_Vectorcall(b->py_set, args, nargs, NULL);
    PyObject *vrs = args[0], *vals = args[1];
    int stored = 0;
    for (Py_ssize_t i = 0; i < PyList_GET_SIZE(vrs); i++) {
        PyObject *vr = PyList_GET_ITEM(vrs, i), *value = PyList_GET_ITEM(vals, i);
        long k = PyLong_Check(vr) ? PyLong_AsLong(vr) : -1;
        if (k == -1 && PyErr_Occurred()) PyErr_Clear();
        int j = 0 <= k && k < b->n_vr ? b->slot_of_vr[k] : -1;
        if (j >= 0 && PyFloat_CheckExact(value)) {
            const slot *s = &b->slots[j];
            double v = PyFloat_AS_DOUBLE(value);
            if (cf_value_check(v, s->lo, s->hi, s->open_lo) == CF_VALUE_OK) {
                if (store(b, s, value, v)) return NULL;
                stored = 1;
                continue;
            }
        }
        if (set_one(b, vr, value)) return NULL;
    }
    /* once for all values stored here (the adapter's setter marks its own) */
    if (stored && PyObject_SetAttr(b->shared, s_dirty, Py_True)) return NULL;
    Py_RETURN_NONE;
}

static PyObject *get_real(Binding *b, PyObject *const *args, Py_ssize_t nargs) {
    if (nargs != 1 || !PyList_Check(args[0]))
        return PyObject_Vectorcall(b->py_get, args, nargs, NULL);
    PyObject *vrs = args[0];
    Py_ssize_t n = PyList_GET_SIZE(vrs);
    PyObject *res = PyList_New(n);
    if (res == NULL) return NULL;
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *vr = PyList_GET_ITEM(vrs, i);
        long k = PyLong_Check(vr) ? PyLong_AsLong(vr) : -1;
        if (k == -1 && PyErr_Occurred()) PyErr_Clear();
        int j = 0 <= k && k < b->n_vr ? b->out_of_vr[k] : -1;
        PyObject *x = j >= 0 ? PyFloat_FromDouble(b->out[j]) : NULL;
        if (x == NULL) {
            Py_DECREF(res);
            if (j >= 0) return NULL;
            return PyObject_Vectorcall(b->py_get, args, nargs, NULL);
        }
        PyList_SET_ITEM(res, i, x);
    }
    return res;
}

static PyMethodDef binding_methods[] = {
    {"do_step", (PyCFunction)(void (*)(void))do_step, METH_FASTCALL, "doStep"},
    {"set_real", (PyCFunction)(void (*)(void))set_real, METH_FASTCALL, "setReal"},
    {"get_real", (PyCFunction)(void (*)(void))get_real, METH_FASTCALL, "getReal"},
    {NULL, NULL, 0, NULL},
};

static PyObject *get_steps(Binding *b, void *closure) {
    (void)closure;
    return PyLong_FromUnsignedLongLong(b->steps);
}

static PyGetSetDef binding_getset[] = {
    {"steps", (getter)get_steps, NULL, "doSteps taken here (not handed to Python)", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyTypeObject BindingType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "contact_fmu_fmi.Binding",
    .tp_basicsize = sizeof(Binding),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_doc = "do_step, set_real, get_real of a body FMU on its compiled step",
    .tp_traverse = (traverseproc)traverse,
    .tp_clear = (inquiry)clear,
    .tp_dealloc = (destructor)dealloc,
    .tp_methods = binding_methods,
    .tp_getset = binding_getset,
    .tp_weaklistoffset = offsetof(Binding, weakrefs),
};

static void *address(PyObject *x) { return PyLong_AsVoidPtr(x); }

/* bind(shared, owner, py_step, py_set, py_get, step, params, state, io, out, rtol,
 *      slots, outs): slots a list of (vr, name, lo, hi, open_lo, dst address or 0),
 *      outs a list of (vr, index into out). Addresses as ints. */
static PyObject *bind(PyObject *mod, PyObject *args) {
    (void)mod;
    PyObject *shared, *owner, *py_step, *py_set, *py_get, *a_step, *a_params, *a_state, *a_io,
        *a_out, *slots, *outs;
    double rtol;
    if (!PyArg_ParseTuple(args, "OOOOOOOOOOdO!O!", &shared, &owner, &py_step, &py_set, &py_get,
                          &a_step, &a_params, &a_state, &a_io, &a_out, &rtol, &PyList_Type,
                          &slots, &PyList_Type, &outs))
        return NULL;
    Binding *b = PyObject_GC_New(Binding, &BindingType);
    if (b == NULL) return NULL;
    b->shared = Py_NewRef(shared);
    b->owner = Py_NewRef(owner);
    b->py_step = Py_NewRef(py_step);
    b->py_set = Py_NewRef(py_set);
    b->py_get = Py_NewRef(py_get);
    b->slots = NULL;
    b->slot_of_vr = b->out_of_vr = NULL;
    b->n_slots = b->n_vr = 0;
    b->steps = 0;
    b->weakrefs = NULL;
    b->rtol = rtol;
    PyObject_GC_Track(b);
    b->step = (step_fn)address(a_step);
    b->params = address(a_params);
    b->state = address(a_state);
    b->io = address(a_io);
    b->out = (const double *)address(a_out);
    if (PyErr_Occurred()) goto fail;
    /* the table by value reference: as long as the largest one + 1 */
    long top = -1;
    for (int pass = 0; pass < 2; pass++) {
        PyObject *list = pass ? outs : slots;
        for (Py_ssize_t i = 0; i < PyList_GET_SIZE(list); i++) {
            PyObject *row = PyList_GET_ITEM(list, i);
            if (!PyTuple_Check(row) || PyTuple_GET_SIZE(row) < 2) {
                PyErr_SetString(PyExc_TypeError, "bind: rows are tuples (vr, ...)");
                goto fail;
            }
            long k = PyLong_AsLong(PyTuple_GET_ITEM(row, 0));
            if (k < 0) {
                if (!PyErr_Occurred()) PyErr_SetString(PyExc_ValueError, "bind: vr < 0");
                goto fail;
            }
            top = k > top ? k : top;
        }
    }
    b->n_vr = top + 1;
    b->slot_of_vr = PyMem_Malloc(sizeof(int) * (size_t)(b->n_vr + 1));
    b->out_of_vr = PyMem_Malloc(sizeof(int) * (size_t)(b->n_vr + 1));
    b->slots = PyMem_Calloc((size_t)PyList_GET_SIZE(slots) + 1, sizeof(slot));
    if (b->slot_of_vr == NULL || b->out_of_vr == NULL || b->slots == NULL) {
        PyErr_NoMemory();
        goto fail;
    }
    for (Py_ssize_t k = 0; k < b->n_vr; k++) b->slot_of_vr[k] = b->out_of_vr[k] = -1;
    for (Py_ssize_t i = 0; i < PyList_GET_SIZE(slots); i++) {
        slot *s = &b->slots[i];
        long k, dst;
        PyObject *name;
        if (!PyArg_ParseTuple(PyList_GET_ITEM(slots, i), "lUddpl", &k, &name, &s->lo, &s->hi,
                              &s->open_lo, &dst))
            goto fail;
        s->name = Py_NewRef(name);
        s->dst = (double *)dst;
        b->n_slots = i + 1;
        b->slot_of_vr[k] = (int)i;
    }
    for (Py_ssize_t i = 0; i < PyList_GET_SIZE(outs); i++) {
        long k, j;
        if (!PyArg_ParseTuple(PyList_GET_ITEM(outs, i), "ll", &k, &j)) goto fail;
        b->out_of_vr[k] = (int)j;
    }
    return (PyObject *)b;
fail:
    Py_DECREF(b);
    return NULL;
}

/* ---- CoreBinding: the per-step calls of a pythonfmu FMU that carries its model's C core
 *
 * Where the FMU carries the core (instance.c for its model: fmu/slave_core.py), every FMI
 * call goes to it; do_step, set_real and get_real, per step, go here: one C call each to
 * cf_do_step, cf_set_real, cf_get_real of the core library at the addresses given (no
 * Python frame, no argument converted by ctypes). The call's status goes into the shim's
 * cell (the worse of the cell's and the core's: the FMU's answer, pythonfmu_shim.c); the
 * core logs its messages through its own callback (to the adapter's log) before it
 * returns. do_step answers True up to Warning, False from Discard on. Arguments that are
 * not lists of numbers, and every call after close(), go to the adapter's own methods. */
typedef int (*core_step_fn)(void *, double, double);
typedef int (*core_get_fn)(void *, const unsigned *, size_t, double *);
typedef int (*core_set_fn)(void *, const unsigned *, size_t, const double *);

typedef struct {
    PyObject_HEAD
    PyObject *owner;                     /* keeps the core instance alive */
    PyObject *py_step, *py_set, *py_get; /* the adapter's own methods */
    core_step_fn step;
    core_get_fn get;
    core_set_fn set;
    void *inst; /* cf_inst *, NULL once closed */
    int *cell;  /* the shim's status cell */
    PyObject *weakrefs;
} CoreBinding;

static int core_traverse(CoreBinding *b, visitproc visit, void *arg) {
    Py_VISIT(b->owner);
    Py_VISIT(b->py_step);
    Py_VISIT(b->py_set);
    Py_VISIT(b->py_get);
    return 0;
}

static int core_clear(CoreBinding *b) {
    Py_CLEAR(b->owner);
    Py_CLEAR(b->py_step);
    Py_CLEAR(b->py_set);
    Py_CLEAR(b->py_get);
    b->inst = NULL;
    return 0;
}

static void core_dealloc(CoreBinding *b) {
    PyObject_GC_UnTrack(b);
    if (b->weakrefs != NULL) PyObject_ClearWeakRefs((PyObject *)b);
    core_clear(b);
    Py_TYPE(b)->tp_free((PyObject *)b);
}

static void raise_cell(const CoreBinding *b, int status) {
    if (status > *b->cell) *b->cell = status;
}

static PyObject *core_do_step(CoreBinding *b, PyObject *const *args, Py_ssize_t nargs) {
    if (b->inst == NULL || nargs != 2) return PyObject_Vectorcall(b->py_step, args, nargs, NULL);
    double t = PyFloat_AsDouble(args[0]), h = PyFloat_AsDouble(args[1]);
    if (PyErr_Occurred()) {
        PyErr_Clear();
        return PyObject_Vectorcall(b->py_step, args, nargs, NULL);
    }
    int status = b->step(b->inst, t, h);
    if (PyErr_Occurred()) return NULL; /* the log callback failed */
    raise_cell(b, status);
    return PyBool_FromLong(status <= 1);
}

/* n value references of a list, or -1 (anything but non-negative ints below 2^32) */
static int vrs_of(PyObject *list, unsigned *vr, Py_ssize_t n) {
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *x = PyList_GET_ITEM(list, i);
        unsigned long k = PyLong_Check(x) ? PyLong_AsUnsignedLong(x) : (unsigned long)-1;
        if (PyErr_Occurred() || k > 0xFFFFFFFFul) {
            PyErr_Clear();
            return -1;
        }
        vr[i] = (unsigned)k;
    }
    return 0;
}

#define CF_CORE_STACK 32

static PyObject *core_set_real(CoreBinding *b, PyObject *const *args, Py_ssize_t nargs) {
    if (b->inst == NULL || nargs != 2 || !PyList_Check(args[0]) || !PyList_Check(args[1]) ||
        PyList_GET_SIZE(args[0]) != PyList_GET_SIZE(args[1]) ||
        PyList_GET_SIZE(args[0]) > CF_CORE_STACK)
        return PyObject_Vectorcall(b->py_set, args, nargs, NULL);
    Py_ssize_t n = PyList_GET_SIZE(args[0]);
    unsigned vr[CF_CORE_STACK];
    double v[CF_CORE_STACK];
    if (vrs_of(args[0], vr, n)) return PyObject_Vectorcall(b->py_set, args, nargs, NULL);
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *x = PyList_GET_ITEM(args[1], i);
        if (!PyFloat_CheckExact(x)) return PyObject_Vectorcall(b->py_set, args, nargs, NULL);
        v[i] = PyFloat_AS_DOUBLE(x);
    }
    int status = b->set(b->inst, vr, (size_t)n, v);
    if (PyErr_Occurred()) return NULL;
    raise_cell(b, status);
    Py_RETURN_NONE;
}

static PyObject *core_get_real(CoreBinding *b, PyObject *const *args, Py_ssize_t nargs) {
    if (b->inst == NULL || nargs != 1 || !PyList_Check(args[0]) ||
        PyList_GET_SIZE(args[0]) > CF_CORE_STACK)
        return PyObject_Vectorcall(b->py_get, args, nargs, NULL);
    Py_ssize_t n = PyList_GET_SIZE(args[0]);
    unsigned vr[CF_CORE_STACK];
    double v[CF_CORE_STACK];
    if (vrs_of(args[0], vr, n)) return PyObject_Vectorcall(b->py_get, args, nargs, NULL);
    for (Py_ssize_t i = 0; i < n; i++) v[i] = 0.0;
    int status = b->get(b->inst, vr, (size_t)n, v);
    if (PyErr_Occurred()) return NULL;
    raise_cell(b, status);
    PyObject *res = PyList_New(n);
    if (res == NULL) return NULL;
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *x = PyFloat_FromDouble(v[i]);
        if (x == NULL) {
            Py_DECREF(res);
            return NULL;
        }
        PyList_SET_ITEM(res, i, x);
    }
    return res;
}

static PyObject *core_close(CoreBinding *b, PyObject *unused) {
    (void)unused;
    b->inst = NULL;
    Py_RETURN_NONE;
}

static PyMethodDef core_methods[] = {
    {"do_step", (PyCFunction)(void (*)(void))core_do_step, METH_FASTCALL, "doStep"},
    {"set_real", (PyCFunction)(void (*)(void))core_set_real, METH_FASTCALL, "setReal"},
    {"get_real", (PyCFunction)(void (*)(void))core_get_real, METH_FASTCALL, "getReal"},
    {"close", (PyCFunction)core_close, METH_NOARGS, "no more calls into the core"},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject CoreBindingType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "contact_fmu_fmi.CoreBinding",
    .tp_basicsize = sizeof(CoreBinding),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_doc = "do_step, set_real, get_real of a pythonfmu FMU on its C core",
    .tp_traverse = (traverseproc)core_traverse,
    .tp_clear = (inquiry)core_clear,
    .tp_dealloc = (destructor)core_dealloc,
    .tp_methods = core_methods,
    .tp_weaklistoffset = offsetof(CoreBinding, weakrefs),
};

/* bind_core(owner, py_step, py_set, py_get, do_step, set_real, get_real, inst, cell):
 * the functions' (cf_do_step, cf_set_real, cf_get_real), the instance's and the cell's
 * addresses as ints (none 0). */
static PyObject *bind_core(PyObject *mod, PyObject *args) {
    (void)mod;
    PyObject *owner, *py_step, *py_set, *py_get, *a[5];
    if (!PyArg_ParseTuple(args, "OOOOOOOOO", &owner, &py_step, &py_set, &py_get, &a[0], &a[1],
                          &a[2], &a[3], &a[4]))
        return NULL;
    void *p[5];
    for (int i = 0; i < 5; i++) {
        p[i] = address(a[i]);
        if (p[i] == NULL) {
            if (!PyErr_Occurred()) PyErr_SetString(PyExc_ValueError, "bind_core: a NULL address");
            return NULL;
        }
    }
    CoreBinding *b = PyObject_GC_New(CoreBinding, &CoreBindingType);
    if (b == NULL) return NULL;
    b->owner = Py_NewRef(owner);
    b->py_step = Py_NewRef(py_step);
    b->py_set = Py_NewRef(py_set);
    b->py_get = Py_NewRef(py_get);
    /* POSIX: function pointers from data pointers (ctypes' addresses) */
    *(void **)&b->step = p[0];
    *(void **)&b->set = p[1];
    *(void **)&b->get = p[2];
    b->inst = p[3];
    b->cell = (int *)p[4];
    b->weakrefs = NULL;
    PyObject_GC_Track(b);
    return (PyObject *)b;
}

static PyMethodDef module_methods[] = {
    {"bind", bind, METH_VARARGS, "A Binding of an adapter to its compiled step"},
    {"bind_core", bind_core, METH_VARARGS, "A CoreBinding of an adapter to its C core"},
    {NULL, NULL, 0, NULL},
};

static int exec_module(PyObject *m) {
    if (PyType_Ready(&BindingType) < 0) return -1;
    if (PyModule_AddObjectRef(m, "Binding", (PyObject *)&BindingType) < 0) return -1;
    if (PyType_Ready(&CoreBindingType) < 0) return -1;
    if (PyModule_AddObjectRef(m, "CoreBinding", (PyObject *)&CoreBindingType) < 0) return -1;
#define INTERN(v, s) \
    if ((v) == NULL && ((v) = PyUnicode_InternFromString(s)) == NULL) return -1
    INTERN(s_time, "time");
    INTERN(s_bad, "bad");
    INTERN(s_values, "values");
    INTERN(s_in, "inputs");
    INTERN(s_dirty, "dirty");
    INTERN(s_stale, "out_stale");
    return 0;
}

static PyModuleDef_Slot module_slots[] = {{Py_mod_exec, exec_module}, {0, NULL}};

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT, "contact_fmu_fmi", "FMI calls of a body FMU on its compiled step",
    0, module_methods, module_slots, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit_contact_fmu_fmi(void) { return PyModuleDef_Init(&module_def); }
