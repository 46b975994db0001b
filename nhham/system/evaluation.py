"""From sympy expressions to numbers: the one route of the exact layers.

:func:`numeric_function` compiles expressions once into a Python function of numbers,
with numpy (float64) or mpmath (arbitrary precision) as the numeric module;
:class:`Lambdified` keeps one compiled function per :class:`Backend` and evaluates a
list of expressions to an array. The submanifold decisions, the Legendre map's numeric
helpers and the sampled checks all go through them. An exact backend (residues modulo p,
:class:`nhham.lagrangian.linalg.ModularBackend`) evaluates the expressions itself, at
exact points, with no compilation. The generated kernels of :mod:`nhham.numerics.codegen`
are the other, compiled, route (C and numpy code for integration).
"""

from __future__ import annotations

import functools
from typing import Callable, Sequence

import mpmath
import numpy as np
import sympy as sp

from nhham.settings import Precision

__all__ = ["numeric_function", "numeric_module", "Backend", "Lambdified", "flatten",
           "object_solve"]


def numeric_module(precision: int | None) -> str:
    """``"numpy"`` for float64 (precision None), ``"mpmath"`` otherwise."""
    return "numpy" if precision is None else "mpmath"


def numeric_function(args: Sequence, exprs, precision: int | None = None,
                     cse: bool = False) -> Callable:
    """``f(*values)`` evaluating ``exprs`` (an expression, a list or a Matrix) at ``args``.

    Parameters
    ----------
    args : sequence of sympy.Symbol
        The arguments, in order.
    exprs : sympy.Expr, list or sympy.Matrix
        What to evaluate; the result has the same nesting (numpy arrays for matrices).
    precision : int or None
        None: numpy, float64; an integer: mpmath (the caller sets ``mpmath.mp.dps``).
    cse : bool
        Common subexpressions extracted once (worth it for long lists).
    """
    from sympy.printing.numpy import NumPyPrinter
    from sympy.printing.pycode import MpmathPrinter

    # The terms of a sum are printed as they are stored: sorting them (sympy's default)
    # is most of the cost of printing the bicycle's matrices.
    printer = (NumPyPrinter if precision is None else MpmathPrinter)(
        {"fully_qualified_modules": False, "inline": True, "allow_unknown_functions": True,
         "user_functions": {}, "order": "none"})
    modules = numeric_module(precision)
    f = sp.lambdify(list(args), exprs, cse=cse, printer=printer,
                    modules=[_numpy_namespace()] if modules == "numpy" else modules)
    if precision is not None:
        return f

    def ieee(*values):
        # numpy numbers, not Python floats: y**(-1.0) at y = 0 is inf (which the callers
        # read as "not finite there"), not a ZeroDivisionError
        return f(*[np.float64(v) if type(v) is float else v for v in values])
    return ieee


@functools.cache
def _numpy_namespace() -> dict:
    """The names lambdify's ``"numpy"`` module gives its functions, without its ``from
    numpy import *``: that star import loads every submodule numpy keeps lazy (f2py,
    testing, ...; 0.4 s of a command's start) for names no generated code uses."""
    from sympy.utilities.lambdify import NUMPY_DEFAULT, NUMPY_TRANSLATIONS

    loaded = {n: getattr(np, n) for n in np.__all__ if n in vars(np)}
    namespace = {"numpy": np, **loaded,
                 **{n: getattr(np.linalg, n) for n in np.linalg.__all__}, **NUMPY_DEFAULT}
    namespace.update({k: namespace[v] for k, v in NUMPY_TRANSLATIONS.items()})
    return namespace


