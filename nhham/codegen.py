"""Code generation: the one bridge from sympy to numbers.

:func:`numeric_model` turns the symbolic pieces of a :class:`~nhham.System`
(``DESIGN.md`` §2, :class:`~nhham.lagrangian.DynamicsIngredients`) into a
:class:`~nhham.numeric.NumericModel` whose methods take arrays of states and
never touch sympy.

What is generated ("kernels"; each one is a single ``sympy.cse`` over all of
its outputs, so common subexpressions are shared):

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
high-precision reference integrator). The right-hand side (saddle kernel plus
the scaled LU solve) is also printed as C and compiled with the system
compiler into a cache directory keyed by a hash of the source; when no
compiler works the model falls back to numpy and says why.

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

from .errors import ComputationError, MissingParameterValueError
from .lagrangian import lagrangian_geometry
from .numeric import CompiledRHS, GeneratedKernels, NumericModel, NumericsWarning

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

    printed = {name: _cse(outputs) for name, (_, outputs) in kernels.items()}
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
        #include <math.h>
        #define NQ {n}
        #define NC {m}
        #define NH {k}
        #define NN {N}
        #define NOUT {n * n + n + m * n + 3 * m + k}
        """)
    # Parameters may be unused; keep compilers quiet.
    lines = [head]
    lines += _c_kernel("saddle", printed["saddle"], n, npar)
    lines.append(_C_SOLVER)
    lines.append(_C_RHS.replace("%NPAR%", str(npar)))
    lines += _c_kernel("geometry", printed["geometry"], n, npar, with_v=False)
    lines += _c_kernel("lagr_q", printed["lq"], n, npar)
    lines += _c_kernel("jphi", printed["jphi"], n, npar)
    lines.append(_C_RATTLE)
    if path == "closed_form":
        lines += _c_kernel("closed", printed["closed"], n, npar)
        lines.append(_C_CLOSED)
    return "\n".join(lines) + "\n"


_C_SOLVER = r"""
/* Solve K x = b in place (K row-major NN x NN) by LU with partial pivoting.
   Returns 0 on success, 1 if a pivot is exactly zero. */
static int lu_solve(double *K, double *b) {
    for (int c = 0; c < NN; ++c) {
        int piv = c;
        double best = fabs(K[c * NN + c]);
        for (int r = c + 1; r < NN; ++r) {
            double a = fabs(K[r * NN + c]);
            if (a > best) { best = a; piv = r; }
        }
        if (best == 0.0) return 1;
        if (piv != c) {
            for (int j = 0; j < NN; ++j) {
                double t = K[c * NN + j]; K[c * NN + j] = K[piv * NN + j]; K[piv * NN + j] = t;
            }
            double t = b[c]; b[c] = b[piv]; b[piv] = t;
        }
        double inv = 1.0 / K[c * NN + c];
        for (int r = c + 1; r < NN; ++r) {
            double f = K[r * NN + c] * inv;
            if (f == 0.0) continue;
            for (int j = c + 1; j < NN; ++j) K[r * NN + j] -= f * K[c * NN + j];
            b[r] -= f * b[c];
        }
    }
    for (int r = NN - 1; r >= 0; --r) {
        double s = b[r];
        for (int j = r + 1; j < NN; ++j) s -= K[r * NN + j] * b[j];
        b[r] = s / K[r * NN + r];
    }
    return 0;
}
"""

