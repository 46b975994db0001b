"""Code generation: the one bridge from sympy to numbers.

:func:`numeric_model` turns the symbolic pieces of a :class:`~nhham.System`
(``DESIGN.md`` §2, :class:`~nhham.lagrangian.DynamicsIngredients`) into a
:class:`~nhham.numeric.NumericModel` whose methods take arrays of states and
never touch sympy.

What is generated ("kernels"; each one is a single ``sympy.cse`` over all of
its outputs, so common subexpressions are shared; sin/cos of sums of
coordinates whose own sin/cos are computed anyway are expanded first, see
:func:`_expand_angle_sums`):

``saddle(q, v)``
    W (n x n), forcing F (n), mu (m x n), drift (m), h (m), g (k holonomic).
    The default right-hand side solves ``[[W, mu^T], [mu, 0]] [a; lambda] =
    [F; -drift]`` at run time: no symbolic inverse is ever formed.
``geometry(q)``
    W, mu, h, g: what projection onto M_1 and the structure-preserving
    integrator need.
``energy(q, v)``
    E_L.
``lq(q, v)``, ``jphi(q, v)``
    dL/dq (n) and d(phi)/dq (m x n), for the Newton iterations of the
    nonholonomic RATTLE scheme.
``closed(q, v)``
    Only for ``path="closed_form"``: the accelerations of the symbolic
    projected field P(xi_L) and the symbolic multipliers, so the two paths can
    be compared.

Each kernel is printed three ways: scalar Python on floats (``math``; the
fastest pure-Python single-state path), numpy on columns of a batch (shape
(k,) per symbol, no Python loop over states), and mpmath (for the
high-precision reference integrator). The kernels are also printed as C and
compiled with the system compiler into a cache directory keyed by a hash of
the source, together with

- the saddle solve ``ksolve``: Cholesky of W and of the Schur complement
  mu W^-1 mu^T (W is positive definite for mechanical Lagrangians), LU with
  partial pivoting of the scaled saddle matrix when W is indefinite or nearly
  singular;
- the right-hand side for one state and for a batch (the loop over states in
  C), the nonholonomic RATTLE loop for constant W, and scipy's explicit
  Runge-Kutta methods (RK23, RK45, DOP853) as one loop with projection onto
  M_1 (``nhham_erk``, used by :func:`nhham.integrate.simulate`);
- when the Python and numpy headers are installed, CPython entry points for
  the single-state calls (no ctypes on the hot path).

When no compiler works the model falls back to numpy and says why
(``model.backend_note``). ``$NHHAM_CFLAGS`` adds compiler flags (e.g.
``-O3 -march=native``; the default ``-O2`` is portable).

Parameters stay symbolic in the generated code and are passed at run time
(``p``), so a parameter sweep reuses one compiled library.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
import warnings
from functools import lru_cache

import sympy as sp
from sympy.printing.c import C99CodePrinter
from sympy.printing.numpy import NumPyPrinter
from sympy.printing.pycode import MpmathPrinter, PythonCodePrinter

from nhham.errors import ComputationError, MissingParameterValueError
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.numerics.model import CompiledRHS, GeneratedKernels, NumericModel, NumericsWarning

__all__ = ["numeric_model", "generate_sources", "compile_c", "c_compiler"]

_BACKENDS = ("numpy", "c", "auto")
_PATHS = ("saddle", "closed_form")


# ------------------------------------------------------------------ public
def numeric_model(system, *, backend: str = "auto", path: str = "saddle",
                  parameters=None, cache_dir=None) -> NumericModel:
    """Generate the numeric model of ``system``.

    Parameters
    ----------
    system : nhham.System
    backend : {"auto", "numpy", "c"}, optional
        ``"numpy"``: generated Python/numpy only. ``"c"``: also compile the
        right-hand side with the system C compiler; if that is impossible a
        :class:`~nhham.numeric.NumericsWarning` is issued and numpy is used.
        ``"auto"`` (default): C when a compiler works, numpy otherwise
        (silently; ``model.backend_note`` says why).
    path : {"saddle", "closed_form"}, optional
        ``"saddle"`` (default) solves the saddle-point system numerically at
        every evaluation. ``"closed_form"`` evaluates the symbolic closed form
        of P(xi_L) (costly to derive for large systems; meant for comparison).
    parameters : mapping of str to float, optional
        Values overriding ``system.parameter_values``.
    cache_dir : str, optional
        Where compiled libraries are kept (default ``$NHHAM_CACHE`` or
        ``~/.cache/nhham``).

    Returns
    -------
    NumericModel

    Raises
    ------
    MissingParameterValueError
        When a parameter used by the system has no numeric value.
    ValueError
        For an unknown backend or path.
    """
    if backend not in _BACKENDS:
        raise ValueError(f"backend must be one of {_BACKENDS}, got {backend!r}")
    if path not in _PATHS:
        raise ValueError(f"path must be one of {_PATHS}, got {path!r}")
    values = _parameter_values(system, parameters)
    sources = generate_sources(system, path=path)
    kernels = GeneratedKernels.from_source(sources["python"], sources["layout"])
    compiled, note = None, "numpy backend requested"
    if backend in ("c", "auto"):
        compiled, note = _try_compile(sources, cache_dir)
        if compiled is None and backend == "c":
            warnings.warn(f"C backend unavailable ({note}); using numpy", NumericsWarning,
                          stacklevel=2)
    return NumericModel(
        layout=sources["layout"],
        kernels=kernels,
        parameter_values=tuple(values[p.name] for p in system.parameters),
        compiled=compiled,
        path=path,
        backend_note=note,
        python_source=sources["python"],
        c_source=sources["c"],
    )


def c_compiler() -> str | None:
    """Path of the C compiler used for the compiled backend, or None.

    ``$CC`` is used when set, else ``cc``. Setting ``NHHAM_NO_CC=1`` disables
    the compiled backend (used to test the numpy fallback).
    """
    if os.environ.get("NHHAM_NO_CC"):
        return None
    return shutil.which(os.environ.get("CC", "cc"))


# ---------------------------------------------------------------- sources
def generate_sources(system, path: str = "saddle") -> dict:
    """Generated source texts and the layout describing them.

    Returns
    -------
    dict
        ``python`` (module text with scalar, batch and mpmath kernels), ``c``
        (C text of the right-hand side), ``layout`` (plain dict: sizes, names
        and flags that :class:`~nhham.numeric.NumericModel` needs).
    """
    return _generate_sources(_SystemKey(system), path)


class _SystemKey:
    """Hash a System by identity so that sources are generated once per system."""

    def __init__(self, system):
        self.system = system

    def __hash__(self):
        return id(self.system)

    def __eq__(self, other):
        return isinstance(other, _SystemKey) and other.system is self.system


@lru_cache(maxsize=64)
def _generate_sources(key: _SystemKey, path: str) -> dict:
    system = key.system
    geom = lagrangian_geometry(system)
    ing = geom.ingredients
    n, m, k = system.n, system.m, len(system.holonomic)
    rename = _renaming(system)

    def R(expr):
        return sp.sympify(expr).xreplace(rename)

    W = [R(ing.W[i, j]) for i in range(n) for j in range(n)]
    F = [R(e) for e in ing.forcing]
    mu = [R(ing.mu[i, j]) for i in range(m) for j in range(n)]
    drift = [R(e) for e in ing.drift]
    h = [R(e) for e in system.h]
    g = [R(e) for e in system.holonomic]
    qs = [rename[q] for q in system.coordinates]
    vs = [rename[v] for v in system.velocities]
    L = R(system.lagrangian)
    lq = [sp.diff(L, q) for q in qs]
    phi = [R(e) for e in system.phi]
    jphi = [sp.diff(f, q) for f in phi for q in qs]

    kernels = {
        "saddle": ("qv", W + F + mu + drift + h + g),
        "geometry": ("q", W + mu + h + g),
        "energy": ("qv", [R(geom.energy)]),
        "lq": ("qv", lq),
        "jphi": ("qv", jphi),
    }
    if path == "closed_form":
        field = geom.projected_field
        acc = [R(field[n + i]) for i in range(n)]
        lam = [R(e) for e in geom.multipliers]
        kernels["closed"] = ("qv", acc + lam)

    printed = {name: _cse(_expand_angle_sums(outputs, qs))
               for name, (_, outputs) in kernels.items()}
    python = _python_module(kernels, printed, n, len(system.parameters))
    c = _c_module(printed, n, m, k, len(system.parameters), path)
    layout = {
        "n": n, "m": m, "k": k,
        "coordinate_names": tuple(q.name for q in system.coordinates),
        "velocity_names": tuple(v.name for v in system.velocities),
        "parameter_names": tuple(p.name for p in system.parameters),
        "constraint_labels": tuple(system.constraint_labels),
        "holonomic_labels": tuple(f"holonomic[{i}]" for i in range(k)),
        "constant_W": not any(e.free_symbols & set(qs) for e in W),
        "quadratic": _is_quadratic(system),
        "linear_constraints": all(sp.simplify(e) == 0 for e in h),
        "name": system.name,
        "kernels": tuple(kernels),
    }
    return {"python": python, "c": c, "layout": layout}


def _renaming(system) -> dict:
    """Map user symbols to safe generated names q0.., v0.., p0..

    User names may be Python keywords or C identifiers in use (``lambda``,
    ``I``); the generated code never sees them.
    """
    rename = {q: sp.Symbol(f"q{i}", real=True) for i, q in enumerate(system.coordinates)}
    rename.update({v: sp.Symbol(f"v{i}", real=True) for i, v in enumerate(system.velocities)})
    rename.update({p: sp.Symbol(f"p{i}", real=True) for i, p in enumerate(system.parameters)})
    return rename


def _is_quadratic(system) -> bool:
    """True when L = 1/2 v^T W(q) v - V(q) (no linear-in-v terms, W free of v)."""
    W = system.hessian
    vs = set(system.velocities)
    if any(e.free_symbols & vs for e in W):
        return False
    v = sp.Matrix(system.velocities)
    p = sp.Matrix([sp.diff(system.lagrangian, s) for s in system.velocities])
    return all(sp.simplify(e) == 0 for e in (p - W * v))


def _parameter_values(system, overrides) -> dict:
    """Numeric values for every declared parameter (overrides by name)."""
    overrides = dict(overrides or {})
    names = {p.name for p in system.parameters}
    unknown = sorted(set(overrides) - names)
    if unknown:
        raise MissingParameterValueError(
            f"parameters: {', '.join(unknown)} are not parameters of the system "
            f"(known: {', '.join(sorted(names)) or 'none'})")
    values = {p.name: v for p, v in system.parameter_values.items()}
    values.update({k: float(v) for k, v in overrides.items()})
    missing = [p.name for p in system.parameters if p.name not in values]
    if missing:
        raise MissingParameterValueError(
            f"parameters: no numeric value for {', '.join(missing)} (needed for numbers)")
    return values


def _expand_angle_sums(outputs, coordinates, max_terms=3):
    """sin/cos of sums of coordinates by the addition formulas, when that saves calls.

    A chain of N links has sin and cos of every theta_i and also of every
    difference theta_i - theta_j: N (N + 1) sincos calls per evaluation where N
    suffice. ``sin(a +- b)`` and ``cos(a +- b)`` (up to ``max_terms`` summands,
    coefficients +-1) are rewritten as sums of products of sin and cos of the
    summands, but only when every summand's own sin or cos is computed anyway
    (so no new call appears). Exact in exact arithmetic; in floating point the
    result has an absolute error of a few ulps instead of a relative one, which
    is what the saddle solve needs (its backward error is normwise).
    """
    coords = set(coordinates)
    trig = set()
    for e in outputs:
        trig |= sp.sympify(e).atoms(sp.sin, sp.cos)
    base = {f.args[0] for f in trig if f.args[0] in coords}

    def split(arg):
        if not isinstance(arg, sp.Add) or len(arg.args) > max_terms:
            return None
        terms = []
        for t in arg.args:
            c, s = t.as_coeff_Mul()
            if s not in base or c not in (1, -1):
                return None
            terms.append((int(c), s))
        return terms

    def sc(terms):
        """(sin, cos) of sum(c * s) by the addition formulas."""
        c, s = terms[0]
        sin, cos = c * sp.sin(s), sp.cos(s)
        for c, s in terms[1:]:
            sin2, cos2 = c * sp.sin(s), sp.cos(s)
            sin, cos = sin * cos2 + cos * sin2, cos * cos2 - sin * sin2
        return sin, cos

    rules = {}
    for f in trig:
        terms = split(f.args[0])
        if terms:
            sin, cos = sc(terms)
            rules[f] = sin if isinstance(f, sp.sin) else cos
    if not rules:
        return list(outputs)
    return [sp.sympify(e).xreplace(rules) for e in outputs]


def _cse(outputs):
    """Common subexpressions shared by all outputs of one kernel."""
    temps, reduced = sp.cse(list(outputs), symbols=sp.numbered_symbols("_t"), order="none")
    return temps, reduced


# ------------------------------------------------------------- python text
class _ScalarPrinter(PythonCodePrinter):
    """Floats via ``math``; integer powers stay ``**`` (fast on floats)."""


class _BatchPrinter(NumPyPrinter):
    """Columns of a batch via ``numpy`` ufuncs."""


def _python_module(kernels, printed, n, npar) -> str:
    lines = [
        '"""Generated by nhham.codegen; do not edit. Kernels on scalars, batches, mpmath."""',
        "import math",
        "import numpy",
        "import mpmath",
        "",
    ]
    unpack_qv = _unpack(n, "qv")
    unpack_q = _unpack(n, "q")
    for name, (args, _) in kernels.items():
        temps, reduced = printed[name]
        unpack = unpack_qv if args == "qv" else unpack_q
        lines += _py_scalar(name, unpack, npar, temps, reduced, _ScalarPrinter(
            {"fully_qualified_modules": True}), suffix="scalar")
        lines += _py_scalar(name, unpack, npar, temps, reduced, MpmathPrinter(
            {"fully_qualified_modules": True}), suffix="mp")
        lines += _py_batch(name, unpack, npar, temps, reduced)
    return "\n".join(lines) + "\n"


def _unpack(n, args):
    names = [f"q{i}" for i in range(n)]
    if args == "qv":
        names += [f"v{i}" for i in range(n)]
    return names


def _param_line(npar, indent="    "):
    if npar == 0:
        return []
    return [indent + ", ".join(f"p{i}" for i in range(npar)) + (",  = p" if npar == 1 else " = p")]


def _py_scalar(name, unpack, npar, temps, reduced, printer, suffix):
    out = [f"def {name}_{suffix}(y, p):"]
    out.append("    " + ", ".join(unpack) + (",  = y" if len(unpack) == 1 else " = y")
               + f"[:{len(unpack)}]")
    out += _param_line(npar)
    for sym, expr in temps:
        out.append(f"    {sym} = {printer.doprint(expr)}")
    out.append("    return [" + ", ".join(printer.doprint(e) for e in reduced) + "]")
    out.append("")
    return out


def _py_batch(name, unpack, npar, temps, reduced):
    printer = _BatchPrinter({"fully_qualified_modules": True})
    out = [f"def {name}_batch(Y, p, out):",
           "    # Y: (2n or n, k) contiguous rows; out: (len(outputs), k), zero on entry."]
    for i, s in enumerate(unpack):
        out.append(f"    {s} = Y[{i}]")
    out += _param_line(npar)
    for sym, expr in temps:
        out.append(f"    {sym} = {printer.doprint(expr)}")
    for j, e in enumerate(reduced):
        if e == 0:
            continue  # out is zero on entry
        out.append(f"    out[{j}] = {printer.doprint(e)}")
    out.append("    return out")
    out.append("")
    return out


# ------------------------------------------------------------------ C text
class _CPrinter(C99CodePrinter):
    """C99 with small integer powers expanded to products (exact, faster)."""

    def _print_Pow(self, expr):
        b, e = expr.as_base_exp()
        if e.is_Integer and 2 <= int(e) <= 4:
            base = self.parenthesize(b, 100)
            return "(" + "*".join([base] * int(e)) + ")"
        if e.is_Integer and -4 <= int(e) <= -1:
            base = self.parenthesize(b, 100)
            return "(1.0/(" + "*".join([base] * -int(e)) + "))"
        return super()._print_Pow(expr)


def _c_kernel(fname, printed, n, npar, with_v=True):
    temps, reduced = printed
    pr = _CPrinter()
    body = [f"static void {fname}(const double *y, const double *p, double *out) {{"]
    for i in range(npar):
        body.append(f"    const double p{i} = p[{i}]; (void)p{i};")
    for i in range(n):
        body.append(f"    const double q{i} = y[{i}]; (void)q{i};")
    if with_v:
        for i in range(n):
            body.append(f"    const double v{i} = y[{n + i}]; (void)v{i};")
    for sym, expr in temps:
        body.append(f"    const double {sym} = {pr.doprint(expr)};")
    for j, e in enumerate(reduced):
        body.append(f"    out[{j}] = {pr.doprint(e)};")
    body.append("}")
    return body


def _c_module(printed, n, m, k, npar, path) -> str:
    """C source of the right-hand side: saddle kernel + scaled LU solve.

    Layout of the saddle kernel outputs (``out``): W (n*n, row-major), F (n),
    mu (m*n), drift (m), h (m), g (k).
    """
    N = n + m
    head = textwrap.dedent(f"""\
        /* Generated by nhham.codegen; do not edit. */
        #ifdef NHHAM_PYEXT
        #define PY_SSIZE_T_CLEAN
        #include <Python.h>
        #define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
        #include <numpy/arrayobject.h>
        #endif
        #include <math.h>
        #define NQ {n}
        #define NC {m}
        #define NH {k}
        #define NN {N}
        #define NOUT {n * n + n + m * n + 3 * m + k}
        #define NCX (NC > 0 ? NC : 1)
        #define NNX (NQ + NCX)
        #define NPAR {npar}
        #define NRES (2 * NQ + NC + 1)
        """)
    # Parameters may be unused; keep compilers quiet.
    lines = [head]
    lines += _c_kernel("saddle", printed["saddle"], n, npar)
    lines += _c_kernel("geometry", printed["geometry"], n, npar, with_v=False)
    lines += _c_kernel("lagr_q", printed["lq"], n, npar)
    lines += _c_kernel("jphi", printed["jphi"], n, npar)
    lines.append(_C_LINALG)
    lines.append(_C_RHS)
    lines.append(_C_RATTLE)
    lines.append(_C_ERK)
    if path == "closed_form":
        lines += _c_kernel("closed", printed["closed"], n, npar)
        lines.append(_C_CLOSED)
    else:
        lines.append(_C_PYEXT)
    return "\n".join(lines) + "\n"


_C_LINALG = r"""
/* ---- small dense linear algebra (row-major) ---- */

