"""Loads of :mod:`sympy.physics.mechanics` as nhham's forces, for
:mod:`nhham.system.mechanics`.

Forces (``DESIGN.md`` §2): a force F on a point P adds Q_A = F . dv_P/dq'_A and a torque
T on a frame B adds Q_A = T . dw_B/dq'_A (partial velocities, as ``KanesMethod`` and
``LagrangesMethod`` count them, :func:`generalized_forces`); a force constant in the
inertial frame (gravity type) goes into the Lagrangian as the potential -F . r(P)
instead (:func:`split_loads`, :func:`lagrangian_of`). Inputs (controls) given as
dynamicsymbols, Symbols or names become nhham's plain input symbols (:func:`input_map`).
"""

from __future__ import annotations

import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.physics import mechanics as me

from nhham.system.dynamicsymbols import QUOTE, plain_map
from nhham.system.expressions import short
from nhham.system.naming import TIME, as_symbol, velocity_symbol

__all__ = ["input_map", "load_items", "load_pair", "components", "split_loads",
           "lagrangian_of", "free_velocity", "generalized_forces", "vector_xreplace",
           "load_problems", "velocity_problem"]

def input_map(inputs, coords, to_q, problems) -> tuple[dict, tuple]:
    """({input as given -> plain input symbol}, the plain input symbols in order).

    A dynamicsymbol ``T(t)`` becomes ``T``; a Symbol or a name ``T`` is the plain input
    ``T`` and stands for the dynamicsymbol ``T(t)`` too."""
    t = me.dynamicsymbols._t
    if isinstance(inputs, (str, sp.Basic)):
        inputs = [inputs]
    reserved = {f.func.__name__ for f in coords} | {
        velocity_symbol(sp.Symbol(f.func.__name__)).name for f in coords}
    mapping: dict = {}
    plain: list = []
    for i, given in enumerate(inputs):
        label = f"inputs[{i}]"
        if isinstance(given, AppliedUndef) and given.args == (t,):
            if given in coords:
                problems.append(f"{label}: {given} is a coordinate, not an input")
                continue
            if given in to_q:
                problems.append(f"{label}: {given} is a generalized speed (defined by the "
                                f"kinematic differential equations), not an input")
                continue
            sym = sp.Symbol(given.func.__name__)
        elif isinstance(given, (str, sp.Symbol)):
            sym = as_symbol(given)
            if sym == TIME:
                problems.append(f"{label}: t is the time, not an input (a load may use it "
                                f"as it is)")
                continue
        else:
            problems.append(f"{label}: {short(given, QUOTE)} is not an input: give a "
                            f"dynamicsymbol (dynamicsymbols('T')), a Symbol or a name")
            continue
        if sym.name in reserved:
            problems.append(f"{label}: {sym.name} is the name of a coordinate or velocity")
            continue
        if sym in plain:
            problems.append(f"{label}: {sym.name} is given twice")
            continue
        plain.append(sym)
        if isinstance(given, sp.Basic) and given != sym:
            mapping[given] = sym
        if not isinstance(given, AppliedUndef):  # a name stands for T and for T(t)
            mapping[sp.Function(sym.name)(t)] = sym
    return mapping, tuple(plain)


def load_items(loads, actuators, problems, kind="loads") -> list:
    """[(label, point or frame, vector)] of the loads and of the actuators' ``to_loads()``."""
    items = []
    for i, load in enumerate(loads):
        pair = load_pair(f"{kind}[{i}]", load, problems)
        if pair is not None:
            items.append((f"{kind}[{i}]",) + pair)
    for j, act in enumerate(actuators):
        to_loads = getattr(act, "to_loads", None)
        if not callable(to_loads):
            problems.append(f"actuators[{j}]: {short(act, QUOTE)} is not an actuator (it has "
                            f"no to_loads(); give sympy.physics.mechanics actuators, e.g. "
                            f"LinearSpring, TorqueActuator)")
            continue
        try:
            produced = list(to_loads())
        except (ValueError, TypeError, AttributeError) as exc:
            problems.append(f"actuators[{j}]: {type(act).__name__}.to_loads() failed: "
                            f"{' '.join(str(exc).split())}")
            continue
        for k, load in enumerate(produced):
            label = f"actuators[{j}].to_loads()[{k}]"
            pair = load_pair(label, load, problems)
            if pair is not None:
                items.append((label,) + pair)
    return items