# ======================================================================
# Numeric backend shared by the Hamiltonian side, classification and
# cross-check: float64 numpy arrays, or numpy object arrays of mpmath.mpf.
# ======================================================================
class Backend:
    """Dense linear algebra in float64 (``precision=None``) or mpmath digits.

    Arrays are numpy arrays: ``float`` dtype, or ``object`` dtype holding
    ``mpmath.mpf`` (object arrays support ``@`` through Python arithmetic).
    """

    def __init__(self, precision: int | None):
        self.precision = precision
        self.module = "numpy" if precision is None else "mpmath"

    @property
    def label(self) -> str:
        return Precision(self.precision).label

    def context(self):
        if self.precision is None:
            return np.errstate(all="ignore")
        return mpmath.workdps(self.precision + 5)

    def default_tol(self) -> float:
        return Precision(self.precision).tolerance

    def scalar(self, x):
        return float(x) if self.precision is None else mpmath.mpf(x)

    def vector(self, xs) -> np.ndarray:
        if self.precision is None:
            return np.asarray(flatten(xs), dtype=float)
        return np.array([mpmath.mpf(x) for x in flatten(xs)], dtype=object)

    def matrix(self, rows, shape=None) -> np.ndarray:
        if isinstance(rows, mpmath.matrix):
            rows = rows.tolist()
        if self.precision is None:
            out = np.asarray(rows, dtype=float)
        else:
            out = np.array([[mpmath.mpf(x) for x in row] for row in rows], dtype=object) \
                if len(rows) else np.zeros((0, 0), dtype=object)
        if shape is not None:
            out = out.reshape(shape)
        return out

    def zeros(self, *shape) -> np.ndarray:
        if self.precision is None:
            return np.zeros(shape)
        out = np.empty(shape, dtype=object)
        out.fill(mpmath.mpf(0))
        return out

    def norm(self, x):
        if x.size == 0:
            return self.scalar(0)
        if self.precision is None:
            return float(np.max(np.abs(x)))
        return max(abs(e) for e in x.ravel())

    def evaluate(self, f: "Lambdified", values: Sequence) -> np.ndarray:
        """``f``'s expressions at ``values``, a flat array of this backend's numbers."""
        if not f.exprs:
            return self.zeros(len(f.exprs))
        out = f.compiled(self)(*values)
        # Real parts: sqrt of a negative number on a bad sample is complex;
        # such samples are rejected by finiteness checks of the callers.
        if self.precision is None:
            return np.array([complex(o).real for o in out], dtype=float)
        return np.array([mpmath.mpf(mpmath.re(mpmath.mpmathify(o))) for o in out],
                        dtype=object)

    def solve(self, A: np.ndarray, B: np.ndarray) -> np.ndarray:
        """A^{-1} B for a square A (vector or matrix B)."""
        if self.precision is None:
            return np.linalg.solve(A, B)
        return object_solve(A, B)


def flatten(xs):
    if isinstance(xs, mpmath.matrix):
        return [xs[i, j] for i in range(xs.rows) for j in range(xs.cols)]
    if isinstance(xs, np.ndarray):
        return list(xs.ravel())
    out = []
    for x in xs:
        if isinstance(x, (list, tuple, np.ndarray, mpmath.matrix)):
            out.extend(flatten(x))
        else:
            out.append(x)
    return out


def object_solve(A, B):
    """Gaussian elimination with partial pivoting on object (mpmath) arrays."""
    n = A.shape[0]
    vec = B.ndim == 1
    M = np.concatenate([A.astype(object), (B.reshape(n, 1) if vec else B).astype(object)], axis=1)
    for k in range(n):
        piv = max(range(k, n), key=lambda i: abs(M[i, k]))
        if M[piv, k] == 0:
            raise ZeroDivisionError("singular matrix")
        if piv != k:
            M[[k, piv]] = M[[piv, k]]
        for i in range(k + 1, n):
            f = M[i, k] / M[k, k]
            if f != 0:
                M[i, k:] = M[i, k:] - f * M[k, k:]
    X = np.empty((n, M.shape[1] - n), dtype=object)
    for i in range(n - 1, -1, -1):
        X[i] = (M[i, n:] - M[i, i + 1:n] @ X[i + 1:]) / M[i, i] if i + 1 < n else M[i, n:] / M[i, i]
    return X[:, 0] if vec else X


class Lambdified:
    """A list of expressions compiled once per backend, evaluated to an array.

    Parameters
    ----------
    args : sequence of sympy.Symbol
    exprs : sequence of sympy.Expr
    shape : tuple
        Shape of the result array.
    """

    def __init__(self, args: Sequence, exprs: Sequence, shape: tuple):
        self.args = tuple(args)
        self.exprs = [sp.sympify(e) for e in exprs]
        self.shape = shape
        self._compiled: dict = {}

    def __call__(self, backend: Backend, values: Sequence) -> np.ndarray:
        return backend.evaluate(self, values).reshape(self.shape)

    def compiled(self, backend: Backend) -> Callable:
        """The function of numbers for ``backend``'s module, compiled on first use."""
        fn = self._compiled.get(backend.module)
        if fn is None:
            fn = numeric_function(self.args, self.exprs, backend.precision,
                                  cse=len(self.exprs) > 4)
            self._compiled[backend.module] = fn
        return fn