/* Solve A x = b (d x d) in place by LU with partial pivoting.
   Returns 0 on success, 1 if a pivot is exactly zero. */
static int gsolve(int d, double *A, double *b) {
    for (int c = 0; c < d; ++c) {
        int piv = c;
        double best = fabs(A[c * d + c]);
        for (int r = c + 1; r < d; ++r) if (fabs(A[r * d + c]) > best) { best = fabs(A[r * d + c]); piv = r; }
        if (best == 0.0) return 1;
        if (piv != c) {
            for (int j = 0; j < d; ++j) { double t = A[c * d + j]; A[c * d + j] = A[piv * d + j]; A[piv * d + j] = t; }
            double t = b[c]; b[c] = b[piv]; b[piv] = t;
        }
        double inv = 1.0 / A[c * d + c];
        for (int r = c + 1; r < d; ++r) {
            double f = A[r * d + c] * inv;
            if (f == 0.0) continue;
            for (int j = c + 1; j < d; ++j) A[r * d + j] -= f * A[c * d + j];
            b[r] -= f * b[c];
        }
    }
    for (int r = d - 1; r >= 0; --r) {
        double s = b[r];
        for (int j = r + 1; j < d; ++j) s -= A[r * d + j] * b[j];
        b[r] = s / A[r * d + r];
    }
    return 0;
}

