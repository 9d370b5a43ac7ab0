/* kinengine.model.fastcall: the hot path's input check and frame calls in C (optional accelerator).
 *
 * Pure-Python kinengine spends about 0.3 us per call on its input check and 0.1 us on a Python frame and
 * a threading.local lookup, against about 0.7 us for Pinocchio's own work on a 6-dof arm. This module
 * does the same work without the interpreter:
 *
 *   Ready(dof, limit)      ready(q) -> bool: q is exactly a numpy.ndarray of the canonical native float64
 *                          dtype, one-dimensional, dof entries, C-contiguous, every |q_i| <= limit (NaN and
 *                          inf fail). Same meaning as the pure-Python CoordinateMap.ready.
 *   FrameCalls(...)        .pose(q), .jacobian(q, reference=...), .kinematics(q, reference=...): the same
 *                          Pinocchio calls, in the same order, as the pure-Python closures of
 *                          kinengine/kinematics/handle.py. Anything but the plain case (a q that is not
 *                          ready, other arguments, an unknown reference) is handed to those closures
 *                          unchanged, so every conversion and error message lives in Python, once.
 *
 * numpy arrays are read through numpy's public C API (numpy's headers at build time: numpy is in
 * build-system.requires). Pinocchio is called through its Python functions, so results are bit for bit
 * those of the pure-Python path. Each thread uses its own Pinocchio Data: the one the handle's
 * threading.local holds for it. With the GIL, the last one used is cached with the thread state's unique id
 * (never reused, unlike thread idents); a free-threaded build (Py_GIL_DISABLED) keeps no cache, reads
 * threading.local on every call and declares Py_MOD_GIL_NOT_USED.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>

#ifndef Py_GIL_DISABLED
#define CACHE_DATA 1 /* the GIL serializes every update of a FrameCalls' cached Data */
#endif

static int
is_ready(PyObject *q, Py_ssize_t dof, double limit)
{
    if (!PyArray_CheckExact(q)) {
        return 0;
    }
    PyArrayObject *a = (PyArrayObject *)q;
    if (PyArray_TYPE(a) != NPY_DOUBLE || !PyArray_ISNOTSWAPPED(a) || PyArray_NDIM(a) != 1 ||
        PyArray_DIM(a, 0) != dof || !PyArray_IS_C_CONTIGUOUS(a)) {
        return 0;
    }
    const char *p = PyArray_BYTES(a);
    for (Py_ssize_t i = 0; i < dof; i++) {
        double x;
        memcpy(&x, p + 8 * i, sizeof x); /* any alignment */
        if (!(fabs(x) <= limit)) {       /* false for NaN */
            return 0;
        }
    }
    return 1;
}

/* ---- Ready ------------------------------------------------------------------------------------- */

typedef struct {
    PyObject_HEAD
    Py_ssize_t dof;
    double limit;
} ReadyObject;

static PyObject *
ready_new(PyTypeObject *type, PyObject *args, PyObject *kwds)
{
    Py_ssize_t dof;
    double limit;
    static char *names[] = {"dof", "limit", NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "nd", names, &dof, &limit)) {
        return NULL;
    }
    ReadyObject *self = (ReadyObject *)type->tp_alloc(type, 0);
    if (self != NULL) {
        self->dof = dof;
        self->limit = limit;
    }
    return (PyObject *)self;
}

static PyObject *
ready_check(ReadyObject *self, PyObject *q)
{
    return PyBool_FromLong(is_ready(q, self->dof, self->limit));
}

static PyMethodDef ready_methods[] = {
    {"check", (PyCFunction)ready_check, METH_O, "check(q) -> bool: q may be passed to Pinocchio as it is."},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject ReadyType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "kinengine.model.fastcall.Ready",
    .tp_basicsize = sizeof(ReadyObject),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "Ready(dof, limit): .check(q) is True for a C-contiguous float64 (dof,) array with |q_i| <= limit.",
    .tp_new = ready_new,
    .tp_methods = ready_methods,
};

