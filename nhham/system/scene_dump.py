"""Scenes written back as TOML: what :func:`dump_scene` writes, :func:`nhham.load_scene` reads.
"""

from __future__ import annotations

import math

import sympy as sp

from nhham.errors import (
    SceneError,
)
from nhham.system.expressions import to_text
from nhham.system.scene_structure import BARE_KEY, SimulateOptions, toml_string

__all__ = ["dump_scene", "dependent_velocities"]


# -------------------------------------------------------------------- dump
def dump_scene(system, initial=None, simulate=None, *, description: str = "",
               steady=None, contacts=(), symmetry=None) -> str:
    """Write a system (and optional initial data and options) as scene TOML.

    Parameters
    ----------
    system : nhham.system.System
    initial : mapping of str to float, optional
        Initial value of every coordinate and velocity. The velocities the constraints
        determine (the first ones, in the order of the coordinates, whose columns of mu
        raise its rank at the state) are left out: the reader solves them again at any
        parameter values (a full table would be off the constraints as soon as a
        parameter moves: ``sweep --over`` would project every start).
    simulate : SimulateOptions or mapping, optional
        Simulation defaults.
    description : str, optional
    steady : SteadyState or mapping of str to (float or str), optional
        The ``[steady]`` table (numbers, or expressions in the parameters).
    contacts : sequence of ContactPoint, optional
        The ``[contacts.<name>]`` tables (:mod:`nhham.system.contacts`).
    symmetry : Symmetry or mapping of str to str, optional
        The ``[symmetry]`` table (the generator xi by coordinate).

    The system's ``inputs``, ``forces`` (by coordinate) and ``dissipation`` are written
    too; control laws are not part of a System (a scene's ``[control]``).

    Returns
    -------
    str
        TOML text that :func:`loads_scene` reads back to an equal system.

    Raises
    ------
    SceneError
        A value cannot be written (non-finite number).

    Examples
    --------
    >>> from nhham import dump_scene, loads_scene, models
    >>> text = dump_scene(models.chaplygin_sleigh())
    >>> print(text)
    name = "Chaplygin sleigh"
    coordinates = ["x", "y", "theta"]
    parameters = { m = 1.0, I = 0.25, a = 0.5 }
    lagrangian = "I*theta_dot**2/2 + m*(x_dot**2 + y_dot**2)/2"
    constraints = ["-a*theta_dot - x_dot*sin(theta) + y_dot*cos(theta)"]
    holonomic = []
    <BLANKLINE>
    >>> loads_scene(text).system.mu == models.chaplygin_sleigh().mu
    True
    """
    lines = []
    if system.name:
        lines.append(f"name = {toml_string(system.name)}")
    if description:
        lines.append(f"description = {toml_string(description)}")
    lines.append(f"coordinates = {_toml_array([q.name for q in system.coordinates])}")
    values = {p.name: v for p, v in system.parameter_values.items()}
    declared = system.declared_parameters  # the inputs and t are written as such
    numeric = [p.name for p in declared if p.name in values]
    symbolic = [p.name for p in declared if p.name not in values]
    if numeric:
        items = ", ".join(f"{_toml_key(p)} = {_toml_float(values[p], p)}" for p in numeric)
        lines.append(f"parameters = {{ {items} }}")
    if symbolic:
        lines.append(f"symbolic_parameters = {_toml_array(symbolic)}")
    lines.append(f"lagrangian = {toml_string(to_text(system.lagrangian))}")
    lines.append(f"constraints = {_toml_array([to_text(c) for c in system.constraints])}")
    lines.append(f"holonomic = {_toml_array([to_text(g) for g in system.holonomic])}")
    if system.inputs:
        lines.append(f"inputs = {_toml_array([u.name for u in system.inputs])}")
    forces = [(q.name, f) for q, f in zip(system.coordinates, system.forces) if f != 0]
    if forces:
        items = ", ".join(f"{_toml_key(q)} = {toml_string(to_text(f))}" for q, f in forces)
        lines.append(f"forces = {{ {items} }}")
    if system.dissipation != 0:
        lines.append(f"dissipation = {toml_string(to_text(system.dissipation))}")
    if initial is not None:
        dependent = dependent_velocities(system, initial)
        lines.append("")
        lines.append("[initial]")
        lines.extend(f"{_toml_key(k)} = {_toml_float(v, k)}" for k, v in initial.items()
                     if k not in dependent)
    if steady is not None:
        table = steady.to_toml_table() if hasattr(steady, "to_toml_table") else dict(steady)
        lines.append("")
        lines.append("[steady]")
        for k, v in table.items():
            if isinstance(v, (str, sp.Basic)) and not sp.sympify(v).is_number:
                text = toml_string(to_text(sp.sympify(v)))
            else:
                text = _toml_float(float(sp.sympify(v)), k)
            lines.append(f"{_toml_key(k)} = {text}")
    if symmetry is not None:
        table = (symmetry.to_toml_table() if hasattr(symmetry, "to_toml_table")
                 else dict(symmetry))
        lines += ["", "[symmetry]"]
        lines.extend(f"{_toml_key(k)} = {toml_string(str(v))}" for k, v in table.items())
    for contact in contacts:
        lines += ["", f"[contacts.{_toml_key(contact.name)}]",
                  f"velocity = {_toml_array([to_text(e) for e in contact.velocity])}",
                  f"constraints = {_toml_array(list(contact.constraints))}"]
    options = simulate.given() if isinstance(simulate, SimulateOptions) else dict(simulate or {})
    if options:
        lines.append("")
        lines.append("[simulate]")
        for key, value in options.items():
            text = toml_string(value) if isinstance(value, str) else _toml_float(value, key)
            lines.append(f"{_toml_key(key)} = {text}")
    return "\n".join(lines) + "\n"