/* The scaled saddle matrix [[D W D, (E M D)^T], [E M D, 0]] by LU with partial
   pivoting (the fallback of ksolve). */
static int lu_solve(int mm, const double *W, const double *mu, const double *d,
                     const double *e, const double *top, const double *bottom,
                     double *x, double *y) {
    const int nn = NQ + mm;
    double K[NNX * NNX], b[NNX];
    for (int i = 0; i < NQ; ++i) {
        for (int j = 0; j < NQ; ++j) K[i * nn + j] = W[i * NQ + j] * d[i] * d[j];
        for (int c = 0; c < mm; ++c) {
            double t = mu[c * NQ + i] * d[i] * e[c];
            K[i * nn + NQ + c] = t;
            K[(NQ + c) * nn + i] = t;
        }
        b[i] = top[i] * d[i];
    }
    for (int c = 0; c < mm; ++c) {
        for (int k = 0; k < mm; ++k) K[(NQ + c) * nn + NQ + k] = 0.0;
        b[NQ + c] = bottom[c] * e[c];
    }
    if (gsolve(nn, K, b)) return 1;
    for (int i = 0; i < NQ; ++i) x[i] = b[i] * d[i];
    for (int c = 0; c < mm; ++c) y[c] = b[NQ + c] * e[c];
    return 0;
}

/* Smallest accepted Cholesky pivot of W relative to its diagonal entry (a
   pivot of the unit-diagonal scaled W; the smallest pivot bounds the
   smallest eigenvalue from above, a cheap condition estimate): below it W
   is indefinite or nearly singular and the saddle matrix is solved by LU
   instead. The range-space method loses about log10 cond(W) digits, LU on
   the scaled saddle matrix does not depend on cond(W). The N-link snake's
   smallest pivots are 0.4 (N = 2) .. 0.04 (N = 16). */
