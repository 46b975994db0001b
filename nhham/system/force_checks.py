"""Checks of the forces (``DESIGN.md`` §2, Forces): a Rayleigh function that dissipates,
and forces defined at the state a run or a linearisation starts from.

:func:`dissipation_problems` is part of the validation of a :class:`~nhham.System`: a
Rayleigh dissipation function R(q, v) has velocities in it and a Hessian in the
velocities that is positive semi-definite (its force -dR/dv then takes energy out,
dE_L/dt = -v . dR/dv = -2R for a quadratic form). It is decided exactly where the Hessian
at the parameter values is a matrix of numbers, and at seeded sampled states otherwise
(float64 eigenvalues; the message names the state); a Hessian that still holds a
parameter without a value, an input or the time is not judged.

:func:`singular_force` finds a generalized force that is not defined (a division by
zero, a logarithm of zero) at a given state, exactly: the numeric kernels would return
NaN there (compiled) or raise (Python), and the user is better told which force and
which state.
"""

from __future__ import annotations

import random
from typing import Mapping

import numpy as np
import sympy as sp

from nhham.errors import InputError

__all__ = ["dissipation_problems", "singular_force", "check_forces_at",
           "DISSIPATION_SAMPLES", "DISSIPATION_SEED"]

#: Seeded states at which a Hessian that depends on the state is examined.
DISSIPATION_SAMPLES = 24
#: Their seed.
DISSIPATION_SEED = 1996

_INFINITE = (sp.zoo, sp.nan, sp.oo, -sp.oo)


def _exact(value) -> sp.Rational:
    """A float as the rational number its shortest decimal repr says (0.1 -> 1/10)."""
    return sp.Rational(repr(float(value)))


def dissipation_problems(R, coordinates, velocities, values: Mapping) -> list[str]:
    """What is wrong with a Rayleigh dissipation function ``R`` (``[]`` when nothing).

    Parameters
    ----------
    R : sympy.Expr
        The dissipation function (0: none).
    coordinates, velocities : sequence of sympy.Symbol
    values : mapping of sympy.Symbol to float
        The parameter values.

    Returns
    -------
    list of str
        Problems keyed ``dissipation: ...``: no velocity in R; a Hessian in the
        velocities that is not positive semi-definite at the parameter values (exactly
        when it is a matrix of numbers there, else at :data:`DISSIPATION_SAMPLES` seeded
        states, named in the message).
    """
    if R == 0:
        return []
    vels = list(velocities)
    if not R.free_symbols & set(vels):
        return [f"dissipation: R = {R} has no velocity in it: a Rayleigh dissipation "
                f"function is a (positive semi-definite) form in the velocities whose force "
                f"is -dR/dv; a force that depends on the coordinates only belongs in "
                f"[forces]"]
    point = {p: _exact(v) for p, v in values.items()}
    H = sp.hessian(R, vels).xreplace(point)
    state = set(coordinates) | set(vels)
    if not H.free_symbols:
        if H.is_positive_semidefinite is False:
            low = min(np.linalg.eigvalsh(np.array(H.evalf(), dtype=float)))
            return [f"dissipation: R = {R} is not positive semi-definite in the velocities: "
                    f"its Hessian d2R/dv2 = {H.tolist()} at the parameter values has the "
                    f"eigenvalue {low:.6g} < 0 (decided exactly), so its force would feed "
                    f"energy in; a Rayleigh function R >= 0 dissipates"]
        return []
    if not H.free_symbols <= state:   # a parameter without a value, an input, the time
        return []
    return _sampled_problem(R, H, list(coordinates), vels)


def _sampled_problem(R, H, coordinates, velocities) -> list[str]:
    """The Hessian's smallest eigenvalue at seeded states (uniform in [-2, 2])."""
    from nhham.system.evaluation import numeric_function

    names = coordinates + velocities
    f = numeric_function(names, H)
    rng = random.Random(DISSIPATION_SEED)
    for _ in range(DISSIPATION_SAMPLES):
        at = [rng.uniform(-2.0, 2.0) for _ in names]
        with np.errstate(all="ignore"):
            try:
                M = np.array(f(*at), dtype=float)
            except (ArithmeticError, ValueError, TypeError):
                continue
        if not np.all(np.isfinite(M)):
            continue
        ev = np.linalg.eigvalsh((M + M.T) / 2)
        if ev[0] < -1e-9 * max(1.0, float(np.max(np.abs(ev)))):
            where = ", ".join(f"{s} = {v:.4g}" for s, v in zip(names, at))
            return [f"dissipation: R = {R} is not positive semi-definite in the velocities: "
                    f"its Hessian d2R/dv2 has the eigenvalue {ev[0]:.6g} < 0 at the state "
                    f"{where} (found among {DISSIPATION_SAMPLES} seeded states, float64 "
                    f"eigenvalues), so its force would feed energy in there; a Rayleigh "
                    f"function R >= 0 dissipates"]
    return []


def singular_force(system, state: Mapping, t: float = 0.0) -> tuple[str, str] | None:
    """``(key, description)`` of the first generalized force not defined at ``state``, or
    None.

    Parameters
    ----------
    system : nhham.System
    state : mapping of str to float
        A value for every coordinate and velocity (inputs too, when known).
    t : float
        The time (for forces that use ``t``).

    Notes
    -----
    Exact: the parameter values and the state enter as rational numbers, so ``k/x`` at
    ``x = 0`` is sympy's complex infinity, not a rounding accident.
    """
    if not system.has_forces:
        return None
    point = {p: _exact(v) for p, v in system.parameter_values.items()}
    names = {s.name: s for s in system.coordinates + system.velocities + system.inputs}
    point.update({names[k]: _exact(v) for k, v in state.items() if k in names})
    if system.time is not None:
        point[system.time] = _exact(t)
    R = system.dissipation
    pieces = [(f"forces.{q.name}", f"the force {f} on {q.name}", f)
              for q, f in zip(system.coordinates, system.forces) if f != 0]
    pieces += [("dissipation", f"the dissipation's force -dR/d{v.name} = {-sp.diff(R, v)}",
                -sp.diff(R, v)) for v in system.velocities if R != 0]
    for key, what, f in pieces:
        value = f.xreplace(point)
        if value.has(*_INFINITE) or value.is_finite is False:
            return key, what
    return None


def check_forces_at(system, state: Mapping, *, where: str, t: float = 0.0) -> None:
    """Raise an :class:`~nhham.errors.InputError` (key ``forces.<q>`` or
    ``dissipation``) when a force is not defined at ``state`` (:func:`singular_force`);
    ``where`` names the state ("the initial state")."""
    found = singular_force(system, state, t)
    if found is None:
        return
    key, what = found
    shown = ", ".join(f"{k} = {float(v):.10g}" for k, v in state.items())
    raise InputError(f"{key}: {what} is not defined at {where} ({shown}); choose another "
                     f"state or a force defined there", key=key)
