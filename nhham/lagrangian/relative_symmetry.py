"""Whether a declared symmetry is one: the checks behind a scene's ``[symmetry]``
(``DESIGN.md`` §2, "Relative equilibria").

The tangent lift Xi = xi^A d/dq^A + (d xi^A/d q^B) v^B d/dv^A of the generator xi on Q
(:func:`~nhham.lagrangian.symmetries.complete_lift`) must

- leave L invariant: Xi(L) = 0 on TQ;
- map the constraints into themselves: Xi(phi_i) = 0 on M_1 and xi(g_k) = 0 there;
- leave the forces invariant: the Lie derivative of the 1-form F = Q_A dq^A along Xi,
  (L_Xi F)_A = Xi(Q_A) + Q_B d xi^B/d q^A, is 0 on TQ.

Then Xi commutes with the constrained field on M_1, and a motion along xi is a relative
equilibrium that ``nhham linearize`` linearises in co-moving variables. Its momentum
J = (dL/dv^A) xi^A is conserved (Noether) when besides the reactions do no work along xi
(d phi_i/d v . xi = 0 on M_1 for every velocity constraint) and neither do the forces
(Q . xi = 0 on M_1): ``linearize`` then divides out its level as well. Each test is a
decision of the engine (:meth:`Submanifold.vanishes`: exact reduction, else exact points
with an error bound, else sampled points) on M_1, or on TQ (the system without its
constraints); a failing one is refused naming ``symmetry`` and what is not invariant.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from nhham.errors import InputError
from nhham.lagrangian.symmetries import complete_lift

__all__ = ["SymmetryCheck", "check_symmetry"]


@dataclass(frozen=True)
class SymmetryCheck:
    """The invariance checks of a generator, each with how it was decided.

    Attributes
    ----------
    generator : tuple of sympy.Expr
        xi's n components.
    lift : sympy.Matrix
        Xi as a 2n-vector.
    decisions : tuple of (str, Decision)
        ``("lagrangian", ...)``, ``("constraints[i]", ...)``, ``("holonomic[k]", ...)``,
        ``("forces.<q>", ...)``: each invariance test.
    momentum : sympy.Expr or None
        J = (dL/dv) . xi where it is conserved (no reaction and no force along xi on
        M_1), else None.
    """

    generator: tuple
    lift: sp.Matrix
    decisions: tuple
    momentum: sp.Expr | None = None

    def methods(self) -> str:
        """How the tests were decided, in a few words."""
        return ", ".join(sorted({d.method for _, d in self.decisions})) or "exact"


def check_symmetry(system, symmetry) -> SymmetryCheck:
    """Check that ``symmetry`` (its generator xi) leaves L, the constraints and the
    forces of ``system`` invariant.

    Parameters
    ----------
    system : System
    symmetry : nhham.system.symmetry.Symmetry or sequence of n expressions

    Returns
    -------
    SymmetryCheck

    Raises
    ------
    InputError
        (key ``symmetry``) naming every part that is not invariant.

    Examples
    --------
    The rolling disk: turning the plane with the heading is a symmetry, turning the
    heading alone is not (the rolling constraints turn with it).

    >>> import sympy as sp
    >>> from nhham import models
    >>> from nhham.lagrangian.relative_symmetry import check_symmetry
    >>> disk = models.rolling_disk()
    >>> x, y, theta, phi = disk.coordinates
    >>> check_symmetry(disk, [-y, x, 1, 0]).methods()
    'exact'
    >>> check_symmetry(disk, [0, 0, 1, 0])   # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    nhham.errors.InputError: symmetry: the generator xi = (0, 0, 1, 0) does not leave constraints[0], constraints[1] invariant ...
    """
    from nhham.lagrangian.geometry import lagrangian_geometry

    xi = (symmetry.field(system.coordinates) if hasattr(symmetry, "field")
          else [sp.sympify(e) for e in symmetry])
    Xc = complete_lift(system, xi)
    state = system.state
    derivative = lambda f: sum((Xc[i] * sp.diff(f, s) for i, s in enumerate(state)),  # noqa: E731
                               sp.S.Zero)
    free = _free(system)
    decisions = [("lagrangian", _on(free, derivative(system.lagrangian)))]
    M1 = lagrangian_geometry(system).M1
    decisions += [(label, _on(M1, derivative(phi)))
                  for label, phi in zip(_labels(system), system.phi)]
    Q = list(system.generalized_forces)
    for A, q in enumerate(system.coordinates):
        term = derivative(Q[A]) + sum((Q[B] * sp.diff(xi[B], q) for B in range(system.n)),
                                      sp.S.Zero)
        if Q[A] != 0 or term != 0:
            decisions.append((f"forces.{q.name}", _on(free, term)))
    failed = [label for label, d in decisions if not d.value]
    if failed:
        raise InputError(
            f"symmetry: the generator xi = ({', '.join(map(str, xi))}) does not leave "
            f"{', '.join(failed)} invariant (its tangent lift's derivative of each does not "
            f"vanish{' on M_1' if any(f.startswith(('constraints', 'holonomic')) for f in failed) else ''}); "
            f"a [symmetry] must leave L, the constraints and the forces invariant",
            key="symmetry")
    return SymmetryCheck(tuple(xi), Xc, tuple(decisions), _momentum(system, xi, M1))


def _momentum(system, xi, M1):
    """J = (dL/dv) . xi when no reaction and no force does work along xi on M_1 (each a
    decision of the engine; the first that fails ends the tests), else None."""
    velocities = system.velocities
    # the holonomic constraints' lifts give xi(g), zero on M_1 already
    powers = [sum((sp.diff(phi, v) * e for v, e in zip(velocities, xi)), sp.S.Zero)
              for phi in system.phi]
    powers.append(sum((Q * e for Q, e in zip(system.generalized_forces, xi)), sp.S.Zero))
    # at the parameter values (a damping coefficient c = 0 does no work)
    values = {p: sp.nsimplify(v, rational=True) for p, v in system.parameter_values.items()
              if v is not None}
    for power in powers:
        power = sp.expand(sp.sympify(power).xreplace(values))
        if power != 0 and not _on(M1, power).value:
            return None
    return sum((sp.diff(system.lagrangian, v) * e for v, e in zip(velocities, xi)), sp.S.Zero)


def _labels(system) -> list:
    """Labels of ``system.phi``: the holonomic constraints' lifts first, then the
    velocity constraints (nhham's order)."""
    return ([f"holonomic[{k}]" for k in range(len(system.holonomic))]
            + [f"constraints[{i}]" for i in range(len(system.constraints))])[:len(system.phi)]


def _on(manifold, expr):
    """Whether ``expr`` vanishes on ``manifold`` (exact zero first: no points needed)."""
    from nhham.lagrangian.decision import Decision

    if sp.expand(expr) == 0:
        return Decision(True, "exact", "zero after expansion")
    return manifold.vanishes(expr)


def _free(system):
    """TQ: the system without its constraints, its inputs as symbolic parameters."""
    from nhham.lagrangian.geometry import lagrangian_geometry
    from nhham.system.description import System

    values = {p.name: v for p, v in system.parameter_values.items()}
    parameters = {p.name: values.get(p.name) for p in system.parameters
                  if p not in system.inputs and p.name != "t"}
    free = System([q.name for q in system.coordinates], system.lagrangian,
                  parameters=parameters, inputs=[u.name for u in system.inputs])
    return lagrangian_geometry(free).M1