#define CHOL_MIN 1e-4
#if defined(__GNUC__)
#define HOT static inline __attribute__((always_inline))
#else
#define HOT static inline
#endif

/* [[W, mu^T], [mu, 0]] [x; y] = [top; bottom] with the first mm rows of mu
   (row stride NQ); W symmetric.

   When W = L L^T (Cholesky, every pivot above CHOL_MIN times its diagonal
   entry) the range-space method: [Z | u] = L^-1 [mu^T | top], the Schur
   complement S = Z^T Z = mu W^-1 mu^T (positive definite when mu has full
   rank) by Cholesky, S y = Z^T u - bottom, L^T x = u - Z y. That is about
   n^3/6 + (m+1) n^2/2 + (m+1)^2 n/2 multiply-adds against (n+m)^3/3 for LU,
   with no pivot search; Cholesky and the triangular solves are invariant
   under the diagonal scaling that LU needs, so none is applied.
   Otherwise (W indefinite, e.g. a Lorentzian metric, or nearly singular; S
   not numerically positive definite, e.g. mu rank deficient): LU with partial
   pivoting on the symmetrically scaled saddle matrix (unit diagonal of W,
   unit rows of mu), which makes extreme mass ratios harmless.
   Returns 0, or 1 when the matrix is singular. */
HOT int ksolve(int mm, const double *W, const double *mu, const double *top,
               const double *bottom, double *x, double *y) {
    enum { M1 = NCX + 1 };
    double L[NQ * NQ], Z[M1 * NQ], G[M1 * M1], r[NCX];
    /* Cholesky W = L L^T; the diagonal of L holds 1 / L_jj. */
    for (int j = 0; j < NQ; ++j) {
        const double wjj = W[j * NQ + j];
        double s = wjj;
        for (int k = 0; k < j; ++k) s -= L[j * NQ + k] * L[j * NQ + k];
        if (!(s > CHOL_MIN * wjj)) goto lu;
        const double inv = 1.0 / sqrt(s);
        L[j * NQ + j] = inv;
        for (int i = j + 1; i < NQ; ++i) {
            double t = W[i * NQ + j];
            for (int k = 0; k < j; ++k) t -= L[i * NQ + k] * L[j * NQ + k];
            L[i * NQ + j] = t * inv;
        }
    }
    /* [Z | u] = L^-1 [mu^T | top]: row c of Z holds column c (c = mm: u). */
    for (int c = 0; c <= mm; ++c) {
        double *zc = Z + c * NQ;
        const double *b = c < mm ? mu + c * NQ : top;
        for (int i = 0; i < NQ; ++i) {
            double s = b[i];
            for (int k = 0; k < i; ++k) s -= L[i * NQ + k] * zc[k];
            zc[i] = s * L[i * NQ + i];
        }
    }
    /* G = [Z | u]^T [Z | u] (lower part): S = G[:mm, :mm], Z^T u = G[mm, :mm]. */
    for (int c = 0; c <= mm; ++c)
        for (int e = 0; e <= c && e < mm; ++e) {
            const double *zc = Z + c * NQ, *ze = Z + e * NQ;
            double s = 0.0;
            for (int i = 0; i < NQ; ++i) s += zc[i] * ze[i];
            G[c * M1 + e] = s;
        }
    /* Cholesky of S in place (diagonal holds 1 / R_jj); S y = Z^T u - bottom. */
    for (int j = 0; j < mm; ++j) {
        double s = G[j * M1 + j];
        for (int k = 0; k < j; ++k) s -= G[j * M1 + k] * G[j * M1 + k];
        if (!(s > 0.0) || !isfinite(s)) goto lu;
        const double inv = 1.0 / sqrt(s);
        G[j * M1 + j] = inv;
        for (int i = j + 1; i < mm; ++i) {
            double t = G[i * M1 + j];
            for (int k = 0; k < j; ++k) t -= G[i * M1 + k] * G[j * M1 + k];
            G[i * M1 + j] = t * inv;
        }
    }
    for (int i = 0; i < mm; ++i) {
        double s = G[mm * M1 + i] - bottom[i];
        for (int k = 0; k < i; ++k) s -= G[i * M1 + k] * r[k];
        r[i] = s * G[i * M1 + i];
    }
    for (int i = mm - 1; i >= 0; --i) {
        double s = r[i];
        for (int k = i + 1; k < mm; ++k) s -= G[k * M1 + i] * r[k];
        r[i] = s * G[i * M1 + i];
        y[i] = r[i];
    }
    /* x = L^-T (u - Z y), column-oriented back substitution. */
    for (int i = 0; i < NQ; ++i) x[i] = Z[mm * NQ + i];
    for (int c = 0; c < mm; ++c) {
        const double *zc = Z + c * NQ, rc = r[c];
        for (int i = 0; i < NQ; ++i) x[i] -= zc[i] * rc;
    }
    for (int i = NQ - 1; i >= 0; --i) {
        const double xi = x[i] * L[i * NQ + i];
        x[i] = xi;
        for (int k = 0; k < i; ++k) x[k] -= L[i * NQ + k] * xi;
    }
    return 0;
lu:
    {
        double d[NQ], e[NCX];
        for (int i = 0; i < NQ; ++i) {
            double a = fabs(W[i * NQ + i]);
            d[i] = a > 0.0 ? 1.0 / sqrt(a) : 1.0;
        }
        for (int c = 0; c < mm; ++c) {
            double s = 0.0;
            for (int j = 0; j < NQ; ++j) { double t = mu[c * NQ + j] * d[j]; s += t * t; }
            e[c] = s > 0.0 ? 1.0 / sqrt(s) : 1.0;
        }
        return lu_solve(mm, W, mu, d, e, top, bottom, x, y);
    }
}
"""

_C_RHS = r"""
/* dy = (v, a), lam = multipliers, power = -lam . (mu v) (= dE/dt exactly).
   alpha2, beta2: Baumgarte terms (2 alpha, beta^2); zero for none.
   The saddle-point system is solved by ksolve (scaled: extreme mass ratios
   are harmless). Returns 0, 1 (singular) or 2 (not finite). */
static int rhs_one(const double *y, const double *p, double alpha2, double beta2,
                   double *dy, double *lam, double *power) {
    double out[NOUT > 0 ? NOUT : 1], bot[NCX], muv[NCX];
    saddle(y, p, out);
    const double *W = out, *F = out + NQ * NQ, *mu = F + NQ, *drift = mu + NC * NQ;
    const double *h = drift + NC, *g = h + NC;
    const double *v = y + NQ;
    for (int c = 0; c < NC; ++c) {
        double mv = 0.0;
        for (int j = 0; j < NQ; ++j) mv += mu[c * NQ + j] * v[j];
        muv[c] = mv;
        double rhs = -drift[c];
        if (alpha2 != 0.0) rhs -= alpha2 * (mv + h[c]);
        if (beta2 != 0.0 && c < NH) rhs -= beta2 * g[c];
        bot[c] = rhs;
    }
    (void)h; (void)g;
    if (ksolve(NC, W, mu, F, bot, dy + NQ, lam)) return 1;
    double pw = 0.0;
    for (int i = 0; i < NQ; ++i) dy[i] = v[i];
    for (int c = 0; c < NC; ++c) pw -= lam[c] * muv[c];
    *power = pw;
    for (int i = 0; i < 2 * NQ; ++i) if (!isfinite(dy[i])) return 2;
    return 0;
}

