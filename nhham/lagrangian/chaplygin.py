"""Abelian Chaplygin reduction: the constrained dynamics on the shape space.

A system is of Chaplygin type (abelian) when its coordinates split as q = (r, s) with

- L, the constraints and the forces free of s (the s are cyclic: translations in s are
  symmetries), and
- the constraints, linear in the velocities, solving for every s-velocity:
  s' = -A(r) r' (mu_s invertible, A = mu_s^{-1} mu_r).

Then the motion of r obeys the reduced Lagrange–d'Alembert equations on the shape space
S (Bloch–Krishnaprasad–Marsden–Murray; Koiller 1992): with L_c(r, r') = L(r, r', -A r'),
J_a = dL/ds'^a at s' = -A r' and the curvature B^a_{ab} = d_a A^a_b - d_b A^a_a,

    d/dt dL_c/dr'^a - dL_c/dr^a = J_a B^a_{ab} r'^b,

and s is reconstructed by s' = -A r'. Forces Q enter as Q_r - A^T Q_s at s' = -A r' (the
virtual displacements obey ds = -A dr). (By hand: the variations obey ds = -A dr, so the
Lagrange–d'Alembert equation is [EL(L)]_r - A^T d/dt J = 0; writing it in L_c the terms
d/dt J cancel and the curvature is what is left.) The reduced accelerations lifted back
must equal those of P(xi_L) on M_1: :func:`chaplygin_reduction` checks that exactly.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any

import sympy as sp

from nhham.errors import InputError
from nhham.lagrangian.algebra import cancel, tidy
from nhham.system.expressions import to_text
from nhham.lagrangian.decision import Decision

__all__ = ["singular_factors", "symmetry_choices", "ChaplyginReduction", "chaplygin_reduction"]


@dataclass(frozen=True)
class ChaplyginReduction:
    """The reduced data of an abelian Chaplygin system.

    Attributes
    ----------
    system : System
    shape, symmetry : tuple of sympy.Symbol
        The shape coordinates r (k of them) and the symmetry coordinates s (m).
    connection : sympy.Matrix, shape (m, k)
        A(r) with s' = -A r' (the reconstruction).
    lagrangian : sympy.Expr
        L_c(r, r') = L(r, r', -A r').
    momenta : sympy.Matrix, shape (m, 1)
        J_a = dL/ds'^a at s' = -A r' (functions of r, r').
    curvature : tuple of sympy.Matrix, each (k, k)
        B^a_{ab} = d A^a_b/d r^a - d A^a_a/d r^b, one per symmetry coordinate.
    gyroscopic : sympy.Matrix, shape (k, 1)
        J_a B^a_{ab} r'^b, the right-hand side of the reduced equations (with the
        forces below).
    accelerations : sympy.Matrix, shape (k, 1)
        r'' from the reduced equations.
    momentum_equations : tuple of (sympy.Symbol, sympy.Expr, sympy.Expr)
        For every shape coordinate r^c that L_c, J B r' and the forces do not contain
        (a symmetry of the reduced system that is not horizontal): (r^c, p_c = dL_c/dr'^c,
        dp_c/dt = (J B r')_c), the nonholonomic momentum equation (Bloch, Krishnaprasad,
        Marsden & Murray 1996); dp_c/dt = 0 makes p_c a constant of the motion.
    check : Decision
        The reduced r'' against P(xi_L)'s on M_1 (s' = -A r'), decided exactly.
    shape_forces : sympy.Matrix, shape (k, 1)
        The forces on r, Q_r - A^T Q_s at s' = -A r' (virtual displacements ds = -A dr).
    constraints : sympy.Matrix, shape (m - m', k)
        a(r) with a r' = 0: the constraints left on the shape space when fewer symmetry
        coordinates than constraints were named (the reduced equations then carry
        a^T lambda; :func:`nhham.lagrangian.chaplygin_stages.reduce_again` takes them).
    """

    system: Any
    shape: tuple
    symmetry: tuple
    connection: sp.Matrix
    lagrangian: sp.Expr
    momenta: sp.Matrix
    curvature: tuple
    gyroscopic: sp.Matrix
    accelerations: sp.Matrix
    check: Decision
    shape_forces: sp.Matrix
    constraints: sp.Matrix
    momentum_equations: tuple = ()

    @property
    def shape_velocities(self) -> tuple:
        return tuple(velocities_of(self.system, self.shape))

    @property
    def gyroscopic_form(self) -> sp.Matrix:
        """G_{ab} = J_a B^a_{ab}, shape (k, k), antisymmetric: the reduced equations' right-hand
        side is G r' and the compressed 2-form's dr^a ^ dr^b part is -1/2 G_{ab}."""
        return gyroscopic_form(self.momenta, self.curvature)

    @property
    def reconstruction(self) -> sp.Matrix:
        """s' = -A r', shape (m, 1)."""
        return -self.connection * sp.Matrix(self.shape_velocities)

    @property
    def lift(self) -> dict:
        """The symmetry velocities on M_1, s' = -A r' (a map of symbols)."""
        velocity = dict(zip(self.system.coordinates, self.system.velocities))
        return dict(zip([velocity[s] for s in self.symmetry], self.reconstruction))

    @property
    def stages(self) -> tuple:
        return (self,)

    def stage_dict(self) -> dict:
        """This step alone: the symmetry it reduced (the JSON ``stages`` entry)."""
        return {"shape_coordinates": [to_text(r) for r in self.shape],
                "reduced_coordinates": [to_text(s) for s in self.symmetry],
                "by": "symmetry", "level": {},
                "connection": [[to_text(e) for e in self.connection.row(i)]
                               for i in range(self.connection.rows)]}

    def to_dict(self) -> dict:
        return reduced_data(self, {}, [self.stage_dict()])


def velocities_of(system, coordinates) -> list:
    """The system's velocity symbols of ``coordinates``, in their order."""
    velocity = dict(zip(system.coordinates, system.velocities))
    return [velocity[c] for c in coordinates]


def reduced_data(red, level: dict, stages: list) -> dict:
    """The JSON data of a reduction (first step or a further one): ``level`` and ``stages``
    are the step's own."""
    return {
        "shape_coordinates": [to_text(r) for r in red.shape],
        "symmetry_coordinates": [to_text(s) for s in red.symmetry],
        "connection": [[to_text(e) for e in red.connection.row(i)]
                       for i in range(red.connection.rows)],
        "reduced_lagrangian": to_text(red.lagrangian),
        "momenta": [to_text(e) for e in red.momenta],
        "curvature": [[[to_text(e) for e in B.row(i)] for i in range(B.rows)]
                      for B in red.curvature],
        "gyroscopic": [to_text(e) for e in red.gyroscopic],
        "accelerations": [to_text(e) for e in red.accelerations],
        "reconstruction": [to_text(e) for e in red.reconstruction],
        "forces": [to_text(e) for e in red.shape_forces],
        "shape_constraints": [to_text(e) for e in red.constraints * sp.Matrix(
            red.shape_velocities)],
        "momentum_equations": [{"coordinate": to_text(c), "momentum": to_text(p),
                                "rate": to_text(r)} for c, p, r in red.momentum_equations],
        "check": {"agrees": bool(red.check.value), "method": red.check.method,
                  "detail": red.check.detail},
        "level": level,
        "stages": stages,
    }


def chaplygin_reduction(system, symmetry=None) -> ChaplyginReduction:
    """Reduce an abelian Chaplygin system to its shape space.

    Parameters
    ----------
    system : System
        Linear velocity constraints solving for m cyclic coordinates, no holonomic
        constraint, autonomous.
    symmetry : sequence of str, optional
        The symmetry coordinates s (default: among the cyclic coordinates, those whose
        velocities the constraints solve for everywhere, the simplest A first).

    Returns
    -------
    ChaplyginReduction

    Raises
    ------
    InputError
        When the system is not of Chaplygin type, saying why (key ``constraints``).

    Examples
    --------
    The nonholonomic particle z' = y x': s = z, A = (-y, 0), L_c = ((1 + y^2) x'^2 + y'^2)/2,
    J = y x', B_xy = 1, so d/dt((1 + y^2) x') = y x' y' and y'' = -y x'^2 + y x'^2 = 0.

    >>> from nhham import System
    >>> red = chaplygin_reduction(System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2",
    ...                                  ["z_dot - y*x_dot"]))
    >>> red.shape, red.symmetry, red.lagrangian
    ((x, y), (z,), x_dot**2*y**2/2 + x_dot**2/2 + y_dot**2/2)
    >>> red.curvature[0], red.accelerations.T, red.check.value
    (Matrix([
    [ 0, 1],
    [-1, 0]]), Matrix([[-x_dot*y*y_dot/(y**2 + 1), 0]]), True)
    """
    symmetry, A, rest = _split(system, symmetry)
    q, v = list(system.coordinates), list(system.velocities)
    shape = tuple(c for c in q if c not in symmetry)
    vel = dict(zip(q, v))
    rdot = sp.Matrix([vel[r] for r in shape])
    sdot = [vel[s] for s in symmetry]
    on_m1 = dict(zip(sdot, -A * rdot))
    L_c = _tidy(system.lagrangian.xreplace(on_m1))
    J = sp.Matrix([_tidy(sp.diff(system.lagrangian, w).xreplace(on_m1)) for w in sdot])
    curvature = curvatures(A, shape)
    gyro = (gyroscopic_form(J, curvature) * rdot).applyfunc(_tidy)
    forces = _reduced_forces(system, shape, symmetry, A, on_m1)
    acc = reduced_accelerations(L_c, shape, rdot, gyro + forces, rest)
    check = check_reduction(system, shape, on_m1, acc)
    return ChaplyginReduction(system, shape, tuple(symmetry), A, L_c, J, curvature, gyro,
                              acc, check, forces, rest,
                              momentum_equations(shape, rdot, L_c, gyro + forces, rest))


def curvatures(A, shape) -> tuple:
    """B^a_{ab} = d A^a_b/d r^a - d A^a_a/d r^b, one (k, k) matrix per row of A.

    Examples
    --------
    >>> x, y = sp.symbols("x y")
    >>> curvatures(sp.Matrix([[-y, 0]]), (x, y))
    (Matrix([
    [ 0, 1],
    [-1, 0]]),)
    """
    k = len(shape)
    return tuple(sp.Matrix(k, k, lambda i, j: _tidy(sp.diff(A[a, j], shape[i])
                                                    - sp.diff(A[a, i], shape[j])))
                 for a in range(A.rows))


def gyroscopic_form(J, curvature) -> sp.Matrix:
    """J_a B^a, shape (k, k).

    Examples
    --------
    >>> gyroscopic_form(sp.Matrix([2]), (sp.Matrix([[0, 1], [-1, 0]]),))
    Matrix([
    [ 0, 2],
    [-2, 0]])
    """
    k = curvature[0].rows if curvature else 0
    return sp.Matrix(k, k, lambda i, j: sum((J[a] * B[i, j] for a, B in enumerate(curvature)),
                                            sp.S.Zero))


def _split(system, symmetry=None) -> tuple:
    """(symmetry coordinates, A) or InputError saying why the system is not Chaplygin."""
    def refuse(why):
        raise InputError(f"the system is not of Chaplygin type: {why}", key="constraints")

    if system.holonomic:
        refuse("it has holonomic constraints (eliminate them with coordinates on Q first)")
    if system.time is not None:
        refuse("it depends on the time t")
    if not system.is_affine or not system.is_linear:
        refuse("its constraints are not linear in the velocities (mu(q) v = 0)")
    m = system.m
    if m == 0:
        refuse("it has no velocity constraint")
    cyclic = _cyclic(system)
    if symmetry is None and len(cyclic) < m:
        refuse(f"{m} constraint(s) need as many cyclic coordinates (absent from L, the "
               f"constraints and the forces); found {len(cyclic)}"
               + (f" ({', '.join(map(str, cyclic))}; name fewer with symmetry to keep the "
                  f"other constraints on the shape space)" if cyclic else ""))
    if symmetry is not None:
        named = {str(c): c for c in system.coordinates}
        unknown = [s for s in symmetry if s not in named]
        if unknown or not 0 < len(symmetry) <= m:
            refuse(f"symmetry: 1 to {m} coordinate(s) of the system expected, got "
                   f"{', '.join(symmetry) or 'none'}")
        not_cyclic = [s for s in symmetry if named[s] not in cyclic]
        if not_cyclic:
            refuse(f"symmetry: {', '.join(not_cyclic)} not cyclic (it enters L, a "
                   f"constraint or a force)")
        groups = [tuple(named[s] for s in symmetry)]
    else:
        groups = list(itertools.combinations(cyclic, m))
    found = _solved(system, groups)
    if not found:
        refuse("the constraints do not solve for the velocities of "
               + ("the symmetry coordinates given" if symmetry is not None else
                  f"any {m} of the cyclic coordinates {', '.join(map(str, cyclic))}"))
    _, group, A, rest = min(found, key=lambda f: f[0])
    return group, A, rest


def singular_factors(connection, shape) -> tuple:
    """The factors of the connection's denominators that depend on the shape: A(r), the
    reduced data and the reconstruction s' = -A r' are singular where one vanishes (the
    constraints do not solve for s' there), so the reduction does not describe a motion
    that reaches it; other symmetry coordinates may (:func:`symmetry_choices`).

    >>> x, y = sp.symbols("x y")
    >>> singular_factors(sp.Matrix([[-y/sp.sin(x)**2, 0]]), (x, y))
    (sin(x),)
    """
    shape = set(shape)
    found: dict = {}
    for entry in connection:
        _, den = sp.fraction(sp.together(entry))
        for factor in sp.Mul.make_args(sp.factor_terms(den)):
            base = factor.base if factor.is_Pow else factor
            if base.free_symbols & shape:
                found.setdefault(sp.srepr(base), base)
    return tuple(found.values())


def symmetry_choices(system) -> tuple:
    """Every set of symmetry coordinates the reduction can take (cyclic coordinates whose
    velocities the constraints solve for), the simplest connection first, as tuples of
    names.

    >>> from nhham import System
    >>> symmetry_choices(System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2",
    ...                         ["z_dot - x_dot"]))
    (('x',), ('z',))
    """
    try:
        _split(system)
    except InputError:
        return ()
    found = _solved(system, itertools.combinations(_cyclic(system), system.m))
    return tuple(tuple(str(c) for c in group)
                 for _, group, _, _ in sorted(found, key=lambda f: f[0]))


def _cyclic(system) -> list:
    """The coordinates absent from L, the constraints and the forces."""
    used = set(system.lagrangian.free_symbols)
    for e in list(system.phi) + (list(system.generalized_forces) if system.has_forces else []):
        used |= sp.sympify(e).free_symbols
    return [c for c in system.coordinates if c not in used]


def _solved(system, groups) -> list:
    """(key, group, A, a) for each group of coordinates whose velocities the constraints
    solve for (:func:`solve_for`)."""
    index = {c: i for i, c in enumerate(system.coordinates)}
    found = []
    for group in groups:
        solved = solve_for(system.mu, [index[c] for c in group], system.coordinates)
        if solved is not None:
            found.append((solved[0], tuple(group), solved[1], solved[2]))
    return found


def solve_for(mu, cols, coordinates) -> tuple | None:
    """(rank key, A, a) when m' = len(cols) rows of mu r' + mu_s s' = 0 solve for the
    velocities of the columns cols (s' = -A r'), a: the other rows with s' eliminated,
    a r' = 0 (constraints left on the shape space); None when no rows do.

    Examples
    --------
    >>> x, y, z = sp.symbols("x y z")
    >>> key, A, a = solve_for(sp.Matrix([[-y, 0, 1], [1, 1, 0]]), [2], (x, y, z))
    >>> A, a
    (Matrix([[-y, 0]]), Matrix([[1, 1]]))
    """
    m, n = mu.rows, mu.cols
    rest_cols = [i for i in range(n) if i not in cols]
    found = []
    for rows in itertools.combinations(range(m), len(cols)):
        mu_s = mu.extract(list(rows), cols)
        det = cancel(mu_s.det())
        if det != 0:
            A = (mu_s.inv() * mu.extract(list(rows), rest_cols)).applyfunc(cancel)
            # prefer s' solved everywhere (det mu_s constant), then the simplest A
            found.append(((bool(det.free_symbols & set(coordinates)), sp.count_ops(A)),
                          rows, A))
    if not found:
        return None
    key, rows, A = min(found, key=lambda f: f[0])
    others = [i for i in range(m) if i not in rows]
    a = (mu.extract(others, rest_cols) - mu.extract(others, cols) * A).applyfunc(cancel) \
        if others else sp.zeros(0, len(rest_cols))
    return key, A, a


def momentum_equations(shape, rdot, L_c, right, constraints=None, tidy=None) -> tuple:
    """(r^c, dL_c/dr'^c, its rate) for the shape coordinates that L_c, the right-hand side
    G r' + Q and the constraints left on the shape space do not contain, and that no such
    constraint moves (their column is zero): d/dt dL_c/dr'^c = (G r' + Q)_c.

    Examples
    --------
    >>> x, y, xd, yd = sp.symbols("x y x_dot y_dot")
    >>> momentum_equations((x, y), (xd, yd), ((1 + y**2)*xd**2 + yd**2)/2,
    ...                    sp.Matrix([y*xd*yd, -y*xd**2]))
    ((x, x_dot*y**2 + x_dot, x_dot*y*y_dot),)
    """
    a = constraints if constraints is not None else sp.zeros(0, len(shape))
    used = set(L_c.free_symbols) | set().union(*(e.free_symbols for e in right))
    used |= set().union(*(e.free_symbols for e in a))
    return tuple((r, (tidy or _tidy)(sp.diff(L_c, w)), right[i]) for i, (r, w) in
                 enumerate(zip(shape, rdot))
                 if r not in used and all(a[j, i] == 0 for j in range(a.rows)))


def reduced_accelerations(L_c, shape, rdot, right, constraints=None, tidy=None) -> sp.Matrix:
    """r'' from d/dt dL_c/dr' - dL_c/dr = right (+ a^T lambda with a r' = 0 when
    constraints a remain on the shape space: the saddle-point system in r'', lambda).

    Examples
    --------
    >>> y, xd, yd = sp.symbols("y x_dot y_dot")
    >>> reduced_accelerations(((1 + y**2)*xd**2 + yd**2)/2, (sp.Symbol("x"), y), (xd, yd),
    ...                       [y*xd*yd, -y*xd**2]).T
    Matrix([[-x_dot*y*y_dot/(y**2 + 1), 0]])
    """
    k = len(shape)
    W = sp.Matrix(k, k, lambda i, j: sp.diff(L_c, rdot[i], rdot[j]))
    rhs = []
    for i, r in enumerate(shape):
        p = sp.diff(L_c, rdot[i])
        mixed = sum((sp.diff(p, s) * w for s, w in zip(shape, rdot)), sp.S.Zero)
        rhs.append(sp.diff(L_c, r) - mixed + right[i])
    if constraints is None or constraints.rows == 0:
        return W.LUsolve(sp.Matrix(rhs)).applyfunc(tidy or _tidy)
    a, m2 = constraints, constraints.rows
    # a r'' + (d/dt a) r' = 0
    drift = [-sum((sp.diff(a[i, j], r) * w * rdot[j] for j in range(k)
                   for r, w in zip(shape, rdot)), sp.S.Zero) for i in range(m2)]
    K = sp.zeros(k + m2, k + m2)
    K[:k, :k], K[:k, k:], K[k:, :k] = W, a.T, a
    return K.LUsolve(sp.Matrix(rhs + drift))[:k, :].applyfunc(tidy or _tidy)


def _reduced_forces(system, shape, symmetry, A, on_m1) -> sp.Matrix:
    """The forces on r: the virtual displacements obey ds = -A dr, so Q_r - A^T Q_s, at
    s' = -A r' (forces may depend on the velocities)."""
    k = len(shape)
    if not system.has_forces:
        return sp.zeros(k, 1)
    Q = dict(zip(system.coordinates, system.generalized_forces))
    Q_r = sp.Matrix([Q[r] for r in shape])
    Q_s = sp.Matrix([Q[s] for s in symmetry])
    return (Q_r - A.T * Q_s).xreplace(on_m1).applyfunc(_tidy)


def _tidy(expr) -> sp.Expr:
    """cancel, and sin^2 + cos^2 = 1 where the expression has them (the reduced data are
    read by people: the 3-D disc's accelerations shrink fourfold)."""
    if sp.count_ops(expr) > TIDY_OPS:  # a Chaplygin sphere's: left as derived
        return expr
    # Polynomial arithmetic modulo sin^2 + cos^2 = 1 (bounded by the terms), not sympy's
    # trigsimp, whose search took 10 s on a rigid body's reduced data in Euler angles.
    expr = tidy(expr)
    return sp.factor_terms(expr) if expr.has(sp.sin, sp.cos) else expr


#: Largest expression (sympy operations) that is tidied (cancel, trigsimp) for reading.
TIDY_OPS = 400

_POINTS, _DIGITS = 4, 30


def check_reduction(system, shape, on_m1, acc) -> Decision:
    """The reduced r'' against the r'' of P(xi_L) on M_1: exactly (the closed form of
    P(xi_L)) where W^-1 is small in closed form (``closed_form_affordable``: the size of
    W, not n; the 3-D disc's took minutes, a rigid body's in Euler angles as long), else
    at seeded points of M_1 in 30 digits (the saddle-point system W a + mu^T lambda = F,
    mu a = -drift solved there).

    Examples
    --------
    >>> from nhham import System
    >>> particle = System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2",
    ...                   ["z_dot - y*x_dot"])
    >>> x, y, z = particle.coordinates
    >>> xd, yd, zd = particle.velocities
    >>> check_reduction(particle, (x, y), {zd: y*xd},
    ...                 sp.Matrix([-xd*y*yd/(1 + y**2), 0])).value
    True
    """
    from nhham.lagrangian.geometry import lagrangian_geometry

    n = system.n
    index = {c: i for i, c in enumerate(system.coordinates)}
    if lagrangian_geometry(system).closed_form_affordable:
        field = lagrangian_geometry(system, closed_form=True).projected_field
        diff = [cancel(sp.together(field[n + index[r]].xreplace(on_m1) - a))
                for r, a in zip(shape, acc)]
        diff = [d if d == 0 else sp.simplify(d) for d in diff]
        agrees = all(d == 0 for d in diff)
        detail = ("the reduced accelerations lifted back (s' = -A r') equal those of P(xi_L) "
                  "on M_1: the difference cancels" if agrees else
                  "the reduced accelerations differ from P(xi_L)'s: " + "; ".join(
                      f"{r}'': {d}" for r, d in zip(shape, diff) if d != 0))
        return Decision(agrees, "exact", detail)
    return _check_at_points(system, shape, on_m1, acc)


def _check_at_points(system, shape, on_m1, acc) -> Decision:
    import random

    from nhham.lagrangian.geometry import lagrangian_geometry

    ing = lagrangian_geometry(system).ingredients
    n, m = system.n, system.m
    index = {c: i for i, c in enumerate(system.coordinates)}
    K = sp.zeros(n + m, n + m)
    rng = random.Random(20261127)
    worst = sp.S.Zero
    values = dict(system.exact_parameter_values)
    for _ in range(_POINTS):
        at = {p: sp.Float(rng.uniform(0.3, 1.3), _DIGITS) for p in system.parameters
              if p not in values}
        at.update({p: sp.Float(v, _DIGITS) for p, v in values.items()})
        at.update({q: sp.Float(rng.uniform(0.3, 1.3), _DIGITS) for q in system.coordinates})
        at.update({w: sp.Float(rng.uniform(-1, 1), _DIGITS) for w in system.velocities
                   if w not in on_m1})
        at.update({w: e.xreplace(at).evalf(_DIGITS) for w, e in on_m1.items()})
        K[:n, :n] = ing.W.xreplace(at).evalf(_DIGITS)
        mu = ing.mu.xreplace(at).evalf(_DIGITS)
        K[:n, n:], K[n:, :n] = mu.T, mu
        rhs = sp.Matrix.vstack(ing.forcing.xreplace(at), -ing.drift.xreplace(at)).evalf(_DIGITS)
        a = K.LUsolve(rhs)
        for r, reduced in zip(shape, acc):
            d = abs(a[index[r]] - reduced.xreplace(at).evalf(_DIGITS))
            worst = max(worst, d / max(1, abs(a[index[r]])))
    agrees = worst < sp.Float(10) ** (10 - _DIGITS)
    return Decision(bool(agrees), "sampled",
                    f"the reduced accelerations against P(xi_L)'s on M_1 at {_POINTS} seeded "
                    f"points in {_DIGITS} digits (the saddle-point system solved there): "
                    f"largest relative difference {float(worst):.3g}", samples=_POINTS)
