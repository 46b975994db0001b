"""C and Python text from the symbolic pieces of a System (the sympy half of the bridge).

:func:`generate_sources` turns a :class:`~nhham.System` (``DESIGN.md`` §2,
:class:`~nhham.lagrangian.geometry.DynamicsIngredients`) into source texts and a layout;
:mod:`nhham.numerics.codegen.build` compiles the C and :mod:`nhham.numerics.kernels` loads
both. What is generated ("kernels"; each one is a single ``sympy.cse`` over all of its
outputs, so common subexpressions are shared; sin/cos of sums of coordinates whose own
sin/cos are computed anyway are expanded first, see :func:`expand_angle_sums`):

``saddle(q, v)``
    W (n x n), forcing F (n; with the generalized forces Q), mu (m x n), drift (m), h (m),
    g (k holonomic), and with forces the applied power Q . v.
    The right-hand side solves ``[[W, mu^T], [mu, 0]] [a; lambda] = [F; -drift]`` at run
    time: no symbolic inverse is ever formed.
``geometry(q)``
    W, mu, h, g: what projection onto M_1 and the structure-preserving integrator need.
    With a nonlinear (Chetaev) constraint it is ``geometry(q, v)``: mu = d phi/d v at
    (q, v) and h = phi - mu v (so that mu v + h = phi), in the saddle kernel too; and so
    with a Lagrangian not quadratic in v, whose W depends on v (layout
    ``geometry_reads_v``).
``energy(q, v)``
    E_L (v^T W v / 2 + V for L = v^T W v / 2 + b . v - V, read from the terms of L).
``lq(q, v)``, ``jphi(q, v)``
    dL/dq (n) and d(phi)/dq (m x n), for the Newton iterations of the nonholonomic RATTLE
    scheme.
``closed(q, v)``
    Only for ``path="closed_form"``: the accelerations of the symbolic projected field
    P(xi_L) and the symbolic multipliers, so the two paths can be compared.

The one evaluation route from sympy to numbers in the numerics layer
--------------------------------------------------------------------
Every number the numerics layer computes from a sympy expression goes through here:
``cse`` once per kernel, then one printer per target over the same reduced expressions —
scalar Python on floats (``math``; the fastest pure-Python single-state path), numpy on
columns of a batch (no Python loop over states), mpmath (the high-precision reference
integrator) and C99 (the compiled backend). So the four agree expression by expression,
and nothing in the numerics layer calls ``sympy.lambdify`` or evaluates sympy objects.
(The exact layers' own sampled decisions evaluate with ``lambdify``, below this layer.)

The Python text is :mod:`nhham.numerics.codegen.python_text`'s. The C text is the
generated kernels followed by the C runtime, which lives in real files
under ``nhham/numerics/c/`` (package data, see ``nhham.h`` there for the order).
Parameters stay symbolic in the generated code and are passed at run time (``p``), so a
parameter sweep reuses one compiled library.
"""

from __future__ import annotations

import functools
import hashlib
import re
from collections import OrderedDict
from importlib import resources
from pathlib import Path

import sympy as sp
from sympy.printing.c import C99CodePrinter

from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.numerics.codegen.python_text import python_module
from nhham.numerics.status import c_defines
from nhham.system.derivative import symbols_in
from nhham.system.expressions import derivative

__all__ = ["generate_sources", "system_fingerprint", "expression_digest", "source_key",
           "sources_digest", "code_digest", "cached_sources", "remember_sources", "expand_angle_sums",
           "kernel_parameters", "parameter_layout", "with_parameter_layout",
           "runtime_source", "RUNTIME_FILES"]

#: The runtime files, in the order they follow the generated kernels (``nhham.h`` first).
RUNTIME_FILES = ("linalg.c", "rhs.c", "rattle.c", "erk.c", "dgrad.c")