/* ---- FrameCalls -------------------------------------------------------------------------------- */

/* What a FrameCalls binds, in the order of its keyword arguments: the Pinocchio model, the frame index, the
 * threading.local and the new-Data callable, pinocchio's forwardKinematics, updateFramePlacement and
 * computeFrameJacobian, the reference table (dict), the default and LOCAL references, the pure-Python closures. */
enum { MODEL, FRAME_ID, LOCAL, STATE, FORWARD, PLACE, FRAME_JACOBIAN, REFERENCES, DEFAULT_REFERENCE,
       LOCAL_REFERENCE, SLOW_POSE, SLOW_JACOBIAN, SLOW_KINEMATICS, BOUND };

typedef struct {
    PyObject_HEAD
    Py_ssize_t dof;
    double limit;
    int checking;
    PyObject *bound[BOUND];
    uint64_t cached_thread; /* PyThreadState_GetID of the thread owning cached_data */
    PyObject *cached_data;
} FrameCallsObject;

static PyObject *str_data, *str_homogeneous, *str_reference;

static int
calls_traverse(FrameCallsObject *self, visitproc visit, void *arg)
{
    for (int i = 0; i < BOUND; i++) {
        Py_VISIT(self->bound[i]);
    }
    Py_VISIT(self->cached_data);
    return 0;
}

static int
calls_clear(FrameCallsObject *self)
{
    for (int i = 0; i < BOUND; i++) {
        Py_CLEAR(self->bound[i]);
    }
    Py_CLEAR(self->cached_data);
    return 0;
}

static void
calls_dealloc(FrameCallsObject *self)
{
    PyObject_GC_UnTrack(self);
    calls_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *
calls_new(PyTypeObject *type, PyObject *args, PyObject *kwds)
{
    static char *names[] = {"dof", "limit", "checking", "model", "frame_id", "local", "state", "forward",
                            "place", "frame_jacobian", "references", "default_reference",
                            "local_reference", "slow_pose", "slow_jacobian", "slow_kinematics", NULL};
    Py_ssize_t dof;
    double limit;
    int checking;
    PyObject *o[BOUND];
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "ndpOOOOOOOO!OOOOO", names, &dof, &limit, &checking, &o[0],
                                     &o[1], &o[2], &o[3], &o[4], &o[5], &o[6], &PyDict_Type, &o[7], &o[8],
                                     &o[9], &o[10], &o[11], &o[12])) {
        return NULL;
    }
    FrameCallsObject *self = (FrameCallsObject *)type->tp_alloc(type, 0);
    if (self == NULL) {
        return NULL;
    }
    self->dof = dof;
    self->limit = limit;
    self->checking = checking;
    for (int i = 0; i < BOUND; i++) {
        Py_INCREF(o[i]);
        self->bound[i] = o[i];
    }
    self->cached_data = NULL;
    self->cached_thread = 0;
    return (PyObject *)self;
}

/* This thread's Data (a new reference): the cached one if this thread placed it, else local.data,
 * made by state() the first time a thread asks. */
static PyObject *
thread_data(FrameCallsObject *self)
{
#ifdef CACHE_DATA
    uint64_t thread = PyThreadState_GetID(PyThreadState_Get());
    if (self->cached_data != NULL && self->cached_thread == thread) {
        Py_INCREF(self->cached_data);
        return self->cached_data;
    }
#endif
    PyObject *data = PyObject_GetAttr(self->bound[LOCAL], str_data);
    if (data == NULL) {
        if (!PyErr_ExceptionMatches(PyExc_AttributeError)) {
            return NULL;
        }
        PyErr_Clear();
        data = PyObject_CallNoArgs(self->bound[STATE]);
        if (data == NULL) {
            return NULL;
        }
    }
#ifdef CACHE_DATA
    Py_INCREF(data);
    Py_XSETREF(self->cached_data, data);
    self->cached_thread = thread;
#endif
    return data;
}