def load_pair(label, load, problems):
    """(point or frame, vector) of a Force, a Torque or a pair; None (and a problem) else."""
    if hasattr(load, "location") and hasattr(load, "vector"):
        where, vector = load.location, load.vector
    elif isinstance(load, (tuple, list)) and len(load) == 2:
        where, vector = load
    else:
        problems.append(f"{label}: {short(load, QUOTE)} is not a load: give Force(point, "
                        f"vector), Torque(frame, vector) or a (point or frame, vector) pair")
        return None
    if not isinstance(where, (me.Point, me.ReferenceFrame)):
        problems.append(f"{label}: {short(where, QUOTE)} is neither a Point nor a "
                        f"ReferenceFrame (a load acts on a point or, as a torque, on a frame)")
        return None
    if isinstance(vector, me.Vector):
        return where, vector
    if isinstance(vector, (int, sp.Expr)) and vector == 0:
        return where, me.Vector(0)
    problems.append(f"{label}: {short(vector, QUOTE)} is not a Vector (write the "
                    f"{'force' if isinstance(where, me.Point) else 'torque'} along unit vectors, "
                    f"e.g. F*N.x)")
    return None


def components(label, vector, frame, problems):
    """The components of ``vector`` in ``frame`` (3 x 1), or None (and a problem)."""
    if vector == 0:
        return sp.zeros(3, 1)
    try:
        return vector.to_matrix(frame)
    except ValueError as exc:
        problems.append(f"{label}: the vector {short(vector, QUOTE)} cannot be expressed in "
                        f"{frame} ({' '.join(str(exc).split())})")
        return None


def split_loads(items, frame, inputs, problems) -> tuple[list, list]:
    """(loads with a potential, the others): a force on a point whose components in
    ``frame`` are constant (no function of time, no time, no input) has the potential
    -F . r; everything else (torques, moving forces) is a generalized force.
    ``inputs``: the plain symbols that are inputs, as given and as nhham's."""
    t = me.dynamicsymbols._t
    input_symbols = set(inputs)
    potential: list = []
    forced: list = []
    for label, where, vector in items:
        comps = components(label, vector, frame, problems)
        if comps is None:
            continue
        constant = (isinstance(where, me.Point) and not comps.atoms(AppliedUndef)
                    and not comps.atoms(sp.Derivative) and not comps.has(t)
                    and not (comps.free_symbols & input_symbols))
        (potential if constant else forced).append((label, where, vector, comps))
    return potential, forced


def lagrangian_of(bodies, loads, frame, origin, problems) -> sp.Expr:
    """T - V of rigid bodies/particles and constant (gravity-type) forces ``loads``:
    ``(label, point, vector, components)``."""
    T = sp.S.Zero
    for i, body in enumerate(bodies):
        label = f"bodies[{i}] ({getattr(body, 'name', body)})"
        point = getattr(body, "masscenter", None) or getattr(body, "point", None)
        if point is None or not hasattr(body, "mass"):
            problems.append(f"{label}: not a RigidBody or Particle")
            continue
        vel = free_velocity(label, point, frame, origin, problems)
        if vel is None:
            continue
        T += body.mass * vel.dot(vel) / 2
        body_frame = getattr(body, "frame", None)
        if body_frame is not None and hasattr(body, "central_inertia"):
            w = body_frame.ang_vel_in(frame)
            T += w.dot(body.central_inertia.dot(w)) / 2
    V = sp.S.Zero
    for label, where, vector, _ in loads:
        try:
            r = where.pos_from(origin)
        except ValueError:
            problems.append(f"{label}: the point {where} has no position from the origin "
                            f"{origin}; locate it from there (locatenew)")
            continue
        V -= vector.dot(r)
    return T - V


def free_velocity(label, point, frame, origin, problems, what="its mass centre"):
    """d/dt of the position of ``point`` from ``origin`` in ``frame``."""
    try:
        r = point.pos_from(origin)
    except ValueError:
        problems.append(f"{label}: {what} {point} has no position from the origin "
                        f"{origin}; nhham needs the free velocity d/dt(position), not a "
                        f"velocity with constraints already substituted (set_vel): locate "
                        f"the point from the origin")
        return None
    return r.dt(frame)