def generate_sources(system, path: str = "saddle") -> dict:
    """Generated source texts and the layout describing them.

    Sources are kept for the last 64 distinct systems, keyed by
    :func:`system_fingerprint` (the system's content, not its identity: equal systems
    share them, and no system is kept alive).

    Returns
    -------
    dict
        ``python`` (module text with scalar, batch and mpmath kernels), ``c`` (the whole C
        translation unit), ``c_complex`` (the complex-step kernels' translation unit, or
        ``""``), ``layout`` (plain dict: sizes, names and flags that
        :class:`~nhham.numerics.model.NumericModel` needs).
    """
    key = source_key(system, path)
    cached = cached_sources(key)
    sources = remember_sources(key, _generate(system, path)) if cached is None else cached
    return with_parameter_layout(sources, system)


def parameter_layout(system) -> dict:
    """The layout entries that name the whole parameter vector (the kernels read its
    :func:`kernel_parameters`): the system's own, where sources are shared by systems
    that differ in parameters no expression reads."""
    return {"parameter_names": tuple(p.name for p in system.parameters),
            "kernel_parameters": kernel_parameters(system),
            "input_names": tuple(u.name for u in system.inputs),
            "time_slot": system.time_slot}


def with_parameter_layout(sources: dict, system) -> dict:
    """``sources`` (not changed) with ``system``'s :func:`parameter_layout`."""
    return {**sources, "layout": {**sources["layout"], **parameter_layout(system)}}


def cached_sources(key: str) -> dict | None:
    """The sources of :func:`source_key` ``key`` held by this process, or None."""
    cached = _SOURCES.get(key)
    if cached is not None:
        _SOURCES.move_to_end(key)
    return cached


def remember_sources(key: str, sources: dict) -> dict:
    """Hold ``sources`` under ``key`` in this process (the last 64 kept); returns them."""
    _SOURCES[key] = sources
    while len(_SOURCES) > _SOURCES_KEPT:
        _SOURCES.popitem(last=False)
    return sources


def source_key(system, path: str = "saddle") -> str:
    """The key of a system's generated sources: its :func:`system_fingerprint` and a
    digest of nhham's own code (a change of the generator never meets old sources)."""
    return hashlib.sha256((system_fingerprint(system, path) + code_digest()).encode()
                          ).hexdigest()[:40]


@functools.cache
def code_digest() -> str:
    """SHA-256 of the code the generated sources come from, read once: this module, the
    nhham modules it imports (transitively, by their import lines: :func:`generator_files`)
    and the C runtime. An edit elsewhere in nhham (a command, a renderer, the integrators)
    leaves every model's sources valid."""
    root = Path(__file__).resolve().parents[3]
    h = hashlib.sha256()
    for f in generator_files():
        h.update(str(f.relative_to(root)).encode() + b"\0" + f.read_bytes())
    return h.hexdigest()


#: ``from nhham.a.b import x, y`` and ``import nhham.a.b``, anywhere in a line (imports
#: inside functions count: the geometry imports most of what it uses where it uses it).
_IMPORT = re.compile(r"^[ \t]*(?:from[ \t]+(nhham(?:\.\w+)*)[ \t]+import\b"
                     r"|import[ \t]+(nhham(?:\.\w+)*))", re.MULTILINE)


def generator_files() -> list:
    """The source files :func:`code_digest` covers, sorted: from this module, every nhham
    module reached through import lines (a name imported from a package brings the whole
    package: its lazy table may lead anywhere in it), and ``nhham/numerics/c``."""
    package = Path(__file__).resolve().parents[2]
    seen: set = set()
    todo = [Path(__file__).resolve()]
    while todo:
        f = todo.pop()
        if f in seen:
            continue
        seen.add(f)
        for m in _IMPORT.finditer(f.read_text(encoding="utf-8")):
            parts = (m.group(1) or m.group(2)).split(".")[1:]
            base = package.joinpath(*parts)
            if base.with_suffix(".py").is_file():
                todo.append(base.with_suffix(".py"))
            elif base.is_dir():
                todo += [p for p in base.rglob("*.py") if "__pycache__" not in p.parts]
    runtime = [p for p in (package / "numerics" / "c").iterdir() if p.suffix in (".c", ".h")]
    return sorted(seen | set(runtime))


def sources_digest(sources: dict) -> str:
    """SHA-256 of generated Python and C texts: what a study's workers check their model
    against."""
    return hashlib.sha256((sources["python"] + "\0" + sources["c"]).encode()).hexdigest()