/* pext = [parameters..., 2 alpha, beta^2]; out = [dy (2n), lam (m), power]. */
int nhham_rhs(const double *y, double *out, const double *pext) {
    return rhs_one(y, pext, pext[NPAR], pext[NPAR + 1], out, out + 2 * NQ, out + 2 * NQ + NC);
}

/* k states in Y (k x 2n row-major), OUT (k x NRES); returns the number of failed states. */
int nhham_rhs_batch(int k, const double *Y, double *OUT, const double *pext) {
    int bad = 0;
    for (int s = 0; s < k; ++s) {
        double *o = OUT + (long)s * NRES;
        bad += rhs_one(Y + (long)s * 2 * NQ, pext, pext[NPAR], pext[NPAR + 1],
                       o, o + 2 * NQ, o + 2 * NQ + NC) != 0;
    }
    return bad;
}
"""

_C_CLOSED = r"""
/* Closed-form path: accelerations and multipliers of the symbolic P(xi_L). */
static int closed_one(const double *y, const double *p, double *o) {
    double out[NQ + NC];
    closed(y, p, out);
    for (int i = 0; i < NQ; ++i) { o[i] = y[NQ + i]; o[NQ + i] = out[i]; }
    for (int c = 0; c < NC; ++c) o[2 * NQ + c] = out[NQ + c];
    o[2 * NQ + NC] = 0.0;  /* power is computed by the caller */
    for (int i = 0; i < 2 * NQ; ++i) if (!isfinite(o[i])) return 2;
    return 0;
}

int nhham_closed(const double *y, double *out, const double *pext) {
    return closed_one(y, pext, out);
}

int nhham_closed_batch(int k, const double *Y, double *OUT, const double *pext) {
    int bad = 0;
    for (int s = 0; s < k; ++s)
        bad += closed_one(Y + (long)s * 2 * NQ, pext, OUT + (long)s * NRES) != 0;
    return bad;
}
"""


_C_RATTLE = r"""
/* ---- nonholonomic RATTLE for constant W (see nhham.integrators) ---- */
#define NGEO (NQ * NQ + NC * NQ + NC + NH)

/* One step (q, v) -> (q1, v1) in place; lam: in = guess for lam0, out = lam1.
   Returns 0, or -4 (Newton failed), -3 (singular). */
static int rattle_step(double *q, double *v, double h, double *lam, const double *p,
                       const double *W, const double *Winv, double tol, int maxiter,
                       long *newton) {
    double geo[NGEO], y[2 * NQ], p0[NQ], Lq[NQ], base[NQ], qf[NQ], dq[NQ * NCX];
    double q1[NQ], qm[NQ], u[NQ], r[NCX], J[NCX * NCX], Jp[NCX * NQ], Jq[NCX * NQ];
    double mu0[NCX * NQ], mu1h[NCX * NQ], top[NQ], bot[NCX], v1[NQ], nu[NCX];
    geometry(q, p, geo);
    for (int i = 0; i < NC * NQ; ++i) mu0[i] = geo[NQ * NQ + i];
    for (int i = 0; i < NQ; ++i) {
        double s = 0.0;
        for (int j = 0; j < NQ; ++j) s += W[i * NQ + j] * v[j];
        p0[i] = s; y[i] = q[i]; y[NQ + i] = v[i];
    }
    lagr_q(y, p, Lq);
    for (int i = 0; i < NQ; ++i) base[i] = p0[i] + 0.5 * h * Lq[i];
    for (int i = 0; i < NQ; ++i) {
        double s = 0.0;
        for (int j = 0; j < NQ; ++j) s += Winv[i * NQ + j] * base[j];
        qf[i] = q[i] + h * s;
        for (int c = 0; c < NC; ++c) {
            double a = 0.0;
            for (int j = 0; j < NQ; ++j) a += Winv[i * NQ + j] * mu0[c * NQ + j];
            dq[i * NCX + c] = -0.5 * h * h * a;
        }
    }
    double best = INFINITY;
    int it = 0;
    for (;; ++it) {
        for (int i = 0; i < NQ; ++i) {
            double s = qf[i];
            for (int c = 0; c < NC; ++c) s += dq[i * NCX + c] * lam[c];
            q1[i] = s; qm[i] = 0.5 * (q[i] + s); u[i] = (s - q[i]) / h;
        }
        if (NC == 0) break;
        geometry(qm, p, geo);
        const double *mum = geo + NQ * NQ, *hm = mum + NC * NQ;
        double err = 0.0, scale = 1.0;
        for (int c = 0; c < NC; ++c) {
            double s = hm[c];
            for (int j = 0; j < NQ; ++j) s += mum[c * NQ + j] * u[j];
            r[c] = s;
        }
        for (int c = 0; c < NC; ++c) for (int j = 0; j < NQ; ++j) Jq[c * NQ + j] = mum[c * NQ + j] / h;
        for (int j = 0; j < NQ; ++j) if (fabs(u[j]) + 1.0 > scale) scale = fabs(u[j]) + 1.0;
        double yy[2 * NQ];
        for (int j = 0; j < NQ; ++j) { yy[j] = qm[j]; yy[NQ + j] = u[j]; }
        jphi(yy, p, Jp);
        for (int c = 0; c < NC; ++c) for (int j = 0; j < NQ; ++j) Jq[c * NQ + j] += 0.5 * Jp[c * NQ + j];
        if (NH > 0) {
            double geo1[NGEO];
            geometry(q1, p, geo1);
            const double *g1 = geo1 + NQ * NQ + NC * NQ + NC;
            for (int c = 0; c < NH; ++c) {
                r[c] = g1[c];
                for (int j = 0; j < NQ; ++j) Jq[c * NQ + j] = geo1[NQ * NQ + c * NQ + j];
            }
        }
        for (int c = 0; c < NC; ++c) if (fabs(r[c]) > err) err = fabs(r[c]);
        if (!(err == err)) return -2;
        if (err <= tol * scale) break;
        if (it > 2 && err >= best) { if (err > 1e-9 * scale) return -4; break; }
        if (it >= maxiter) return -4;
        if (err < best) best = err;
        for (int c = 0; c < NC; ++c)
            for (int e = 0; e < NC; ++e) {
                double s = 0.0;
                for (int j = 0; j < NQ; ++j) s += Jq[c * NQ + j] * dq[j * NCX + e];
                J[c * NC + e] = s;
            }
        if (gsolve(NC, J, r)) return -3;
        for (int c = 0; c < NC; ++c) lam[c] -= r[c];
        ++*newton;
    }
    /* half kick with lam0, then the exact end constraint */
    double ph[NQ];
    for (int i = 0; i < NQ; ++i) {
        double s = 0.0;
        for (int c = 0; c < NC; ++c) s += mu0[c * NQ + i] * lam[c];
        ph[i] = base[i] - 0.5 * h * s;
    }
    geometry(q1, p, geo);
    for (int i = 0; i < NC * NQ; ++i) mu1h[i] = geo[NQ * NQ + i];
    const double *h1 = geo + NQ * NQ + NC * NQ;
    for (int i = 0; i < NQ; ++i) {
        double s = 0.0;
        for (int j = 0; j < NQ; ++j) s += Winv[i * NQ + j] * ph[j];
        y[i] = q1[i]; y[NQ + i] = s;
    }
    lagr_q(y, p, Lq);
    for (int i = 0; i < NQ; ++i) top[i] = ph[i] + 0.5 * h * Lq[i];
    for (int c = 0; c < NC; ++c) bot[c] = -h1[c];
    if (ksolve(NC, W, mu1h, top, bot, v1, nu)) return -3;
    /* Iterative refinement of the constraint rows when their residual is above
       round-off (LU is only normwise backward stable: extreme mass ratios). */
    {
        double rr[NCX], zero[NQ], dv[NQ], dnu[NCX], big = 0.0, size = 0.0;
        for (int c = 0; c < NC; ++c) {
            double s = h1[c], a = fabs(h1[c]);
            for (int j = 0; j < NQ; ++j) { s += mu1h[c * NQ + j] * v1[j]; a += fabs(mu1h[c * NQ + j] * v1[j]); }
            rr[c] = -s;
            if (fabs(s) > big) big = fabs(s);
            if (a > size) size = a;
        }
        if (NC > 0 && big > 4.0 * 2.220446049250313e-16 * size) {
            for (int i = 0; i < NQ; ++i) zero[i] = 0.0;
            if (ksolve(NC, W, mu1h, zero, rr, dv, dnu)) return -3;
            for (int i = 0; i < NQ; ++i) v1[i] += dv[i];
            for (int c = 0; c < NC; ++c) nu[c] += dnu[c];
        }
    }
    for (int c = 0; c < NC; ++c) lam[c] = 2.0 * nu[c] / h;
    for (int i = 0; i < NQ; ++i) {
        q[i] = q1[i]; v[i] = v1[i];
        if (!isfinite(q[i]) || !isfinite(v[i]) || fabs(q[i]) > 1e150 || fabs(v[i]) > 1e150) return -2;
    }
    return 0;
}

