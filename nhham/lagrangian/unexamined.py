"""What the user is told about exceptional conditions that could not be examined exactly
(``DESIGN.md`` §2, "On M_k"): one note per cause, not one per condition.

The exact evaluation at rational points (:mod:`nhham.lagrangian.domains`) gives sin and
cos of an *angle variable* through rational points of the circle; a parameter inside sin
or cos is a number, and sin of a number has no exact value. Every datum that holds such a
term then fails the same way: the note names the parameters and says what the user can
do (declare the angle by its cosine and sine, or take the verdict as decided for generic
values of the parameter).
"""

from __future__ import annotations

import math

import sympy as sp

__all__ = ["unexamined_notes", "trigonometric_parameters"]

_TRIG = (sp.sin, sp.cos, sp.tan, sp.cot, sp.sec, sp.csc)


def trigonometric_parameters(system) -> list:
    """The parameters (with or without values) inside sin, cos, tan... in the system's
    Lagrangian, constraints, holonomic constraints or forces, in declaration order."""
    exprs = [system.lagrangian, *system.phi, *system.holonomic, *system.forces,
             system.dissipation]
    found: set = set()
    for e in exprs:
        for call in sp.sympify(e).atoms(*_TRIG):
            found |= call.args[0].free_symbols
    return [p for p in system.parameters if p in found]


def unexamined_notes(system, unexamined, lead: str) -> list:
    """Notes for ``[(why, reason)]`` of data not examined: one per ``why``.

    Parameters
    ----------
    system : nhham.System
    unexamined : list of (str, str)
        Why a datum was not examined (the NotExact message) and the datum's reason
        ("the Lagrangian is singular (det W = 0)").
    lead : str
        "not examined at the values" or "not examined".
    """
    by_cause: dict = {}
    for why, reason in unexamined:
        by_cause.setdefault(why, []).append(reason)
    out = []
    for why, reasons in by_cause.items():
        whether = "; ".join(f"whether {r}" for r in reasons)
        angles = trigonometric_parameters(system) if "not an angle variable" in why else []
        if not angles:
            out.append(f"{lead} ({why}): {whether}")
            continue
        out.append(f"{lead}: {whether}: {_advice(system, angles, lead)}")
    return out


def _advice(system, angles, lead) -> str:
    names = ", ".join(p.name for p in angles)
    values = system.parameter_values
    examples = []
    for p in angles:
        if p in values:
            x = float(values[p])
            examples.append(f"c_{p.name} = {math.cos(x):.15g} and s_{p.name} = "
                            f"{math.sin(x):.15g}")
        else:
            examples.append(f"c_{p.name} and s_{p.name}")
    what = ("these conditions were not checked at the values: the verdict is the one "
            f"decided for generic {names}" if lead.endswith("values") else
            f"their exceptional sets were not computed: the verdict is the generic one for "
            f"every {names}")
    return (f"{names} inside sin or cos has no exact value at a number, so {what}. To "
            f"have them checked, declare each such angle by its cosine "
            f"and sine (parameters {'; '.join(examples)}, written for cos({angles[0].name}) "
            f"and sin({angles[0].name}) in the scene), or make it a coordinate; or accept "
            f"the verdict as decided")
