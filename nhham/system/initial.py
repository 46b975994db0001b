"""A scene's [initial] data checked against its constraints before anything runs.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import sympy as sp

from nhham.errors import (
    InconsistentInitialDataError,
    MissingParameterValueError,
)

__all__ = ["check_initial", "initial_residuals", "INITIAL_TOLERANCE", "INITIAL_ADVICE",
           "labelled_constraints"]

if TYPE_CHECKING:
    from nhham.system.description import System

#: What the checks read of a scene (``system``, ``initial``, ``source``...): typed
#: loosely so that this module, which the scene loader imports, does not import it back.
Scene = Any


#: Relative tolerance on constraint residuals at the initial state.
INITIAL_TOLERANCE = 1e-9

#: What to do about initial data off the constraints (the end of every such message).
INITIAL_ADVICE = ("leave the dependent velocities (and coordinates) out of [initial] to have "
                  "them solved, or let simulate project the state with --project-initial "
                  "(simulate(..., project_initial=True))")


# ------------------------------------------------------------ initial data
def check_initial(scene: Scene) -> dict:
    """Residuals of every constraint at the scene's initial state.

    Each affine constraint, each holonomic constraint g and its time
    derivative (dg/dq) v (the state must lie on T Q_1) is evaluated at the
    initial coordinates and velocities with the parameter values.

    Parameters
    ----------
    scene : Scene

    Returns
    -------
    dict
        ``{key path: residual}``, e.g. ``{"constraints[0]": 0.0,
        "holonomic[0]": 0.0, "holonomic[0] (time derivative)": 0.0}``;
        empty when the scene has no initial data.

    Raises
    ------
    InconsistentInitialDataError
        A residual exceeds ``INITIAL_TOLERANCE * max(1, |largest term|)``,
        or is not a finite real number; the message names the constraint
        and shows the residual.
    MissingParameterValueError
        A constraint uses a parameter that has no numeric value.
    """
    if scene.initial is None:
        return {}
    return initial_residuals(scene)


def initial_residuals(scene: Scene) -> dict:
    """:func:`check_initial` for a scene that has initial data."""
    system: System = scene.system
    point = {sp.Symbol(name): sp.Float(value) for name, value in (scene.initial or {}).items()}
    point.update({p: sp.Float(v) for p, v in system.parameter_values.items()})
    if system.time is not None:  # a scene's runs start at t = 0
        point[system.time] = sp.Float(0)
    residuals, problems = {}, []
    for path, expr in labelled_constraints(system):
        missing = sorted(s.name for s in expr.free_symbols if s not in point)
        if missing:
            raise MissingParameterValueError(
                f"{path}: no numeric value for parameter {', '.join(map(repr, missing))}, "
                f"needed to check the initial data (give it in parameters)", key="parameters")
        residual, scale = _evaluate(expr, point)
        if residual is None:
            problems.append(f"{path} is not a finite real number")
            continue
        residuals[path] = residual
        tolerance = INITIAL_TOLERANCE * scale
        if abs(residual) > tolerance:
            # the constraint by its key, not its expression (a bicycle's runs to 1,000
            # characters): the residual and the tolerance say what is wrong
            problems.append(f"{path} = {residual:.6g} (tolerance {tolerance:.1g})")
    if problems:
        raise InconsistentInitialDataError(
            f"{scene.source}: [initial] violates " + "; ".join(problems) + " at the initial "
            f"state; {INITIAL_ADVICE}", key=problems[0].split(" ", 1)[0])
    return residuals


def labelled_constraints(system):
    """(key path, expression) for every constraint the initial state must meet."""
    items = []
    for i, g in enumerate(system.holonomic):
        # the complete lift: dg/dq v (+ dg/dt when g depends on the time)
        lift = system.complete_lifts[i]
        items.append((f"holonomic[{i}]", g))
        items.append((f"holonomic[{i}] (time derivative)", lift))
    labels = getattr(system, "constraint_labels", ())
    affine = [label for label in labels if label.startswith("constraints[")]
    if len(affine) != len(system.constraints):
        affine = [f"constraints[{i}]" for i in range(len(system.constraints))]
    items.extend(zip(affine, system.constraints))
    return items


def _evaluate(expr, point):
    """(residual, scale) of ``expr`` at ``point``; residual None if not finite real."""
    def value(e):
        try:
            z = complex(sp.sympify(e.xreplace(point)).evalf())
        except (TypeError, ValueError, OverflowError, ZeroDivisionError):
            return None
        if not (math.isfinite(z.real) and math.isfinite(z.imag)):
            return None
        return z

    total = value(expr)
    if total is None or abs(total.imag) > INITIAL_TOLERANCE * max(1.0, abs(total.real)):
        return None, 1.0
    # Scale: the largest term of the constraint as written, so that a
    # residual of 1e-12 on terms of size 1e6 counts as zero.
    terms = [value(t) for t in sp.Add.make_args(expr)]
    scale = max([1.0] + [abs(t) for t in terms if t is not None])
    return total.real, scale