/* nsteps steps of size h from y0; composition 0: RATTLE, 1: triple jump (order 4).
   out: states every save_every steps (and the last), row-major (.., 2n).
   info: [steps done, Newton iterations, states stored]. Returns the status. */
int nhham_rattle(const double *y0, double h, long nsteps, long save_every, int composition,
                 double *out, const double *pext, double *lam0, double tol, int maxiter,
                 long *info) {
    double W[NQ * NQ], Winv[NQ * NQ], geo[NGEO], q[NQ], v[NQ], lam[NCX];
    geometry(y0, pext, geo);
    for (int i = 0; i < NQ * NQ; ++i) W[i] = geo[i];
    for (int c = 0; c < NQ; ++c) {
        double A[NQ * NQ], e[NQ];
        for (int i = 0; i < NQ * NQ; ++i) A[i] = W[i];
        for (int i = 0; i < NQ; ++i) e[i] = (i == c);
        if (gsolve(NQ, A, e)) return -3;
        for (int i = 0; i < NQ; ++i) Winv[i * NQ + c] = e[i];
    }
    for (int i = 0; i < NQ; ++i) { q[i] = y0[i]; v[i] = y0[NQ + i]; }
    for (int c = 0; c < NC; ++c) lam[c] = lam0[c];
    const double g1 = 1.0 / (2.0 - cbrt(2.0)), g2 = 1.0 - 2.0 * g1;
    long stored = 0, newton = 0, s;
    int status = 0;
    for (int i = 0; i < NQ; ++i) { out[i] = q[i]; out[NQ + i] = v[i]; }
    stored = 1;
    for (s = 1; s <= nsteps; ++s) {
        if (composition == 0) {
            status = rattle_step(q, v, h, lam, pext, W, Winv, tol, maxiter, &newton);
        } else {
            status = rattle_step(q, v, g1 * h, lam, pext, W, Winv, tol, maxiter, &newton);
            if (!status) status = rattle_step(q, v, g2 * h, lam, pext, W, Winv, tol, maxiter, &newton);
            if (!status) status = rattle_step(q, v, g1 * h, lam, pext, W, Winv, tol, maxiter, &newton);
        }
        if (status) break;
        if (s % save_every == 0 || s == nsteps) {
            double *o = out + stored * 2 * NQ;
            for (int i = 0; i < NQ; ++i) { o[i] = q[i]; o[NQ + i] = v[i]; }
            ++stored;
        }
    }
    info[0] = status ? s - 1 : nsteps;
    info[1] = newton;
    info[2] = stored;
    return status;
}
"""


_C_ERK = r"""
/* ---- projection onto M_1 and the explicit Runge-Kutta loop ---- */
#define NZ (2 * NQ + 1)   /* state and the work of the constraint forces */
#define SEXT 16           /* DOP853 stages with the dense-output extras */

/* z (q, v) onto M_1 exactly as NumericModel.project: Newton iterations for the
   holonomic rows (the step of least kinetic length), then the velocities in
   the kinetic metric (one solve and one refinement). 0, -6 (singular) or -4
   (Newton did not converge). */
static int project_state(double *z, const double *p, double tol, int maxiter) {
    double geo[NGEO], zero[NQ], dq[NQ], lam[NCX], r[NCX];
    double *q = z, *v = z + NQ;
    for (int i = 0; i < NQ; ++i) zero[i] = 0.0;
    if (NH > 0) {
        double best = INFINITY;
        int done = 0;
        for (int it = 1; it <= maxiter; ++it) {
            geometry(q, p, geo);
            const double *g = geo + NQ * NQ + NC * NQ + NC;
            double err = 0.0, scale = 0.0;
            for (int c = 0; c < NH; ++c) if (fabs(g[c]) > err) err = fabs(g[c]);
            for (int i = 0; i < NQ; ++i) if (fabs(q[i]) > scale) scale = fabs(q[i]);
            if (err <= tol * (1.0 + scale)) { done = 1; break; }
            if (it > 3 && err >= best) break;
            if (err < best) best = err;
            for (int c = 0; c < NH; ++c) r[c] = -g[c];
            if (ksolve(NH, geo, geo + NQ * NQ, zero, r, dq, lam)) return -6;
            for (int i = 0; i < NQ; ++i) q[i] += dq[i];
        }
        if (!done) {
            geometry(q, p, geo);
            const double *g = geo + NQ * NQ + NC * NQ + NC;
            double err = 0.0, scale = 0.0;
            for (int c = 0; c < NH; ++c) if (fabs(g[c]) > err) err = fabs(g[c]);
            for (int i = 0; i < NQ; ++i) if (fabs(q[i]) > scale) scale = fabs(q[i]);
            if (!(err <= fmax(tol, 1e-12) * (1.0 + scale))) return -4;
        }
    }
    geometry(q, p, geo);
    const double *W = geo, *mu = geo + NQ * NQ, *h = mu + NC * NQ;
    for (int pass = 0; pass < 2 && NC > 0; ++pass) {
        int any = 0;
        for (int c = 0; c < NC; ++c) {
            double s = 0.0;
            for (int j = 0; j < NQ; ++j) s += mu[c * NQ + j] * v[j];
            r[c] = -(s + h[c]);
            any |= r[c] != 0.0;
        }
        if (!any) break;
        if (ksolve(NC, W, mu, zero, r, dq, lam)) return -6;
        for (int i = 0; i < NQ; ++i) v[i] += dq[i];
    }
    for (int i = 0; i < 2 * NQ; ++i) if (!isfinite(z[i])) return -4;
    return 0;
}

/* f = (dy, power) at z; on failure the time and state go to fail. */
static int erk_field(const double *z, double t, const double *pext, double *f, long *nfev,
                     double *fail) {
    double lam[NCX];
    ++*nfev;
    int st = rhs_one(z, pext, pext[NPAR], pext[NPAR + 1], f, lam, f + 2 * NQ);
    if (!st) return 0;
    fail[0] = t;
    for (int i = 0; i < NZ; ++i) fail[1 + i] = z[i];
    return st == 1 ? -3 : -5;
}