static PyObject *
homogeneous(FrameCallsObject *self, PyObject *data)
{
    PyObject *argv[3] = {self->bound[MODEL], data, self->bound[FRAME_ID]};
    PyObject *placement = PyObject_Vectorcall(self->bound[PLACE], argv, 3, NULL);
    if (placement == NULL) {
        return NULL;
    }
    PyObject *T = PyObject_GetAttr(placement, str_homogeneous);
    Py_DECREF(placement);
    return T;
}

static int
forward_kinematics(FrameCallsObject *self, PyObject *data, PyObject *q)
{
    PyObject *argv[3] = {self->bound[MODEL], data, q};
    PyObject *r = PyObject_Vectorcall(self->bound[FORWARD], argv, 3, NULL);
    if (r == NULL) {
        return -1;
    }
    Py_DECREF(r);
    return 0;
}

static PyObject *
frame_jacobian(FrameCallsObject *self, PyObject *data, PyObject *q, PyObject *reference)
{
    PyObject *argv[5] = {self->bound[MODEL], data, q, self->bound[FRAME_ID], reference};
    return PyObject_Vectorcall(self->bound[FRAME_JACOBIAN], argv, 5, NULL);
}

/* The reference frame of a plain call with a ready q (a borrowed reference), or NULL when the call is not
 * plain: (q) or, with ``reference``, (q, reference) or (q, reference=...) naming a reference the table
 * knows. Such calls go to the pure-Python closures, which accept or refuse everything else. */
static PyObject *
plain_call(FrameCallsObject *self, PyObject *const *args, Py_ssize_t nargs, PyObject *kwnames, int reference)
{
    PyObject *given = NULL, *found = self->bound[DEFAULT_REFERENCE];
    if (nargs < 1 || nargs > 1 + reference) {
        return NULL;
    }
    if (kwnames != NULL) {
        if (!reference || nargs != 1 || PyTuple_GET_SIZE(kwnames) != 1 ||
            PyUnicode_Compare(PyTuple_GET_ITEM(kwnames, 0), str_reference) != 0) {
            PyErr_Clear();
            return NULL;
        }
        given = args[1];
    }
    else if (nargs == 2) {
        given = args[1];
    }
    if (given != NULL) {
        if (!PyUnicode_CheckExact(given) || (found = PyDict_GetItemWithError(self->bound[REFERENCES], given)) == NULL) {
            PyErr_Clear();
            return NULL;
        }
    }
    if (self->checking && !is_ready(args[0], self->dof, self->limit)) {
        return NULL;
    }
    return found;
}

enum { POSE, JACOBIAN, KINEMATICS };

static PyObject *
pose_at(FrameCallsObject *self, PyObject *data, PyObject *q)
{
    return forward_kinematics(self, data, q) == 0 ? homogeneous(self, data) : NULL;
}

static PyObject *
kinematics_at(FrameCallsObject *self, PyObject *data, PyObject *q, PyObject *reference)
{
    PyObject *T = NULL, *J = NULL, *result = NULL;
    if (reference == self->bound[LOCAL_REFERENCE]) { /* Pinocchio's LOCAL frame Jacobian does not place the joints */
        if ((T = pose_at(self, data, q)) != NULL) {
            J = frame_jacobian(self, data, q, reference);
        }
    }
    else if ((J = frame_jacobian(self, data, q, reference)) != NULL) {
        T = homogeneous(self, data);
    }
    if (T != NULL && J != NULL) {
        result = PyTuple_Pack(2, T, J);
    }
    Py_XDECREF(T);
    Py_XDECREF(J);
    return result;
}

/* One frame call of this kind: a plain call runs here on this thread's Data, any other goes to the
 * pure-Python closure of the same kind unchanged. */
static PyObject *
frame_call(FrameCallsObject *self, PyObject *const *args, Py_ssize_t nargs, PyObject *kwnames, int kind)
{
    PyObject *reference = plain_call(self, args, nargs, kwnames, kind != POSE);
    if (reference == NULL) {
        return PyObject_Vectorcall(self->bound[SLOW_POSE + kind], args, nargs, kwnames);
    }
    PyObject *data = thread_data(self);
    if (data == NULL) {
        return NULL;
    }
    PyObject *result = kind == POSE       ? pose_at(self, data, args[0])
                       : kind == JACOBIAN ? frame_jacobian(self, data, args[0], reference)
                                          : kinematics_at(self, data, args[0], reference);
    Py_DECREF(data);
    return result;
}