#: Generated sources by source key (strings and plain data only).
_SOURCES: OrderedDict = OrderedDict()
_SOURCES_KEPT = 64


def system_fingerprint(system, path: str = "saddle") -> str:
    """A hash of everything the generated sources depend on.

    The coordinates, the parameters the kernels read (:func:`kernel_parameters`, with
    their assumptions: one that enters no expression changes nothing generated), the
    Lagrangian, the affine constraints phi (complete lifts first), the holonomic
    constraints, their labels, the generalized forces, the name and the path; the
    expressions by their structure (:func:`expression_digest`): equal expressions give
    equal fingerprints in any process, however they were built.
    """
    read = tuple(system.parameters[i] for i in kernel_parameters(system))
    exprs: tuple = (tuple(system.coordinates), read, system.lagrangian,
                    tuple(system.phi), tuple(system.holonomic))
    if system.has_forces:
        exprs += (tuple(system.generalized_forces),)
    h = hashlib.sha256("\0".join([path, system.name,
                                  repr(tuple(system.constraint_labels))]).encode())
    memo: dict = {}
    for e in exprs:
        h.update(b"\0" + expression_digest(e, memo))
    return h.hexdigest()


def expression_digest(expr, memo: dict | None = None) -> bytes:
    """SHA-256 of an expression's tree (a Merkle hash: class, then its arguments' digests).

    Canonical where pickles are not: a pickle writes a subexpression shared by two
    parents once and an equal copy twice, so the bicycle's Lagrangian loaded twice in one
    process pickled differently and missed the cache every time. Symbols carry their
    assumptions, numbers their exact value (a Float its mpf and precision). ``memo`` (by
    expression) makes a shared subtree cost once.
    """
    memo = {} if memo is None else memo
    if isinstance(expr, (tuple, list)):
        h = hashlib.sha256(b"(")
        for e in expr:
            h.update(expression_digest(e, memo))
        return h.digest()
    expr = sp.sympify(expr)
    key = (type(expr), expr)  # Float(1.0) == 1 in older sympy: never one memo entry
    found = memo.get(key)
    if found is not None:
        return found
    if isinstance(expr, sp.Symbol):
        text = f"{type(expr).__name__}:{expr.name}:{sorted(expr.assumptions0.items())}"
        if isinstance(expr, sp.Dummy):
            text += f":{expr.dummy_index}"
        digest = hashlib.sha256(text.encode()).digest()
    elif isinstance(expr, sp.Float):
        digest = hashlib.sha256(f"Float:{expr._mpf_}:{expr._prec}".encode()).digest()
    elif expr.is_Atom:
        digest = hashlib.sha256(sp.srepr(expr).encode()).digest()
    else:
        h = hashlib.sha256(type(expr).__name__.encode() + b"(")
        for a in expr.args:
            h.update(expression_digest(a, memo))
        digest = h.digest()
    memo[key] = digest
    return digest