/* Dense output at t_old + x h (scipy's RkDenseOutput / Dop853DenseOutput). */
static void erk_dense(int dop, int s, int np_, const double *K, const double *P,
                      const double *F, const double *zold, double h, double x, double *zd) {
    if (dop) {
        for (int i = 0; i < NZ; ++i) {
            double y = 0.0;
            for (int j = 6; j >= 0; --j) {
                y += F[j * NZ + i];
                y *= ((6 - j) % 2 == 0) ? x : 1.0 - x;
            }
            zd[i] = y + zold[i];
        }
    } else {
        for (int i = 0; i < NZ; ++i) {
            double y = 0.0, pw = 1.0;
            for (int c = 0; c < np_; ++c) {
                double qc = 0.0;
                for (int k = 0; k <= s; ++k) qc += K[k * NZ + i] * P[k * np_ + c];
                pw *= x;
                y += qc * pw;
            }
            zd[i] = h * y + zold[i];
        }
    }
}

/* scipy's RK23 / RK45 / DOP853 (RungeKutta._step_impl, select_initial_step,
   the error norms and the dense output) with the compiled field, projection
   onto M_1 after every step (and at the dense points) and the storage of the
   steps or of the t_eval points, all in one call.

   info = [stages s, dop853?, columns of P, error estimator order, first call?]
   tab = A (s x s), B (s), C (s), E (s+1; E5 for DOP853), E3 (s+1), P ((s+1) x np),
         A_EXTRA (3 x 16), C_EXTRA (3), D (4 x 16)
   st = [t, h_abs, z (NZ), f (NZ)]: the state carried from call to call
        (h_abs <= 0 on the first call: select the initial step).
   Returns 0 (t_bound reached), 1 (paused: t_pause passed or the step buffer
   full), -1 (step size too small), -2 (non-finite or overflowing state),
   -3 (singular saddle matrix), -4 (projection failed), -5 (non-finite field),
   -6 (singular matrix in the projection). */
