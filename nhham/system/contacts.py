"""Contact points: where a system's constraints act, for their forces.

A constraint of a rolling or touching body usually says that the *material* velocity of
one point of the body (the point in contact) has no component along some directions:
v_P · e_k = 0. The force the constraint exerts is then a force f_P at P, and
:mod:`nhham.numerics.contact_forces` recovers it from the multipliers. A contact point
is given by

* ``velocity``: v_P, the velocity of the material point of the body at the contact, as
  three expressions (components in the inertial frame) affine in the velocities;
* ``constraints``: the labels of the constraints it carries: ``"constraints[j]"``, or
  ``"holonomic[i]"`` for the complete lift of a holonomic constraint (a contact height
  g(q) = 0 acts through g's lift, the vertical velocity of the point).

In a scene::

    [contacts.front]
    velocity = ["x_dot + ...", "y_dot + ...", "z_dot + ..."]
    constraints = ["holonomic[0]", "constraints[2]", "constraints[3]"]

The expressions are parsed by the scene's parser against its symbol table (coordinates,
velocities, parameters), never evaluated as Python.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import sympy as sp

from nhham.errors import ParseError
from nhham.system.expressions import derivative

__all__ = ["ContactPoint", "contacts_structure", "parse_contacts", "contact_rows",
           "velocity_jacobian", "CONTACT_KEYS"]

#: The keys of a ``[contacts.<name>]`` table.
CONTACT_KEYS = ("velocity", "constraints")


@dataclass(frozen=True)
class ContactPoint:
    """A point where constraints act (see the module docstring).

    Attributes
    ----------
    name : str
    velocity : tuple of sympy.Expr, length 3
        v_P in the inertial frame, affine in the velocities.
    constraints : tuple of str
        Labels of the constraints it carries.

    Examples
    --------
    >>> import sympy as sp
    >>> from nhham import ContactPoint, models
    >>> sleigh = models.chaplygin_sleigh()
    >>> theta, (x_dot, y_dot, theta_dot), a = sleigh.coordinates[2], sleigh.velocities, sp.Symbol("a")
    >>> blade = ContactPoint("blade", (x_dot + a * sp.sin(theta) * theta_dot,
    ...                                y_dot - a * sp.cos(theta) * theta_dot, 0), ("constraints[0]",))
    >>> blade.constraints
    ('constraints[0]',)
    """

    name: str
    velocity: tuple
    constraints: tuple

    def __post_init__(self):
        # a plain number (0: the height of a point on a plane) is a constant expression;
        # text is never sympified here (it is parsed, see the module docstring)
        object.__setattr__(self, "velocity", tuple(
            sp.Integer(v) if isinstance(v, int) else sp.Float(v) if isinstance(v, float)
            else v for v in self.velocity))


def contacts_structure(value, problems) -> Mapping | None:
    """Check a raw ``[contacts]`` table: for each name a table with ``velocity`` (three
    strings) and ``constraints`` (a non-empty list of labels). Problems are appended
    to ``problems``, each naming ``contacts.<name>.<key>``."""
    if value is None:
        return None
    if not isinstance(value, dict):
        problems.append("contacts: expected a table of [contacts.<name>] tables")
        return None
    out = {}
    for name, table in value.items():
        path = f"contacts.{name}"
        if not isinstance(table, dict):
            problems.append(f"{path}: expected a table with velocity and constraints")
            continue
        unknown = sorted(set(table) - set(CONTACT_KEYS))
        if unknown:
            problems.append(f"{path}.{unknown[0]}: unknown key (expected velocity, "
                            f"constraints)")
        velocity, labels = table.get("velocity"), table.get("constraints")
        if not (isinstance(velocity, list) and len(velocity) == 3
                and all(isinstance(v, str) for v in velocity)):
            problems.append(f"{path}.velocity: expected three expression strings (the "
                            f"point's velocity in the inertial frame)")
            continue
        if not (isinstance(labels, list) and labels
                and all(isinstance(x, str) for x in labels)):
            problems.append(f"{path}.constraints: expected a non-empty list of constraint "
                            f"labels such as \"constraints[0]\" or \"holonomic[0]\"")
            continue
        out[name] = (tuple(velocity), tuple(labels))
    return out


def parse_contacts(raw: Mapping | None, parse, n_constraints: int, n_holonomic: int):
    """``(tuple of ContactPoint, problems)``: the checked table's expressions parsed by
    ``parse(text, where)`` and its labels checked against the scene's constraints."""
    if not raw:
        return (), []
    points, problems = [], []
    for name, (velocity, labels) in raw.items():
        exprs = []
        for k, text in enumerate(velocity):
            try:
                exprs.append(parse(text, f"contacts.{name}.velocity[{k}]"))
            except ParseError as exc:  # listed with the others
                problems.append(str(exc))
        for label in labels:
            problem = _label_problem(label, n_constraints, n_holonomic)
            if problem:
                problems.append(f"contacts.{name}.constraints: {problem}")
        if len(exprs) == 3:
            points.append(ContactPoint(name, tuple(exprs), tuple(labels)))
    return tuple(points), problems


def _label_problem(label: str, m: int, nh: int) -> str:
    for kind, count in (("constraints", m), ("holonomic", nh)):
        if label.startswith(f"{kind}[") and label.endswith("]"):
            index = label[len(kind) + 1:-1]
            if index.isdigit() and int(index) < count:
                return ""
            return f"{label!r}: the scene has {count} {kind}"
    return f"{label!r} is not a constraint label (constraints[j] or holonomic[i])"


def contact_rows(system, contact: ContactPoint) -> list[int]:
    """The rows of the system's φ (and of its multipliers λ) a contact carries (the
    complete lift of ``holonomic[i]`` is the row labelled so).

    Raises
    ------
    InputError
        A label that is not one of the system's rows (a constraint dropped as
        redundant).
    """
    from nhham.errors import InputError

    labels = list(system.constraint_labels)
    missing = [x for x in contact.constraints if x not in labels]
    if missing:
        raise InputError(f"contacts.{contact.name}.constraints: {missing[0]!r} is not a "
                         f"constraint of the system (rows: {', '.join(labels)})",
                         key=f"contacts.{contact.name}.constraints")
    return [labels.index(x) for x in contact.constraints]


def velocity_jacobian(system, contact: ContactPoint) -> sp.Matrix:
    """J_P = dv_P/dv, shape (3, n): the point's velocity map (v_P = J_P v + j_P)."""
    return sp.Matrix([[derivative(e, v) for v in system.velocities] for e in contact.velocity])