def _generate(system, path: str) -> dict:
    geom = lagrangian_geometry(system, closed_form=True)  # the closed path is chosen by size
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
    # Chetaev's rule (DESIGN.md §2): mu = d phi/d v depends on v, and "h" is phi - mu v, so
    # that mu v + h is phi where the kernels and the loops form the residual.
    nonlinear = not system.is_affine
    if nonlinear:
        h = [R(f - sum((a * v for a, v in zip(ing.mu.row(i), system.velocities)), sp.S.Zero))
             for i, f in enumerate(system.phi)]
    g = [R(e) for e in system.holonomic]
    qs = [rename[q] for q in system.coordinates]
    vs = [rename[v] for v in system.velocities]
    # The geometry kernel reads (q, v) where its outputs depend on v: mu and h of a
    # nonlinear constraint, or W of a Lagrangian not quadratic in v (W = d2L/dv dv).
    geometry_v = nonlinear or any(e.free_symbols & set(vs) for e in W)
    L = R(system.lagrangian)
    # nhham's own derivative: sympy's diff spends most of its time on factors free of x
    lq = [derivative(L, q) for q in qs]
    phi = [R(e) for e in system.phi]
    jphi = [derivative(f, q) for f in phi for q in qs]

    # With forces the saddle kernel ends with the applied power Q . v (dE_L/dt gains
    # it: the energy balance of a forced or dissipative system).
    # With L depending on t the same entry carries -dL/dt: dE_L/dt = Q . v - dL/dt
    # - lambda . (mu v) (DESIGN.md §2).
    timed_L = system.lagrangian_depends_on_time
    powered = system.has_forces or timed_L
    applied = ([R(sp.Add(*[f * v for f, v in zip(system.generalized_forces,
                                                  system.velocities)])
                  - (sp.diff(system.lagrangian, system.time) if timed_L else 0))]
               if powered else [])
    kernels = {
        "saddle": ("qv", W + F + mu + drift + h + g + applied),
        "geometry": ("qv" if geometry_v else "q", W + mu + h + g),
        "energy": ("qv", [_energy(system, L, vs, W)]),
        "lq": ("qv", lq),
        "jphi": ("qv", jphi),
    }
    # L = v^T W v / 2 + b . v - V with b != 0 (a gyroscopic term): p = W v + b(q), what
    # the energy-exact integrator needs beside W (nhham.numerics.discrete_gradient)
    parts, quadratic = system.quadratic_parts, _is_quadratic(system)
    if parts is not None and not geometry_v:   # what the energy-exact integrator reads
        kernels["potential"] = ("q", [R(parts.V)])
        if not quadratic:
            kernels["linear"] = ("q", [R(e) for e in parts.b])
    if path == "closed_form":
        field = geom.projected_field
        acc = [R(field[n + i]) for i in range(n)]
        lam = [R(e) for e in geom.multipliers]
        kernels["closed"] = ("qv", acc + lam)

    printed = {name: _cse(expand_angle_sums(outputs, qs))
               for name, (_, outputs) in kernels.items()}
    # The kernels read only the parameters the expressions use (the model hands them
    # those values), so that a parameter that enters none of them changes no text: not
    # the sources' key, not the compiled library's.
    used = kernel_parameters(system)
    python = python_module(kernels, printed, n, len(used))
    slot = system.time_slot
    c = _c_module(printed, n, m, k, len(used), path,
                  forced=powered, time_slot=None if slot is None else used.index(slot),
                  newton_velocities=nonlinear, geometry_v=geometry_v)
    # the complex step's geometry kernel reads q only: none where the geometry reads v
    c_complex = "" if geometry_v else _c_complex_module(printed, n, m, k, len(used),
                                                       forced=powered)
    layout = {
        "n": n, "m": m, "k": k,
        "coordinate_names": tuple(q.name for q in system.coordinates),
        "velocity_names": tuple(v.name for v in system.velocities),
        # parameter_names, kernel_parameters (the positions in parameter_names of those
        # the kernels read), input_names, time_slot: the system's own
        **parameter_layout(system),
        "constraint_labels": tuple(system.constraint_labels),
        "holonomic_labels": tuple(f"holonomic[{i}]" for i in range(k)),
        "constant_W": not any(e.free_symbols & set(qs) for e in W),
        "quadratic": quadratic,
        # L = v^T W(q) v / 2 + b(q) . v - V(q) with b != 0: the kernel "linear" gives b
        "linear_terms": "linear" in kernels,
        "linear_constraints": system.is_linear,
        "name": system.name,
        "kernels": tuple(kernels),
        "forced": powered,
        # t in L or a constraint: the energy, residuals and conditions change with t;
        # the first scene key that uses it ("" for none)
        "time_in_geometry": _first_timed_key(system),
        "complex_kernels": bool(c_complex),
        # only with a nonlinear (Chetaev) constraint: velocities onto M_1 by Newton
        **({"nonlinear_constraints": True} if nonlinear else {}),
        # the geometry kernel reads (q, v): a nonlinear constraint, or W depending on v
        **({"geometry_reads_v": True} if geometry_v else {}),
    }
    return {"python": python, "c": c, "c_complex": c_complex, "layout": layout}


