"""A further abelian Chaplygin step on the shape space of a Chaplygin reduction.

After the first reduction (:mod:`nhham.lagrangian.chaplygin`) the motion of the shape
r = (r~, c) obeys

    d/dt dL_c/dr' - dL_c/dr = G r' + Q + a^T lambda,   a r' = 0,

with G antisymmetric (J_a B^a), Q the reduced forces and a the constraints left on the
shape space. When a coordinate c is cyclic (absent from L_c, G, Q and a) and linear
constraints solve c' = -A2(r~) r~', the step repeats on r~: the virtual displacements obey
dc = -A2 dr~, so with T = [I; -A2] (r' = T r~') the equations of r~ are T^T of the above,
and written in L_c2(r~, r~') = L_c(r~, r~', -A2 r~') they read (the calculation of the
first step, c cyclic in L_c)

    d/dt dL_c2/dr~' - dL_c2/dr~ = (T^T G T + J2 B2) r~' + T^T Q (+ the constraints left),

all at c' = -A2 r~', with J2 = dL_c/dc' there and B2 the curvature of A2. The gyroscopic
2-form of the second stage is T^T G T + J2 B2: the one that :func:`hamiltonize` reads.

Two sources of the constraint solving for c':

- constraints left on the shape space by the first step (the rubber ball's no-twist
  condition after reducing by the contact point);
- a momentum level p_c = dL_c/dc' = 0 of a cyclic c whose momentum equation has rate 0
  (the Chaplygin ball's yaw: the vertical angular momentum about the contact point). On
  that level the motion obeys the linear constraint dp_c/dr' r' = 0 with a zero
  multiplier, so the step gives the motion ON THAT LEVEL only; there J2 = p_c = 0 and
  only T^T G T remains. (Only the level 0: another level is an affine constraint.)

The reduced accelerations lifted back through both reconstructions are checked against
P(xi_L) of the scene at points of M_1 (on the level, for a level).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import sympy as sp

from nhham.errors import InputError
from nhham.lagrangian.algebra import cancel, normal_form
from nhham.lagrangian.chaplygin import (
    TIDY_OPS, check_reduction, curvatures, gyroscopic_form, momentum_equations,
    reduced_accelerations, reduced_data, velocities_of,
    solve_for,
)
from nhham.lagrangian.decision import Decision
from nhham.system.expressions import to_text

__all__ = ["ChaplyginStage", "reduce_again"]


@dataclass(frozen=True)
class ChaplyginStage:
    """The data of a further Chaplygin step (the attributes of
    :class:`~nhham.lagrangian.chaplygin.ChaplyginReduction`, for the new shape r~).

    Attributes
    ----------
    previous : ChaplyginReduction or ChaplyginStage
        The reduction this step starts from.
    shape : tuple of sympy.Symbol
        r~, the previous shape without the eliminated coordinates.
    eliminated : tuple of sympy.Symbol
        c, the coordinates reduced by this step.
    connection : sympy.Matrix
        A2 with c' = -A2 r~'.
    lagrangian : sympy.Expr
        L_c2(r~, r~').
    momenta : sympy.Matrix
        J2 = dL_c/dc' at c' = -A2 r~' (zero on a momentum level 0).
    curvature : tuple of sympy.Matrix
        B2, the curvature of A2.
    restricted : sympy.Matrix
        T^T G T at c' = -A2 r~' (the previous gyroscopic form restricted).
    shape_forces : sympy.Matrix
        T^T Q at c' = -A2 r~'.
    constraints : sympy.Matrix
        The constraints left on r~ (a r~' = 0).
    accelerations : sympy.Matrix
        r~''.
    check : Decision
        r~'' lifted back through every reconstruction against P(xi_L) on M_1.
    level : tuple of (sympy.Symbol, sympy.Expr)
        (c, value) of the momentum levels the step holds on; empty for a constraint step.
    momentum_equations : tuple
        As for the first step, on r~.
    """

    previous: Any
    shape: tuple
    eliminated: tuple
    connection: sp.Matrix
    lagrangian: sp.Expr
    momenta: sp.Matrix
    curvature: tuple
    restricted: sp.Matrix
    shape_forces: sp.Matrix
    constraints: sp.Matrix
    accelerations: sp.Matrix
    check: Decision
    level: tuple = ()
    momentum_equations: tuple = ()

    @property
    def system(self):
        return self.previous.system

    @property
    def symmetry(self) -> tuple:
        """Every coordinate reduced so far (the first step's, then this one's)."""
        return tuple(self.previous.symmetry) + tuple(self.eliminated)

    @property
    def shape_velocities(self) -> tuple:
        return tuple(velocities_of(self.system, self.shape))

    @property
    def gyroscopic_form(self) -> sp.Matrix:
        """T^T G T + J2 B2, shape (k2, k2), antisymmetric."""
        if not self.curvature:
            return self.restricted
        return self.restricted + gyroscopic_form(self.momenta, self.curvature)

    @property
    def gyroscopic(self) -> sp.Matrix:
        return self.gyroscopic_form * sp.Matrix(self.shape_velocities)

    @property
    def reconstruction(self) -> sp.Matrix:
        """c' = -A2 r~'."""
        return -self.connection * sp.Matrix(self.shape_velocities)

    @property
    def lift(self) -> dict:
        """Every reduced velocity (all steps) in terms of r~'."""
        here = dict(zip(velocities_of(self.system, self.eliminated), self.reconstruction))
        return {**{w: e.xreplace(here) for w, e in self.previous.lift.items()}, **here}

    @property
    def stages(self) -> tuple:
        return tuple(self.previous.stages) + (self,)

    def stage_dict(self) -> dict:
        """This step alone: what it eliminated, by which constraint, on which level."""
        return {"shape_coordinates": [to_text(r) for r in self.shape],
                "reduced_coordinates": [to_text(c) for c in self.eliminated],
                "by": "momentum level" if self.level else "constraint",
                "level": {to_text(c): to_text(v) for c, v in self.level},
                "connection": [[to_text(e) for e in self.connection.row(i)]
                               for i in range(self.connection.rows)]}

    def to_dict(self) -> dict:
        return reduced_data(self, {to_text(c): to_text(v) for c, v in self.level},
                            [s.stage_dict() for s in self.stages])



def reduce_again(reduction, coordinates, *, level=None) -> ChaplyginStage:
    """Reduce a Chaplygin reduction once more, by shape coordinates c cyclic in it.

    Parameters
    ----------
    reduction : ChaplyginReduction or ChaplyginStage
    coordinates : sequence of str
        c, shape coordinates of ``reduction`` absent from its L_c, gyroscopic form, forces
        and remaining constraints.
    level : mapping of str to number, optional
        Reduce c on the momentum level p_c = dL_c/dc' = value (only 0; p_c must be
        conserved, its rate zero). Without it the constraints left on the shape space must
        solve for c'.

    Returns
    -------
    ChaplyginStage

    Raises
    ------
    InputError
        An unknown or non-cyclic c (key ``then``), a level that is not 0 or whose momentum
        is not conserved (key ``level``), constraints that do not solve for c'.

    Examples
    --------
    The nonholonomic particle z' = y x' reduced by z has p_x = (1 + y^2) x' with rate
    y x' y' (not conserved); with a no-drift constraint x' = y' on the shape space
    instead, x is reduced by it: L_c2 = (2 + y^2) y'^2/2.

    >>> from nhham import System
    >>> from nhham.lagrangian.chaplygin import chaplygin_reduction
    >>> first = chaplygin_reduction(System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + "
    ...     "z_dot**2)/2", ["z_dot - y*x_dot", "x_dot - y_dot"]), symmetry=["z"])
    >>> second = reduce_again(first, ["x"])
    >>> second.shape, second.symmetry, sp.factor(second.lagrangian)
    ((y,), (z, x), y_dot**2*(y**2 + 2)/2)
    >>> second.accelerations, second.check.value
    (Matrix([[-y*y_dot**2/(y**2 + 2)]]), True)
    """
    names = {str(r): r for r in reduction.shape}
    unknown = [c for c in coordinates if c not in names]
    if unknown or not coordinates:
        raise InputError(f"then: {', '.join(unknown) or 'nothing'} not a shape coordinate of "
                         f"the reduction (shape: {', '.join(names)})", key="then")
    c = [names[x] for x in coordinates]
    rdot = list(reduction.shape_velocities)
    # tidied: J_a B^a of a rolling body shows the cyclic angle until sin^2 + cos^2 = 1 is used
    G = reduction.gyroscopic_form.applyfunc(_tidy)
    Q, a = reduction.shape_forces, reduction.constraints
    _refuse_unless_cyclic(c, reduction.lagrangian, G, Q, a)
    cols = [reduction.shape.index(x) for x in c]
    if level is not None:
        rows = _level_rows(reduction, c, level)
    else:
        rows = a
        if a.rows == 0:
            raise InputError(f"then: no constraint is left on the shape space to solve for "
                             f"{', '.join(coordinates)}' (give a momentum level with level)",
                             key="then")
    solved = solve_for(rows, cols, reduction.shape)
    if solved is None:
        raise InputError(f"then: the {'level' if level is not None else 'constraints'} do "
                         f"not solve for {', '.join(coordinates)}'", key="then")
    _, A2, rest = solved
    shape = tuple(r for r in reduction.shape if r not in c)
    kept = [i for i in range(len(reduction.shape)) if i not in cols]
    rdot2 = sp.Matrix([rdot[i] for i in kept])
    cdot = [rdot[i] for i in cols]
    on = dict(zip(cdot, -A2 * rdot2))
    T = sp.zeros(len(reduction.shape), len(shape))
    for j, i in enumerate(kept):
        T[i, j] = 1
    for j, i in enumerate(cols):
        T[i, :] = -A2[j, :]
    L2 = _restricted_lagrangian(reduction.lagrangian, rdot, on, T, rdot2)
    J2 = sp.Matrix([_tidy(sp.diff(reduction.lagrangian, w).xreplace(on)) for w in cdot])
    B2 = curvatures(A2, shape)
    restricted = (T.T * G.xreplace(on) * T).applyfunc(_tidy)
    forces = (T.T * Q.xreplace(on)).applyfunc(_tidy)
    if level is not None:  # none left: _level_rows refuses constraints on the shape space
        rest = sp.zeros(0, len(shape))
    gyro = (restricted + (gyroscopic_form(J2, B2) if B2 else sp.zeros(len(shape)))) * rdot2
    acc = reduced_accelerations(L2, shape, rdot2, gyro + forces, rest if rest.rows else None,
                                 tidy=_tidy_small)
    lift_here = dict(zip(cdot, -A2 * rdot2))
    lift = {**{w: e.xreplace(lift_here) for w, e in reduction.lift.items()}, **lift_here}
    check = check_reduction(reduction.system, shape, lift, acc)
    levels = tuple((x, sp.S.Zero) for x in c) if level is not None else ()
    return ChaplyginStage(reduction, shape, tuple(c), A2, L2, J2, B2, restricted, forces,
                          rest, acc, check, levels,
                          momentum_equations(shape, list(rdot2), L2, gyro + forces, rest,
                                             tidy=_tidy_small))


def _restricted_lagrangian(L_c, rdot, on, T, rdot2) -> sp.Expr:
    """L_c(r~, r~', -A2 r~'): for L_c quadratic in r' as 1/2 r~'^T (T^T W T) r~' +
    (T^T b) r~' + L_c(v = 0) with each coefficient tidied (substituted whole, the
    Chaplygin ball's is left too large to tidy, and hamiltonize inverts its Hessian)."""
    W = sp.hessian(L_c, rdot)
    if any(e.free_symbols & set(rdot) for e in W):
        return _tidy(L_c.xreplace(on))
    zero = {w: 0 for w in rdot}
    b = sp.Matrix([sp.diff(L_c, w).xreplace(zero) for w in rdot])
    W2 = (T.T * W * T).applyfunc(_tidy)
    b2 = (T.T * b).applyfunc(_tidy)
    v = sp.Matrix(rdot2)
    return sp.Add(*[W2[i, j] * v[i] * v[j] / 2 for i in range(len(v)) for j in range(len(v))],
                  *[b2[i] * v[i] for i in range(len(v))], _tidy(L_c.xreplace(zero)))


def _tidy(expr) -> sp.Expr:
    """One fraction reduced modulo sin^2 + cos^2 = 1 in polynomial rings (trigsimp, the
    first step's tidying, takes a minute on the Chaplygin ball's second step)."""
    return normal_form(expr)


def _tidy_small(expr) -> sp.Expr:
    """:func:`_tidy` up to TIDY_OPS operations (the accelerations, for reading: the Chaplygin
    ball's are left as derived, their check is at points)."""
    return normal_form(expr) if sp.count_ops(expr) <= TIDY_OPS else expr


def _refuse_unless_cyclic(c, L_c, G, Q, a) -> None:
    where = {"L_c": {L_c}, "the gyroscopic form": set(G), "the forces": set(Q),
             "the constraints left on the shape space": set(a)}
    for x in c:
        enters = [name for name, exprs in where.items()
                  if any(x in e.free_symbols for e in exprs)]
        if enters:
            raise InputError(f"then: {x} is not cyclic in the reduced system (it enters "
                             f"{', '.join(enters)})", key="then")


def _level_rows(reduction, c, level) -> sp.Matrix:
    """dp_c/dr' (the rows of the linear constraint p_c = 0) after checking that the level
    is 0, p_c linear in r' and conserved."""
    named = {str(x): x for x in c}
    if set(map(str, level)) != set(named):
        raise InputError(f"level: one value per reduced coordinate ({', '.join(named)}) "
                         f"expected, got {', '.join(map(str, level)) or 'none'}", key="level")
    nonzero = [k for k, v in level.items() if sp.sympify(v) != 0]
    if nonzero:
        raise InputError(f"level: {', '.join(nonzero)} = {level[nonzero[0]]}: only the "
                         f"level 0 is reduced (another level makes the constraint affine)",
                         key="level")
    if reduction.constraints.rows:
        raise InputError("level: constraints are left on the shape space (their "
                         "multipliers enter the momentum equation); reduce by them first",
                         key="level")
    rates = {r: rate for r, _, rate in reduction.momentum_equations}
    rdot = list(reduction.shape_velocities)
    for x in c:
        if x not in rates:
            raise InputError(f"level: {x} has no momentum equation", key="level")
        if not _vanishes(rates[x]):
            raise InputError(f"level: p_{x} is not conserved (d/dt p_{x} = {rates[x]})",
                             key="level")
    p = [sp.diff(reduction.lagrangian, rdot[reduction.shape.index(x)]) for x in c]
    rows = sp.Matrix(len(c), len(rdot), lambda i, j: sp.diff(p[i], rdot[j]))
    if any(e.free_symbols & set(rdot) for e in rows) or any(
            cancel(pi.xreplace({w: 0 for w in rdot})) != 0 for pi in p):
        raise InputError("level: the momentum is not linear and homogeneous in the shape "
                         "velocities", key="level")
    return rows


def _vanishes(expr) -> bool:
    """Exactly zero (cancel, then trigsimp for the identities sin^2 + cos^2 = 1)."""
    expr = cancel(sp.sympify(expr))
    return expr == 0 or (expr.has(sp.sin, sp.cos) and cancel(sp.trigsimp(expr)) == 0)