_C_RHS = r"""
/* dy = (v, a), lam = multipliers, power = -lam . (mu v) (= dE/dt exactly).
   alpha2, beta2: Baumgarte terms (2 alpha, beta^2); zero for none.
   The saddle matrix is scaled symmetrically (unit diagonal of W, unit rows
   of mu) before the solve; this is what makes extreme mass ratios safe. */
static int rhs_one(const double *y, const double *p, double alpha2, double beta2,
                   double *dy, double *lam, double *power) {
    double out[NOUT > 0 ? NOUT : 1];
    double K[NN * NN];
    double b[NN], d[NN];
    saddle(y, p, out);
    const double *W = out, *F = out + NQ * NQ, *mu = F + NQ, *drift = mu + NC * NQ;
    const double *h = drift + NC, *g = h + NC;
    const double *v = y + NQ;
    double muv[NC > 0 ? NC : 1];
    for (int i = 0; i < NQ; ++i) {
        double w = fabs(W[i * NQ + i]);
        d[i] = w > 0.0 ? 1.0 / sqrt(w) : 1.0;
    }
    for (int i = 0; i < NC; ++i) {
        double s = 0.0, mv = 0.0;
        for (int j = 0; j < NQ; ++j) {
            double t = mu[i * NQ + j] * d[j];
            s += t * t;
            mv += mu[i * NQ + j] * v[j];
        }
        muv[i] = mv;
        d[NQ + i] = s > 0.0 ? 1.0 / sqrt(s) : 1.0;
    }
    for (int i = 0; i < NQ; ++i) {
        for (int j = 0; j < NQ; ++j) K[i * NN + j] = W[i * NQ + j] * d[i] * d[j];
        for (int c = 0; c < NC; ++c) {
            double t = mu[c * NQ + i] * d[i] * d[NQ + c];
            K[i * NN + NQ + c] = t;
            K[(NQ + c) * NN + i] = t;
        }
        b[i] = F[i] * d[i];
    }
    for (int c = 0; c < NC; ++c) {
        for (int e = 0; e < NC; ++e) K[(NQ + c) * NN + NQ + e] = 0.0;
        double rhs = -drift[c];
        if (alpha2 != 0.0) rhs -= alpha2 * (muv[c] + h[c]);
        if (beta2 != 0.0 && c < NH) rhs -= beta2 * g[c];
        b[NQ + c] = rhs * d[NQ + c];
    }
    if (lu_solve(K, b)) return 1;
    double pw = 0.0;
    for (int i = 0; i < NQ; ++i) { dy[i] = v[i]; dy[NQ + i] = b[i] * d[i]; }
    for (int c = 0; c < NC; ++c) { lam[c] = b[NQ + c] * d[NQ + c]; pw -= lam[c] * muv[c]; }
    *power = pw;
    for (int i = 0; i < 2 * NQ; ++i) if (!isfinite(dy[i])) return 2;
    return 0;
}

/* pext = [parameters..., 2 alpha, beta^2]; out = [dy (2n), lam (m), power]. */
#define NPAR %NPAR%
#define NRES (2 * NQ + NC + 1)
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
#define NCX (NC > 0 ? NC : 1)
#define NGEO (NQ * NQ + NC * NQ + NC + NH)

/* Solve A x = b (d x d, row-major) in place by LU with partial pivoting. */
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
        for (int r = c + 1; r < d; ++r) {
            double f = A[r * d + c] / A[c * d + c];
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

/* [[W, mu^T], [mu, 0]] [x; y] = [top; bottom] with the symmetric scaling of rhs_one. */
static int saddle_solve(const double *W, const double *mu, const double *top,
                        const double *bottom, double *x, double *y) {
    double K[NN * NN], b[NN], d[NN];
    for (int i = 0; i < NQ; ++i) { double w = fabs(W[i * NQ + i]); d[i] = w > 0 ? 1.0 / sqrt(w) : 1.0; }
    for (int c = 0; c < NC; ++c) {
        double s = 0.0;
        for (int j = 0; j < NQ; ++j) { double t = mu[c * NQ + j] * d[j]; s += t * t; }
        d[NQ + c] = s > 0 ? 1.0 / sqrt(s) : 1.0;
    }
    for (int i = 0; i < NQ; ++i) {
        for (int j = 0; j < NQ; ++j) K[i * NN + j] = W[i * NQ + j] * d[i] * d[j];
        for (int c = 0; c < NC; ++c) {
            double t = mu[c * NQ + i] * d[i] * d[NQ + c];
            K[i * NN + NQ + c] = t; K[(NQ + c) * NN + i] = t;
        }
        b[i] = top[i] * d[i];
    }
    for (int c = 0; c < NC; ++c) {
        for (int e = 0; e < NC; ++e) K[(NQ + c) * NN + NQ + e] = 0.0;
        b[NQ + c] = bottom[c] * d[NQ + c];
    }
    if (gsolve(NN, K, b)) return 1;
    for (int i = 0; i < NQ; ++i) x[i] = b[i] * d[i];
    for (int c = 0; c < NC; ++c) y[c] = b[NQ + c] * d[NQ + c];
    return 0;
}

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
    if (saddle_solve(W, mu1h, top, bot, v1, nu)) return -3;
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
            if (saddle_solve(W, mu1h, zero, rr, dv, dnu)) return -3;
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


# ----------------------------------------------------------------- compile
def _cache_dir(cache_dir) -> str:
    base = cache_dir or os.environ.get("NHHAM_CACHE") or os.path.join(
        os.path.expanduser("~"), ".cache", "nhham")
    os.makedirs(base, exist_ok=True)
    return base


_FLAGS = ["-O2", "-fno-math-errno", "-shared", "-fPIC", "-std=c99"]


def compile_c(source: str, cache_dir=None) -> str:
    """Compile ``source`` to a shared library in the cache; return its path.

    The file name is a hash of the source, the flags and the platform, so a
    library is compiled once and reused across runs.

    Raises
    ------
    ComputationError
        When no compiler is available or compilation fails (message included).
    """
    cc = c_compiler()
    if cc is None:
        raise ComputationError("no C compiler found (set CC, or unset NHHAM_NO_CC)")
    key = hashlib.sha256("\0".join([source, cc, *_FLAGS, sys.platform,
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
        proc = subprocess.run([cc, *_FLAGS, "-o", lib, src, "-lm"], capture_output=True,
                              text=True, timeout=300)
        if proc.returncode != 0:
            raise ComputationError(f"C compilation failed: {proc.stderr.strip()[:2000]}")
        os.replace(lib, target)  # atomic: concurrent builders never see half a file
    return target


def _try_compile(sources, cache_dir):
    try:
        path = compile_c(sources["c"], cache_dir)
        return CompiledRHS.load(path, sources["layout"]), f"compiled C ({os.path.basename(path)})"
    except (ComputationError, OSError, subprocess.SubprocessError) as exc:
        return None, str(exc)