def _first_timed_key(system) -> str:
    """``lagrangian``, ``holonomic[i]`` or ``constraints[i]``: the first that depends on
    the time t, or ""."""
    if system.lagrangian_depends_on_time:
        return "lagrangian"
    nh = len(system.holonomic)
    labels = system.m1_labels[:nh] + system.constraint_labels[nh:]
    timed = [lab for lab, dep in zip(labels, system.time_dependent[:nh] +
                                     system.time_dependent[2 * nh:]) if dep]
    return timed[0] if timed else ""


def kernel_parameters(system) -> tuple:
    """The positions in ``system.parameters`` of the parameters the kernels read: those in
    the Lagrangian, the constraints or the forces, and the time slot; sorted.

    Examples
    --------
    >>> from nhham import System
    >>> s = System(["x"], "m*x_dot**2/2 - k*x**2/2", parameters=["c", "k", "m"])
    >>> kernel_parameters(s)
    (1, 2)
    """
    exprs = [system.lagrangian, *system.phi, *system.holonomic]
    if system.has_forces:
        exprs += list(system.generalized_forces)
    present = set().union(*(symbols_in(sp.sympify(e)) for e in exprs))  # memoised
    return tuple(i for i, p in enumerate(system.parameters)
                 if p in present or i == system.time_slot)


def _renaming(system) -> dict:
    """Map user symbols to safe generated names q0.., v0.., p0.. (the parameters the
    kernels read, :func:`kernel_parameters`, numbered in their order).

    User names may be Python keywords or C identifiers in use (``lambda``,
    ``I``); the generated code never sees them.
    """
    rename = {q: sp.Symbol(f"q{i}", real=True) for i, q in enumerate(system.coordinates)}
    rename.update({v: sp.Symbol(f"v{i}", real=True) for i, v in enumerate(system.velocities)})
    rename.update({system.parameters[i]: sp.Symbol(f"p{j}", real=True)
                   for j, i in enumerate(kernel_parameters(system))})
    return rename


def _energy(system, L, vs, W):
    """E_L = v^A dL/dv^A - L in the generated names (``L``, ``vs``, the entries ``W``):
    v^T W v / 2 + V when L = v^T W v / 2 + b . v - V (the b terms cancel), else by
    differentiation."""
    parts = system.quadratic_parts
    n = len(vs)
    if parts is None:
        return sp.Add(*[v * derivative(L, v) for v in vs]) - L
    rename = _renaming(system)
    half = sp.Add(*[W[i * n + j] * vs[i] * vs[j] for i in range(n) for j in range(n)]) / 2
    return half + sp.sympify(parts.V).xreplace(rename)


def _is_quadratic(system) -> bool:
    """True when L = 1/2 v^T W(q) v - V(q) (no linear-in-v terms, W free of v)."""
    parts = system.quadratic_parts
    if parts is not None:  # read from the terms of L: only b is left to look at
        return all(sp.simplify(b) == 0 for b in parts.b)
    W = system.hessian
    vs = set(system.velocities)
    if any(e.free_symbols & vs for e in W):
        return False
    v = sp.Matrix(system.velocities)
    p = sp.Matrix([sp.diff(system.lagrangian, s) for s in system.velocities])
    return all(sp.simplify(e) == 0 for e in (p - W * v))


def expand_angle_sums(outputs, coordinates, max_terms=3):
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


# ------------------------------------------------------------------ C text
class _CPrinter(C99CodePrinter):
    """C99 with small integer powers expanded to products (exact, faster); the terms
    in the expression's own order (sorting them is most of a printer's time)."""

    def __init__(self, settings=None):
        super().__init__({"order": "none", **(settings or {})})

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