def generalized_forces(loads, coords, frame, velocity_of, to_q, inputs_in, problems) -> list:
    """Q_A = sum over the loads of F . dv_P/dq'_A (T . dw_B/dq'_A for a torque on B), in
    nhham's plain symbols (coordinates, velocities, inputs, t).

    ``loads``: ``(label, point or frame, vector, components in frame)``;
    ``velocity_of(label, point, problems)``: the velocity of a point in ``frame`` (None
    and a problem when it has none). The speeds ``to_q`` are replaced before the partial
    derivatives are taken. The dot products are sympy's (``Vector.dot``), so a torque
    along a frame's own axis gives its magnitude with no trigonometric leftovers."""
    t = me.dynamicsymbols._t
    to_plain = plain_map(coords, t)
    to_plain.update(inputs_in)
    qdots = [f.diff(t) for f in coords]
    Q = [sp.S.Zero] * len(coords)
    for label, where, vector, comps in loads:
        if comps == sp.zeros(3, 1):
            continue
        bad = load_problems(label, where, vector, comps, coords, to_q, inputs_in, to_plain)
        if bad:
            problems += bad
            continue
        if isinstance(where, me.ReferenceFrame):
            what = f"the angular velocity of frame {where} in {frame}"
            try:
                vel = where.ang_vel_in(frame)
            except ValueError:
                problems.append(f"{label}: the frame {where} has no angular velocity in "
                                f"{frame} (orient it from {frame} or set_ang_vel)")
                continue
        else:
            what = f"the velocity of {where} in {frame}"
            vel = velocity_of(label, where, problems)
            if vel is None:
                continue
        if to_q:
            vector, vel = vector_xreplace(vector, to_q), vector_xreplace(vel, to_q)
        vbad = velocity_problem(label, what, vel, coords)
        if vbad:
            problems.append(vbad)
            continue
        for A, qd in enumerate(qdots):
            partial = vel.diff(qd, frame) if vel != 0 else vel
            if partial != 0:
                Q[A] += sp.sympify(vector.dot(partial)).xreplace(to_plain)
    return Q


def vector_xreplace(vector, rule):
    """``vector`` with ``rule`` applied to its components (in each of its frames)."""
    if vector == 0:
        return vector
    return me.Vector([(m.xreplace(rule), f) for m, f in vector.args])


def load_problems(label, where, vector, comps, coords, to_q, inputs_in, to_plain) -> list:
    """Why a load's components cannot be a force of nhham's (accelerations, unknown
    functions of time, symbols named like a coordinate or velocity), each naming it."""
    t = me.dynamicsymbols._t
    kind = "torque" if isinstance(where, me.ReferenceFrame) else "force"
    head = f"{label}: the {kind} {short(vector, QUOTE)} on {where}"
    out = []
    qdots = {f.diff(t) for f in coords}
    moving = set(coords) | set(to_q)
    for d in sorted(comps.atoms(sp.Derivative) - qdots, key=str):
        if d.expr in moving:
            out.append(f"{head} depends on the acceleration {d}; a load may depend on the "
                       f"coordinates, their first derivatives (or speeds), time and inputs only")
        else:
            out.append(f"{head} contains the derivative {d}; a load may depend on the "
                       f"coordinates, their first derivatives (or speeds), time and inputs "
                       f"only (give a derivative of an input as an input of its own)")
    known = moving | {f for f in inputs_in if isinstance(f, AppliedUndef)}
    for f in sorted(comps.atoms(AppliedUndef) - known, key=str):
        if any(f in d.atoms(AppliedUndef) for d in comps.atoms(sp.Derivative) - qdots):
            continue  # already named with its derivative
        speed = ", a speed defined by the kinematic differential equations" if to_q else ""
        out.append(f"{head} depends on {f}, a function of time that is neither a "
                   f"coordinate{speed} nor an input; if it is an input (a control, a "
                   f"specified function), list it: inputs=[{f}]")
    reserved = {s.name for s in to_plain.values()} - {s.name for s in inputs_in.values()}
    clash = sorted(s.name for s in comps.free_symbols if s != t and s.name in reserved)
    if clash:
        out.append(f"{head}: plain symbol(s) {', '.join(clash)} have the name of a coordinate "
                   f"or velocity; rename them")
    return out


def velocity_problem(label, what, vel, coords) -> str:
    """Why a velocity cannot be used: functions of time that are not coordinates (a speed
    no kinematic equation defines) or derivatives beyond q'; '' if none."""
    t = me.dynamicsymbols._t
    qdots = {f.diff(t) for f in coords}
    parts = [m for m, _ in vel.args] if vel != 0 else []
    derivs = sorted({d for m in parts for d in m.atoms(sp.Derivative)} - qdots, key=str)
    funcs = sorted({f for m in parts for f in m.atoms(AppliedUndef)} - set(coords), key=str)
    if derivs or funcs:
        culprit = (derivs or funcs)[0]
        return (f"{label}: {what} contains {short(culprit, QUOTE)}, a function of time that "
                f"is not one of the coordinates q nor their first derivatives (a speed that "
                f"no kinematic differential equation defines?)")
    return ""