def dependent_velocities(system, state) -> frozenset:
    """The names of the velocities the constraints determine at ``state`` (name -> value):
    scanning the velocities in order, each whose column of mu (the lifts of the holonomic
    constraints first) raises its rank there. Empty when mu cannot be evaluated there
    (a parameter without a value, a name missing from ``state``).

    Examples
    --------
    >>> from nhham import models
    >>> disk = models.rolling_disk()          # x' = R cos(theta) phi', y' = R sin(theta) phi'
    >>> state = {"x": 0, "y": 0, "theta": 0.3, "phi": 0, "x_dot": 1.91, "y_dot": 0.59,
    ...          "theta_dot": 1, "phi_dot": 2}
    >>> sorted(dependent_velocities(disk, state))
    ['x_dot', 'y_dot']
    """
    import numpy as np

    if not system.mu.rows:
        return frozenset()
    point = {sp.Symbol(k): v for k, v in state.items()}
    point.update(system.parameter_values)
    if system.time is not None:
        point.setdefault(system.time, 0.0)
    try:
        mu = np.array(system.mu.xreplace(point).evalf(), dtype=float)
    except (TypeError, ValueError):
        return frozenset()
    if not np.all(np.isfinite(mu)):
        return frozenset()
    tol = 1e-9 * max(1.0, float(np.max(np.abs(mu))))
    chosen: list = []
    for j, v in enumerate(system.velocities):
        if np.linalg.matrix_rank(mu[:, chosen + [j]], tol=tol) > len(chosen):
            chosen.append(j)
        if len(chosen) == mu.shape[0]:
            break
    return frozenset(system.velocities[j].name for j in chosen)


def _toml_key(key: str) -> str:
    return key if BARE_KEY.fullmatch(key) else toml_string(key)


def _toml_float(value, key) -> str:
    number = float(value)
    if not math.isfinite(number):
        raise SceneError(f"{key}: cannot write the non-finite value {value!r}")
    return repr(number)  # shortest text that reads back to the same double


def _toml_array(items) -> str:
    if not items:
        return "[]"
    if sum(len(i) for i in items) < 60:
        return "[" + ", ".join(toml_string(i) for i in items) + "]"
    return "[\n" + "".join(f"    {toml_string(i)},\n" for i in items) + "]"