class _ComplexCPrinter(_CPrinter):
    """C99 on ``double complex`` values: the complex functions of ``<complex.h>``, and the
    first-order continuations of |x| and atan2 (exact for the complex step, where the
    imaginary part is a derivative times a step of 1e-30)."""

    _functions = {"sin": "csin", "cos": "ccos", "tan": "ctan", "asin": "casin",
                  "acos": "cacos", "atan": "catan", "exp": "cexp", "log": "clog",
                  "sinh": "csinh", "cosh": "ccosh", "tanh": "ctanh", "asinh": "casinh",
                  "acosh": "cacosh", "atanh": "catanh", "sqrt": "csqrt",
                  "Abs": "nh_cabs", "atan2": "nh_catan2"}

    def __init__(self):
        super().__init__({"user_functions": dict(self._functions)})

    def _print_Pow(self, expr):
        b, e = expr.as_base_exp()
        if e.is_Integer and (2 <= int(e) <= 4 or -4 <= int(e) <= -1):
            return super()._print_Pow(expr)
        base = self._print(b)
        if e == sp.S.Half:
            return f"csqrt({base})"
        if e == -sp.S.Half:
            return f"(1.0/csqrt({base}))"
        return f"cpow({base}, {self._print(e)})"


#: Functions a complex-step kernel can evaluate (the others have no analytic
#: continuation there: the kernel is then not generated and numpy is used).
_COMPLEX_SAFE = frozenset(_ComplexCPrinter._functions) | {"Pow", "Mul", "Add"}


def _complex_safe(printed) -> bool:
    """Whether every expression of the kernels uses only :data:`_COMPLEX_SAFE` functions."""
    for temps, reduced in printed:
        for e in [x for _, x in temps] + list(reduced):
            for f in sp.sympify(e).atoms(sp.Function):
                if type(f).__name__ not in _COMPLEX_SAFE:
                    return False
            if sp.sympify(e).has(sp.Piecewise, sp.core.relational.Relational):
                return False
    return True


def _c_complex_kernel(fname, printed, n, npar, with_v=True):
    """A kernel on ``double complex`` states and parameters (the complex step of
    :mod:`nhham.numerics.chart`)."""
    temps, reduced = printed
    pr = _ComplexCPrinter()
    cx = "double complex"
    # Real parameters: most products have a parameter factor, and double * complex
    # costs half of complex * complex (a study moves parameters, never differentiates in
    # them here; the input matrix B differentiates in the inputs with numpy).
    body = [f"static void {fname}(const {cx} *y, const double *p, {cx} *out) {{"]
    body += [f"    const double p{i} = p[{i}]; (void)p{i};" for i in range(npar)]
    body += [f"    const {cx} q{i} = y[{i}]; (void)q{i};" for i in range(n)]
    if with_v:
        body += [f"    const {cx} v{i} = y[{n + i}]; (void)v{i};" for i in range(n)]
    body += [f"    const {cx} {sym} = {pr.doprint(expr)};" for sym, expr in temps]
    body += [f"    out[{j}] = {pr.doprint(e)};" for j, e in enumerate(reduced)]
    body.append("}")
    return body


#: The batch entry points of the complex kernels.
_COMPLEX_BATCH = """/* Complex-step kernels (nhham.numerics.chart): the saddle and geometry kernels on
   double complex states (real parameters), k states a call; row i of Y (stride ystride)
   and of P (stride pstride; 0: the same parameters for every state) gives row i of OUT.
   Compiled with -fcx-limited-range: products and quotients by the textbook formulas
   (no recovery of infinities and NaNs, which a complex step never meets). */
void nhham_saddle_cx_batch(long k, const double complex *Y, long ystride,
                           const double *P, long pstride, double complex *OUT) {
    for (long i = 0; i < k; i++) saddle_cx(Y + i * ystride, P + i * pstride, OUT + i * NOUT);
}
void nhham_geometry_cx_batch(long k, const double complex *Y, long ystride,
                             const double *P, long pstride, double complex *OUT) {
    for (long i = 0; i < k; i++)
        geometry_cx(Y + i * ystride, P + i * pstride, OUT + i * (NQ * NQ + NC * NQ + NC + NH));
}
"""

_COMPLEX_HELPERS = """#include <complex.h>
static inline double complex nh_cabs(double complex z) { return creal(z) < 0 ? -z : z; }
static inline double complex nh_catan2(double complex y, double complex x) {
    double xr = creal(x), yr = creal(y);
    return atan2(yr, xr) + I * ((xr * cimag(y) - yr * cimag(x)) / (xr * xr + yr * yr));
}
"""


