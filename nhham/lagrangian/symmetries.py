"""Constants of the motion and symmetries on M_1 (the paper's Section 5).

With C regular, the constrained dynamics on M_1 is Lambda = P(xi_L)|M_1.

- F is a constant of the motion when Lambda(F) = 0 on M_1 (Definition 5.1);
  this *direct* check decides it.
- The paper's test (Z_i F = 0 on M_1 for every i, for F a constant of xi_L)
  is only *sufficient*; it is reported beside the direct check, and a
  function can be conserved although the sufficient test fails.
- A Lie symmetry is a vector field X on Q whose complete lift
  X^c = X^A d/dq^A + (dX^A/dq^B) v^B d/dv^A is tangent to M_1 and commutes
  with Lambda on M_1 (Definition 5.3).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from nhham.lagrangian.decision import Decision

__all__ = [
    "ConservationTest",
    "LieSymmetryTest",
    "constant_of_motion",
    "cyclic_constants",
    "lie_symmetry",
    "complete_lift",
    "lie_bracket",
]


@dataclass(frozen=True)
class ConservationTest:
    """Whether F is a constant of the constrained motion on M_1.

    Attributes
    ----------
    function : sympy.Expr
        F(q, v).
    conserved : Decision
        Lambda(F) = 0 on M_1 (the direct check; decides the answer).
    derivative : sympy.Expr
        Lambda(F) = P(xi_L)(F), reduced on M_1 where the reduction is exact.
    free_constant : Decision
        xi_L(F) = 0 on M_1 (F conserved by the unconstrained motion there).
    sufficient : Decision
        The paper's test: Z_i F = 0 on M_1 for every i.
    """

    function: sp.Expr
    conserved: Decision
    derivative: sp.Expr
    free_constant: Decision
    sufficient: Decision

    def __bool__(self):
        return bool(self.conserved.value)

    def describe(self) -> str:
        """A sentence: conserved or not, and how it was decided."""
        verdict = "conserved" if self.conserved.value else "not conserved"
        text = f"{self.function}: {verdict} ({self.conserved.method}: {self.conserved.detail})"
        if self.conserved.value and not self.sufficient.value:
            text += "; the paper's sufficient test Z_i F = 0 fails, the direct check decides"
        return text


@dataclass(frozen=True)
class LieSymmetryTest:
    """Whether X on Q is a Lie symmetry of Lambda (Definition 5.3).

    Attributes
    ----------
    field : tuple of sympy.Expr
        X^A(q), length n.
    complete_lift : sympy.Matrix
        X^c as a 2n-vector.
    tangent : Decision
        X^c(phi_i) = 0 and X(g) = 0 on M_1 for all constraints.
    commutes : Decision
        [X^c, Lambda] = 0 on M_1 (every component).
    """

    field: tuple
    complete_lift: sp.Matrix
    tangent: Decision
    commutes: Decision

    def __bool__(self):
        return bool(self.tangent.value) and bool(self.commutes.value)


def constant_of_motion(geometry, F) -> ConservationTest:
    """Decide whether ``F`` is a constant of the constrained motion on M_1.

    Parameters
    ----------
    geometry : nhham.lagrangian.LagrangianGeometry
        With C regular on M_1.
    F : sympy.Expr
        A function of coordinates, velocities and parameters.

    Examples
    --------
    The rolling disk keeps its energy; x' changes (x'' = -R sin(theta) theta' phi').

    >>> from nhham import constant_of_motion, lagrangian_geometry, models
    >>> disk = models.rolling_disk()
    >>> geometry = lagrangian_geometry(disk)
    >>> constant_of_motion(geometry, disk.lagrangian).conserved.value
    True
    >>> bool(constant_of_motion(geometry, disk.velocities[0]))
    False
    """
    F = sp.sympify(F)
    M1 = geometry.M1
    derivative = geometry.apply(geometry.projected_field, F)
    conserved = M1.vanishes(derivative)
    free = M1.vanishes(geometry.apply(geometry.euler_lagrange_field, F))
    sufficient = _all_vanish(M1, [geometry.apply(geometry.vertical_fields[i, :].T, F)
                                  for i in range(geometry.m)], "Z_i F")
    return ConservationTest(F, conserved, M1.reduce(derivative), free, sufficient)


def cyclic_constants(geometry) -> dict:
    """Candidate constants from cyclic coordinates, each tested on M_1.

    A coordinate q is cyclic when dL/dq = 0; its momentum dL/dv_q is then a
    constant of the free motion (Noether), and a candidate for the
    constrained one.

    Returns
    -------
    dict
        ``{coordinate: ConservationTest}`` for every cyclic coordinate.

    Examples
    --------
    Every coordinate of the rolling disk is cyclic; the constraint forces change m x' and
    m y', while theta' and phi' stay constant ((I2 + m R^2) phi'' = 0 by hand).

    >>> from nhham import cyclic_constants, lagrangian_geometry, models
    >>> tests = cyclic_constants(lagrangian_geometry(models.rolling_disk()))
    >>> {str(q): bool(test) for q, test in tests.items()}
    {'x': False, 'y': False, 'theta': True, 'phi': True}
    """
    L = geometry.system.lagrangian
    out = {}
    for q, v in zip(geometry.system.coordinates, geometry.system.velocities):
        if sp.diff(L, q) == 0:
            out[q] = constant_of_motion(geometry, sp.diff(L, v))
    return out


def complete_lift(system, X) -> sp.Matrix:
    """X^c = X^A d/dq^A + (dX^A/dq^B) v^B d/dv^A, as a 2n-vector.

    Examples
    --------
    >>> from nhham import complete_lift, models
    >>> disk = models.rolling_disk()
    >>> x, y, theta, phi = disk.coordinates
    >>> complete_lift(disk, [-y, x, 1, 0]).T    # a rotation of the plane, lifted to TQ
    Matrix([[-y, x, 1, 0, -y_dot, x_dot, 0, 0]])
    """
    X = [sp.sympify(x) for x in X]
    if len(X) != system.n:
        from nhham.errors import InputError

        raise InputError(f"vector field: expected {system.n} components, got {len(X)}")
    lifted = [sum((sp.diff(x, q) * v for q, v in zip(system.coordinates, system.velocities)),
                  sp.S.Zero) for x in X]
    return sp.Matrix(X + lifted)


def lie_bracket(state, X: sp.Matrix, Y: sp.Matrix) -> sp.Matrix:
    """[X, Y]^a = X(Y^a) - Y(X^a) for fields given as component vectors."""
    JX = X.jacobian(state)
    JY = Y.jacobian(state)
    return JY * X - JX * Y


def lie_symmetry(geometry, X) -> LieSymmetryTest:
    """Decide whether X (n components, functions of q) is a Lie symmetry.

    Tests X^c tangent to M_1 (X^c(phi_i) = 0 there, and X(g) = 0 for the
    holonomic constraints) and [X^c, Lambda] = 0 on M_1, where Lambda is
    represented by its extension P(xi_L); both fields being tangent to M_1,
    the bracket on M_1 does not depend on the extensions.

    Examples
    --------
    Rotating the rolling disk's plane (and its heading with it) is a symmetry.

    >>> from nhham import lagrangian_geometry, lie_symmetry, models
    >>> disk = models.rolling_disk()
    >>> x, y, theta, phi = disk.coordinates
    >>> test = lie_symmetry(lagrangian_geometry(disk), [-y, x, 1, 0])
    >>> test.tangent.value, test.commutes.value
    (True, True)
    """
    system = geometry.system
    Xc = complete_lift(system, X)
    M1 = geometry.M1
    checks = [geometry.apply(Xc, f) for f in system.phi + system.holonomic]
    tangent = _all_vanish(M1, checks, "X^c(phi_i)")
    if not tangent.value:
        commutes = Decision(False, tangent.method, "not tested: X^c is not tangent to M_1",
                            precision=tangent.precision)
    else:
        bracket = lie_bracket(sp.Matrix(system.state), Xc, geometry.projected_field)
        commutes = _all_vanish(M1, list(bracket), "[X^c, Lambda]")
    return LieSymmetryTest(tuple(sp.sympify(x) for x in X), Xc, tangent, commutes)


def _all_vanish(M, exprs, what) -> Decision:
    """Combine per-expression vanishing decisions into one."""
    decisions = [M.vanishes(e) for e in exprs]
    if not decisions:
        return Decision(True, "exact", f"no {what} to test")
    failing = [i for i, d in enumerate(decisions) if not d.value]
    method = "exact" if all(d.method == "exact" for d in decisions) else "sampled"
    precision = next((d.precision for d in decisions if d.method != "exact"), "exact")
    warnings = tuple(w for d in decisions for w in d.warnings)
    if failing:
        worst = decisions[failing[0]]
        return Decision(False, worst.method, f"{what} does not vanish for index {failing}: "
                                             f"{worst.detail}", precision=worst.precision,
                        samples=worst.samples, max_abs=worst.max_abs, warnings=warnings)
    return Decision(True, method, f"every {what} vanishes on M_1 ("
                    + "; ".join(sorted({d.detail for d in decisions})) + ")",
                    precision=precision, samples=max(d.samples for d in decisions),
                    warnings=warnings)