int nhham_erk(const int *info, const double *tab, double *st, double t_bound, double rtol,
              const double *atol, double max_step, int projection, double proj_tol,
              int proj_maxiter, const double *t_eval, long n_eval, long *i_eval,
              double *out_t, double *out_z, long cap, long *nout, double t_pause,
              const double *pext, long *counts, double *fail) {
    const int s = info[0], dop = info[1], np_ = info[2];
    const double err_exp = -1.0 / (info[3] + 1);
    const double *A = tab, *B = A + s * s, *C = B + s, *E = C + s, *E3 = E + s + 1;
    const double *P = E3 + s + 1, *Aext = P + (s + 1) * np_, *Cext = Aext + 3 * SEXT;
    const double *D = Cext + 3;
    double K[SEXT * NZ], F[7 * NZ], znew[NZ], zold[NZ], ztmp[NZ], scale[NZ];
    double *t = st, *habs = st + 1, *z = st + 2, *f = st + 2 + NZ;
    long *nfev = counts, *nsteps = counts + 1;
    const double dir = t_bound >= *t ? 1.0 : -1.0;
    int status;
    if (info[4]) {
        if ((status = erk_field(z, *t, pext, f, nfev, fail))) return status;
        if (!(*habs > 0.0)) {  /* select_initial_step */
            double interval = fabs(t_bound - *t), d0 = 0.0, d1 = 0.0, d2 = 0.0, h0, h1;
            if (interval == 0.0) {
                *habs = 0.0;
            } else {
                for (int i = 0; i < NZ; ++i) {
                    scale[i] = atol[i] + fabs(z[i]) * rtol;
                    d0 += (z[i] / scale[i]) * (z[i] / scale[i]);
                    d1 += (f[i] / scale[i]) * (f[i] / scale[i]);
                }
                d0 = sqrt(d0 / NZ); d1 = sqrt(d1 / NZ);
                h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
                if (h0 > interval) h0 = interval;
                for (int i = 0; i < NZ; ++i) ztmp[i] = z[i] + h0 * dir * f[i];
                if ((status = erk_field(ztmp, *t + h0 * dir, pext, K, nfev, fail))) return status;
                for (int i = 0; i < NZ; ++i) {
                    double e = (K[i] - f[i]) / scale[i];
                    d2 += e * e;
                }
                d2 = sqrt(d2 / NZ) / h0;
                if (d1 <= 1e-15 && d2 <= 1e-15) h1 = fmax(1e-6, h0 * 1e-3);
                else h1 = pow(0.01 / fmax(d1, d2), 1.0 / (info[3] + 1));
                double hh = 100 * h0;
                if (h1 < hh) hh = h1;
                if (interval < hh) hh = interval;
                if (max_step < hh) hh = max_step;
                *habs = hh;
            }
        }
    }
    for (;;) {
        if (*t == t_bound) return 0;
        if (dir * (*t - t_pause) >= 0.0) return 1;
        if (n_eval == 0 && *nout >= cap) return 1;
        const double t0 = *t;
        const double min_step = 10.0 * fabs(nextafter(t0, dir * INFINITY) - t0);
        double h_abs = *habs > max_step ? max_step : (*habs < min_step ? min_step : *habs);
        double h, t_new;
        int rejected = 0;
        for (;;) {
            if (h_abs < min_step) return -1;
            h = h_abs * dir;
            t_new = t0 + h;
            if (dir * (t_new - t_bound) > 0.0) t_new = t_bound;
            h = t_new - t0;
            h_abs = fabs(h);
            for (int i = 0; i < NZ; ++i) K[i] = f[i];
            for (int j = 1; j < s; ++j) {
                for (int i = 0; i < NZ; ++i) {
                    double acc = 0.0;
                    for (int k = 0; k < j; ++k) acc += K[k * NZ + i] * A[j * s + k];
                    ztmp[i] = z[i] + acc * h;
                }
                if ((status = erk_field(ztmp, t0 + C[j] * h, pext, K + j * NZ, nfev, fail)))
                    return status;
            }
            for (int i = 0; i < NZ; ++i) {
                double acc = 0.0;
                for (int k = 0; k < s; ++k) acc += K[k * NZ + i] * B[k];
                znew[i] = z[i] + h * acc;
            }
            if ((status = erk_field(znew, t0 + h, pext, K + s * NZ, nfev, fail))) return status;
            double errn;
            if (dop) {
                double e5 = 0.0, e3 = 0.0;
                for (int i = 0; i < NZ; ++i) {
                    double a5 = 0.0, a3 = 0.0;
                    for (int k = 0; k <= s; ++k) { a5 += K[k * NZ + i] * E[k]; a3 += K[k * NZ + i] * E3[k]; }
                    double sc = atol[i] + fmax(fabs(z[i]), fabs(znew[i])) * rtol;
                    a5 /= sc; a3 /= sc;
                    e5 += a5 * a5; e3 += a3 * a3;
                }
                errn = (e5 == 0.0 && e3 == 0.0) ? 0.0 : h_abs * e5 / sqrt((e5 + 0.01 * e3) * NZ);
            } else {
                double e = 0.0;
                for (int i = 0; i < NZ; ++i) {
                    double a = 0.0;
                    for (int k = 0; k <= s; ++k) a += K[k * NZ + i] * E[k];
                    a = a * h / (atol[i] + fmax(fabs(z[i]), fabs(znew[i])) * rtol);
                    e += a * a;
                }
                errn = sqrt(e / NZ);
            }
            if (errn < 1.0) {
                double factor = errn == 0.0 ? 10.0 : fmin(10.0, 0.9 * pow(errn, err_exp));
                if (rejected) factor = fmin(1.0, factor);
                h_abs *= factor;
                break;
            }
            h_abs *= fmax(0.2, 0.9 * pow(errn, err_exp));
            rejected = 1;
        }
        for (int i = 0; i < NZ; ++i) { zold[i] = z[i]; z[i] = znew[i]; f[i] = K[s * NZ + i]; }
        *t = t_new;
        *habs = h_abs;
        ++*nsteps;
        for (int i = 0; i < 2 * NQ; ++i) if (!isfinite(z[i]) || fabs(z[i]) > 1e150) return -2;
        if (projection) {
            if ((status = project_state(z, pext, proj_tol, proj_maxiter))) return status;
            if ((status = erk_field(z, *t, pext, f, nfev, fail))) return status;
        }
        if (n_eval == 0) {
            out_t[*nout] = *t;
            for (int i = 0; i < NZ; ++i) out_z[*nout * NZ + i] = z[i];
            ++*nout;
            continue;
        }
        int ready = 0;
        while (*i_eval < n_eval && (dir > 0 ? t_eval[*i_eval] <= *t : t_eval[*i_eval] >= *t)) {
            if (!ready) {
                ready = 1;
                if (dop) {
                    for (int j = s + 1; j < SEXT; ++j) {
                        const double *a = Aext + (j - s - 1) * SEXT;
                        for (int i = 0; i < NZ; ++i) {
                            double acc = 0.0;
                            for (int k = 0; k < j; ++k) acc += K[k * NZ + i] * a[k];
                            ztmp[i] = zold[i] + acc * h;
                        }
                        if ((status = erk_field(ztmp, t0 + Cext[j - s - 1] * h, pext,
                                                K + j * NZ, nfev, fail))) return status;
                    }
                    for (int i = 0; i < NZ; ++i) {
                        double dz = z[i] - zold[i];
                        F[i] = dz;
                        F[NZ + i] = h * K[i] - dz;
                        F[2 * NZ + i] = 2.0 * dz - h * (f[i] + K[i]);
                        for (int r = 0; r < 4; ++r) {
                            double acc = 0.0;
                            for (int k = 0; k < SEXT; ++k) acc += D[r * SEXT + k] * K[k * NZ + i];
                            F[(3 + r) * NZ + i] = h * acc;
                        }
                    }
                }
            }
            double *o = out_z + *nout * NZ;
            erk_dense(dop, s, np_, K, P, F, zold, h, (t_eval[*i_eval] - t0) / h, o);
            if (projection && (status = project_state(o, pext, proj_tol, proj_maxiter)))
                return status;
            out_t[*nout] = t_eval[*i_eval];
            ++*nout;
            ++*i_eval;
        }
    }
}
"""


_C_PYEXT = r"""
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
"""


# ----------------------------------------------------------------- compile
def _cache_dir(cache_dir) -> str:
    base = cache_dir or os.environ.get("NHHAM_CACHE") or os.path.join(
        os.path.expanduser("~"), ".cache", "nhham")
    os.makedirs(base, exist_ok=True)
    return base


_FLAGS = ["-O2", "-fno-math-errno", "-shared", "-fPIC", "-std=c99"]


def _user_flags() -> list:
    """Extra compiler flags from ``$NHHAM_CFLAGS`` (e.g. ``-O3 -march=native``;
    the default stays portable: the cache may be shared between machines)."""
    return os.environ.get("NHHAM_CFLAGS", "").split()


def _pyext_flags():
    """Flags that also build the CPython entry points (``_C_PYEXT``), or None
    when the Python or numpy headers are not installed."""
    try:
        import sysconfig

        import numpy

        include = sysconfig.get_paths().get("include") or ""
        if not os.path.exists(os.path.join(include, "Python.h")):
            return None
        flags = ["-DNHHAM_PYEXT", f"-I{include}", f"-I{numpy.get_include()}"]
        # the ABI the module is built for belongs in the cache key
        return flags, f"{sysconfig.get_config_var('EXT_SUFFIX')} numpy {numpy.__version__}"
    except Exception:  # pragma: no cover - exotic installations
        return None


# Set when building the CPython entry points failed once in this process (no
# headers, a linker that wants libpython, ...): later models go straight to
# the plain library instead of failing again.
_PYEXT_FAILURE: list = []


def compile_c(source: str, cache_dir=None, flags=(), tag: str = "") -> str:
    """Compile ``source`` to a shared library in the cache; return its path.

    The file name is a hash of the source, the flags, ``tag`` and the
    platform, so a library is compiled once and reused across runs. ``flags``
    are added to the portable defaults (and to ``$NHHAM_CFLAGS``).

    Raises
    ------
    ComputationError
        When no compiler is available or compilation fails (message included).
    """
    cc = c_compiler()
    if cc is None:
        raise ComputationError("no C compiler found (set CC, or unset NHHAM_NO_CC)")
    allflags = [*_FLAGS, *_user_flags(), *flags]
    key = hashlib.sha256("\0".join([source, cc, *allflags, tag, sys.platform,
                                    os.uname().machine]).encode()).hexdigest()[:20]
    directory = _cache_dir(cache_dir)
    target = os.path.join(directory, f"nhham_{key}.so")
    if os.path.exists(target):
        return target
    with tempfile.TemporaryDirectory(dir=directory) as tmp:
        src = os.path.join(tmp, "model.c")
        lib = os.path.join(tmp, "model.so")
        with open(src, "w") as fh:
            fh.write(source)
        proc = subprocess.run([cc, *allflags, "-o", lib, src, "-lm"], capture_output=True,
                              text=True, timeout=300)
        if proc.returncode != 0:
            raise ComputationError(f"C compilation failed: {proc.stderr.strip()[:2000]}")
        os.replace(lib, target)  # atomic: concurrent builders never see half a file
    return target


def _try_compile(sources, cache_dir):
    """The compiled library: with the CPython entry points when the headers
    are there (single-state calls without ctypes), else plain ctypes."""
    ext = None
    if "PyInit_nhham_ext" in sources["c"] and not _PYEXT_FAILURE:
        ext = _pyext_flags()
    ext_error = _PYEXT_FAILURE[0] if _PYEXT_FAILURE else None
    if ext is not None:
        try:
            path = compile_c(sources["c"], cache_dir, ext[0], tag=ext[1])
            return (CompiledRHS.load(path, sources["layout"], extension=True),
                    f"compiled C with CPython entry points ({os.path.basename(path)})")
        except (ComputationError, OSError, ImportError, subprocess.SubprocessError) as exc:
            ext_error = str(exc)[:200]
    try:
        path = compile_c(sources["c"], cache_dir)
        compiled = CompiledRHS.load(path, sources["layout"])
    except (ComputationError, OSError, subprocess.SubprocessError) as exc:
        return None, str(exc)
    note = f"compiled C ({os.path.basename(path)})"
    if ext_error is not None:
        if not _PYEXT_FAILURE:  # the plain library builds: the extension part is at fault
            _PYEXT_FAILURE.append(ext_error)
        note += f"; CPython entry points unavailable ({ext_error})"
    return compiled, note