def _c_complex_module(printed, n, m, k, npar, forced=False) -> str:
    """The complex kernels and their batch entry points, a translation unit of their
    own (built on first use: only the complex step needs them, and their long
    straight-line complex code takes a C compiler several times longer than the whole
    real library: the bicycle's 13 s against 3 s); empty when a kernel uses a function
    without a complex continuation."""
    if not _complex_safe([printed["saddle"], printed["geometry"]]):
        return ""
    head = [
        "/* Generated by nhham.numerics.codegen; do not edit: the complex-step kernels. */",
        f"#define NQ {n}",
        f"#define NC {m}",
        f"#define NH {k}",
        f"#define NOUT {n * n + n + m * n + 3 * m + k + int(forced)}",
        "#define _DEFAULT_SOURCE   /* M_PI, M_E, ... of sympy's printer under -std=c99 */",
        "#include <math.h>",
    ]
    lines = ["\n".join(head), _COMPLEX_HELPERS]
    lines += _c_complex_kernel("saddle_cx", printed["saddle"], n, npar)
    lines += _c_complex_kernel("geometry_cx", printed["geometry"], n, npar, with_v=False)
    lines.append(_COMPLEX_BATCH)
    return "\n".join(lines) + "\n"


def _c_module(printed, n, m, k, npar, path, forced=False, time_slot=None,
              newton_velocities=False, geometry_v=False) -> str:
    """The C translation unit: generated definitions and kernels, then the runtime files.

    Layout of the saddle kernel outputs (``out``): W (n*n, row-major), F (n), mu (m*n),
    drift (m), h (m), g (k), and with forces the applied power Q . v (1). A
    time-dependent system reads t from ``p[NHHAM_TIME_SLOT]``, which the loops set.
    """
    head = [
        "/* Generated by nhham.numerics.codegen; do not edit. The runtime below it comes from",
        "   nhham/numerics/c/ (see nhham.h there). */",
        f"#define NQ {n}",
        f"#define NC {m}",
        f"#define NH {k}",
        f"#define NN {n + m}",
        f"#define NOUT {n * n + n + m * n + 3 * m + k + int(forced)}",
        f"#define NPAR {npar}",
    ]
    if forced:  # the index of the applied power Q . v in the saddle kernel's outputs
        head.append(f"#define NHHAM_FORCED {n * n + n + m * n + 2 * m + k}")
    if time_slot is not None:
        head.append(f"#define NHHAM_TIME_SLOT {time_slot}")
    if newton_velocities:  # a nonlinear (Chetaev) constraint: mu and h read v
        head.append("#define NHHAM_GEOMETRY_V 1")
    if path == "closed_form":
        head.append("#define NHHAM_CLOSED_FORM 1")
    if "potential" in printed:   # L = v^T W v / 2 + b . v - V: the energy-exact loop
        head.append("#define NHHAM_DGRAD 1")
    if "linear" in printed:
        head.append("#define NHHAM_LINEAR_TERMS 1")
    lines = ["\n".join(head), c_defines(), runtime_source("nhham.h")]
    # Parameters may be unused; the (void) casts in the kernels keep compilers quiet.
    lines += _c_kernel("saddle", printed["saddle"], n, npar)
    lines += _c_kernel("geometry", printed["geometry"], n, npar, with_v=geometry_v)
    lines += _c_kernel("lagr_q", printed["lq"], n, npar)
    lines += _c_kernel("jphi", printed["jphi"], n, npar)
    if path == "closed_form":
        lines += _c_kernel("closed", printed["closed"], n, npar)
    for name in ("potential", "linear"):
        if name in printed:
            lines += _c_kernel(name, printed[name], n, npar, with_v=False)
    lines += [runtime_source(name) for name in RUNTIME_FILES]
    lines.append(runtime_source("closed.c" if path == "closed_form" else "pyext.c"))
    return "\n".join(lines) + "\n"


def runtime_source(name: str) -> str:
    """The text of one file of the C runtime (``nhham/numerics/c/<name>``, package data)."""
    return resources.files("nhham.numerics").joinpath("c", name).read_text(encoding="utf-8")