static PyObject *
calls_pose(FrameCallsObject *self, PyObject *const *args, Py_ssize_t nargs, PyObject *kwnames)
{
    return frame_call(self, args, nargs, kwnames, POSE);
}

static PyObject *
calls_jacobian(FrameCallsObject *self, PyObject *const *args, Py_ssize_t nargs, PyObject *kwnames)
{
    return frame_call(self, args, nargs, kwnames, JACOBIAN);
}

static PyObject *
calls_kinematics(FrameCallsObject *self, PyObject *const *args, Py_ssize_t nargs, PyObject *kwnames)
{
    return frame_call(self, args, nargs, kwnames, KINEMATICS);
}

static PyMethodDef calls_methods[] = {
    {"pose", (PyCFunction)(void (*)(void))calls_pose, METH_FASTCALL | METH_KEYWORDS, "pose(q) -> T_IF (4, 4)"},
    {"jacobian", (PyCFunction)(void (*)(void))calls_jacobian, METH_FASTCALL | METH_KEYWORDS,
     "jacobian(q, reference='local_world_aligned') -> J (6, dof)"},
    {"kinematics", (PyCFunction)(void (*)(void))calls_kinematics, METH_FASTCALL | METH_KEYWORDS,
     "kinematics(q, reference='local_world_aligned') -> (T_IF, J)"},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject FrameCallsType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "kinengine.model.fastcall.FrameCalls",
    .tp_basicsize = sizeof(FrameCallsObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_doc = "One frame's pose, jacobian and kinematics calls (see the module doc).",
    .tp_new = calls_new,
    .tp_dealloc = (destructor)calls_dealloc,
    .tp_traverse = (traverseproc)calls_traverse,
    .tp_clear = (inquiry)calls_clear,
    .tp_methods = calls_methods,
};

/* ---- module ------------------------------------------------------------------------------------ */

static int
fastcall_exec(PyObject *module)
{
    if (_import_array() < 0) { /* numpy's C API table */
        return -1;
    }
    if (str_data == NULL) {
        str_data = PyUnicode_InternFromString("data");
        str_homogeneous = PyUnicode_InternFromString("homogeneous");
        str_reference = PyUnicode_InternFromString("reference");
        if (str_data == NULL || str_homogeneous == NULL || str_reference == NULL) {
            return -1;
        }
    }
    if (PyType_Ready(&ReadyType) < 0 || PyType_Ready(&FrameCallsType) < 0) {
        return -1;
    }
    /* PyModule_AddObjectRef keeps no reference when it fails: nothing leaks on a failed init */
    if (PyModule_AddObjectRef(module, "Ready", (PyObject *)&ReadyType) < 0 ||
        PyModule_AddObjectRef(module, "FrameCalls", (PyObject *)&FrameCallsType) < 0) {
        return -1;
    }
    return 0;
}

static PyModuleDef_Slot fastcall_slots[] = {
    {Py_mod_exec, fastcall_exec},
#ifdef Py_mod_gil
    /* Ready and FrameCalls are immutable after construction; the Data cache exists only with the GIL. */
    {Py_mod_gil, Py_MOD_GIL_NOT_USED},
#endif
    {0, NULL},
};

static struct PyModuleDef fastcall_module = {
    PyModuleDef_HEAD_INIT,
    .m_name = "kinengine.model.fastcall",
    .m_doc = "The hot path's input check and frame calls in C (see kinengine/model/accelerator.py).",
    .m_size = 0,
    .m_slots = fastcall_slots,
};

PyMODINIT_FUNC
PyInit_fastcall(void)
{
    return PyModuleDef_Init(&fastcall_module);
}
