/* ---- the single-state entry points as a CPython extension (no ctypes) ----
   rhs(y, pext_address) -> dy (2n); field(y, a) -> (dy, power) (2n + 1);
   evaluate(y, a) -> (dy, lam, power) (2n + m + 1). y: a contiguous float64
   array of length 2n (field: also 2n + 1, the last entry ignored); for
   anything else None is returned (the caller converts). On failure the
   status (int) is returned instead of the array. */
#ifdef NHHAM_PYEXT
static PyObject *ext_call(PyObject *const *args, Py_ssize_t nargs, int width, int allow_work) {
    if (nargs != 2) { PyErr_SetString(PyExc_TypeError, "expected (y, pext_address)"); return NULL; }
    const double *pext = (const double *)PyLong_AsVoidPtr(args[1]);
    if (pext == NULL) {
        if (!PyErr_Occurred()) PyErr_SetString(PyExc_ValueError, "null parameter address");
        return NULL;
    }
    /* Anything but one contiguous native float64 state: None (the caller's job). */
    if (!PyArray_Check(args[0])) Py_RETURN_NONE;
    PyArrayObject *y = (PyArrayObject *)args[0];
    if (PyArray_NDIM(y) != 1 || PyArray_TYPE(y) != NPY_DOUBLE || !PyArray_ISCARRAY_RO(y)
        || !PyArray_ISNOTSWAPPED(y)) Py_RETURN_NONE;
    const npy_intp len = PyArray_DIM(y, 0);
    if (len != 2 * NQ && !(allow_work && len == NZ)) Py_RETURN_NONE;
    npy_intp dims[1] = {width};
    PyArrayObject *out = (PyArrayObject *)PyArray_SimpleNew(1, dims, NPY_DOUBLE);
    if (out == NULL) return NULL;
    double *o = (double *)PyArray_DATA(out), lam[NCX], pw;
    double *ol = width >= NRES ? o + 2 * NQ : lam;
    double *op = width >= 2 * NQ + 1 ? o + width - 1 : &pw;
    int status = rhs_one((const double *)PyArray_DATA(y), pext, pext[NPAR], pext[NPAR + 1],
                         o, ol, op);
    if (status) { Py_DECREF(out); return PyLong_FromLong(status); }
    return (PyObject *)out;
}
static PyObject *ext_rhs(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self; return ext_call(args, nargs, 2 * NQ, 0);
}
static PyObject *ext_field(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self; return ext_call(args, nargs, 2 * NQ + 1, 1);
}
static PyObject *ext_evaluate(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self; return ext_call(args, nargs, NRES, 0);
}
static PyMethodDef ext_methods[] = {
    {"rhs", (PyCFunction)(void (*)(void))ext_rhs, METH_FASTCALL, "dy at one state"},
    {"field", (PyCFunction)(void (*)(void))ext_field, METH_FASTCALL, "(dy, power)"},
    {"evaluate", (PyCFunction)(void (*)(void))ext_evaluate, METH_FASTCALL, "(dy, lam, power)"},
    {NULL, NULL, 0, NULL}
};
static struct PyModuleDef ext_module = {PyModuleDef_HEAD_INIT, "nhham_ext", NULL, -1, ext_methods,
                                        NULL, NULL, NULL, NULL};
PyMODINIT_FUNC PyInit_nhham_ext(void) {
    import_array();
    return PyModule_Create(&ext_module);
}
#endif
