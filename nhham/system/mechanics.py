"""Bridges to :mod:`sympy.physics.mechanics`.

:func:`from_mechanics` and :func:`from_lagranges_method` turn a Lagrangian,
bodies, loads, actuators and constraints written in dynamicsymbols q(t),
q(t).diff(t) into an :class:`nhham.System`; :func:`to_lagranges_method` goes
the other way, so that tests and benchmarks can run ``LagrangesMethod`` on
exactly the system nhham sees (forces included).

Names: the dynamicsymbol ``q1(t)`` becomes the coordinate ``q1`` and its
derivative the velocity ``q1_dot``; an input ``T(t)`` (a "specified" symbol,
listed in ``inputs``) becomes the plain input symbol ``T``; sympy's time
``dynamicsymbols._t`` is nhham's time ``t``.

Forces (``DESIGN.md`` §2): the equations are d/dt(dL/dv) - dL/dq = Q - mu^T
lambda, with the generalized force Q on the right-hand side. A force F on a
point P adds Q_A = F . dv_P/dq'_A and a torque T on a frame B adds
Q_A = T . dw_B/dq'_A (partial velocities; v_P, w_B in the inertial frame), as
``KanesMethod`` and ``LagrangesMethod`` count them. A force constant in the
inertial frame (gravity type) goes into the Lagrangian as the potential
-F . r(P) instead (the same equations).

Multipliers: ``LagrangesMethod.eom`` is d/dt(dL/dq') - dL/dq - Q - lam_coeffs^T lam
with lam_coeffs = -d(coneqs)/dq', i.e. d/dt(dL/dv) - dL/dq - Q + mu^T lam = 0,
nhham's convention (``DESIGN.md`` §2); its constraint order (time
derivatives of the holonomic constraints first, then the nonholonomic ones)
is nhham's order of :attr:`System.phi`. So ``lam<i>(t)`` in ``lm.eom``
corresponds to ``lambda_<i>``. Beware: sympy 1.14's ``mass_matrix`` appends
``lam_coeffs.T`` itself, so the multipliers solved from
``mass_matrix_full``/``rhs()`` are the negatives of those in ``lm.eom``.

The pieces: :mod:`nhham.system.dynamicsymbols` turns dynamicsymbols into plain symbols
(and speeds into q'), :mod:`nhham.system.loads` turns loads and actuators into a
potential and generalized forces; this module assembles the :class:`System`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from types import MappingProxyType
from typing import Mapping, NamedTuple, Sequence

import sympy as sp
from sympy.physics import mechanics as me

from nhham.errors import InputError, ValidationError
from nhham.system.description import System
from nhham.system.dynamicsymbols import (
    as_expr,
    convert,
    coordinate_functions,
    plain_map,
    remaining_symbols,
    speed_substitution,
)
from nhham.system.loads import (
    components,
    free_velocity,
    generalized_forces,
    input_map,
    lagrangian_of,
    load_items,
    split_loads,
)
from nhham.system.naming import TIME, acceleration_symbol, multiplier_symbol

__all__ = [
    "from_mechanics",
    "from_lagranges_method",
    "to_lagranges_method",
    "MechanicsForm",
    "Substitutions",
]

@dataclass(frozen=True)
class Substitutions:
    """Maps between nhham's plain symbols and dynamicsymbols.

    Attributes
    ----------
    to_mechanics : mapping
        ``q -> q(t)``, ``q_dot -> q(t).diff(t)`` for every coordinate and
        ``u -> u(t)`` for every input (the time ``t`` is sympy's
        ``dynamicsymbols._t`` already).
    from_mechanics : mapping
        ``q(t) -> q``, ``q'(t) -> q_dot``, ``q''(t) -> q_ddot``, the inputs
        ``u(t) -> u`` and the multipliers ``lam<i>(t) -> lambda_<i>``. Use with
        ``xreplace`` (not ``subs``: a derivative must be replaced as a whole).
    """

    to_mechanics: Mapping[sp.Symbol, sp.Expr]
    from_mechanics: Mapping[sp.Expr, sp.Symbol]


class MechanicsForm(NamedTuple):
    """What :func:`to_lagranges_method` returns (unpacks as a 3-tuple)."""

    lm: me.LagrangesMethod
    q: tuple
    maps: Substitutions


# ------------------------------------------------------------------- into
def from_mechanics(lagrangian=None, q: Sequence | None = None, hol_coneqs: Sequence = (),
                   nonhol_coneqs: Sequence = (), parameters=None, name: str = "", *,
                   bodies: Sequence = (), loads: Sequence = (), actuators: Sequence = (),
                   frame=None, origin=None, u: Sequence | None = None, kd_eqs: Sequence = (),
                   velocity_constraints: Sequence = (),
                   configuration_constraints: Sequence = (), inputs: Sequence = (),
                   drop_redundant: bool = False) -> System:
    """Build a :class:`System` from a ``sympy.physics.mechanics`` description.

    Three ways in, which may be combined:

    1. a Lagrangian: ``from_mechanics(L, q, hol_coneqs, nonhol_coneqs)``
       (as ``LagrangesMethod`` takes them);
    2. bodies, loads and actuators: ``from_mechanics(q=q, bodies=...,
       loads=..., actuators=..., frame=N, origin=O)``; L = T - V with T the
       kinetic energy of every body in ``frame`` and V the potential of every
       force constant in ``frame`` (gravity type); every other load becomes a
       generalized force (below);
    3. a ``sympy.physics.mechanics.System`` as the first argument: its
       frame, fixed point, bodies, loads, actuators, coordinates ``q``, speeds
       ``u``, kinematic differential equations ``kdes``,
       ``holonomic_constraints`` and ``nonholonomic_constraints`` are read as
       in 2.

    A ``LagrangesMethod`` is read as :func:`from_lagranges_method` reads it. A
    ``KanesMethod`` is refused with a pointer to the ``System`` it is formed
    from: it holds the equations of motion, not the energies nor the point from
    which positions are measured.

    Forces: the equations are d/dt(dL/dv) - dL/dq = Q - mu^T lambda
    (``DESIGN.md`` §2), Q the generalized force on the right-hand side
    (:attr:`System.generalized_forces`). A force F on a point P adds
    Q_A = F . dv_P/dq'_A, with v_P the free velocity of P (the time derivative
    of its position from ``origin`` in ``frame``); a torque T on a frame B adds
    Q_A = T . dw_B/dq'_A, with w_B = ``B.ang_vel_in(frame)`` (partial
    velocities, as ``KanesMethod`` counts them). A load may depend on the
    coordinates, their first derivatives, the speeds u (replaced through
    ``kd_eqs``), the time ``dynamicsymbols._t`` (nhham's ``t``) and the
    ``inputs``; a force constant in ``frame`` and free of inputs and time goes
    into V instead (-F . r(P), the same equations). An actuator
    (``LinearSpring``, ``LinearDamper``, ``ForceActuator``,
    ``TorqueActuator``, anything with ``to_loads()``) contributes its
    ``to_loads()`` as loads (a spring as a force, not as a potential).

    Constraints written in generalized speeds u, with kinematic differential
    equations ``kd_eqs`` as ``KanesMethod`` takes them (affine in u and in
    q'; e.g. ``q1' - u1``), are brought to nhham's (q, q') form by solving
    the ``kd_eqs`` for u; ``velocity_constraints`` become velocity constraints
    (affine, or nonlinear with Chetaev's rule), ``configuration_constraints`` holonomic ones.
    Angular velocities and point velocities given in u are converted the
    same way.

    Parameters
    ----------
    lagrangian : sympy.Expr or sympy.physics.mechanics.System, optional
        L in the dynamicsymbols ``q`` and their first time derivatives (and
        u when ``kd_eqs`` are given), or a ``System`` or ``LagrangesMethod``
        (then every other argument but ``parameters``, ``name``, ``inputs``
        and ``drop_redundant`` must be left out).
    q : sequence of dynamicsymbols
        Generalized coordinates, each an undefined function of time
        (``dynamicsymbols('x')``); ``x(t)`` becomes coordinate ``x`` with
        velocity ``x_dot``.
    hol_coneqs : sequence of sympy.Expr, optional
        Holonomic constraints g(q(t)) = 0 (as for ``LagrangesMethod``).
    nonhol_coneqs : sequence of sympy.Expr, optional
        Velocity constraints in q'(t) (each = 0): affine, or nonlinear ones taken with
        Chetaev's rule. ``Eq`` objects are read as lhs - rhs.
    parameters : mapping or sequence, optional
        Passed to :class:`System`. Default: every remaining free symbol
        except time and the inputs, sorted by name, without values.
    name : str, optional
    bodies : sequence of RigidBody or Particle, optional
        Their kinetic energies in ``frame`` are added to L. A mass centre's
        velocity is taken as the time derivative of its position from
        ``origin``: the free velocity, never one that a constraint was
        substituted into.
    loads : sequence, optional
        ``Force(point, vector)`` or ``(point, vector)``, ``Torque(frame,
        vector)`` or ``(frame, vector)``, of any dependence on the state, the
        time and the inputs (see Forces above). The point must be located
        from ``origin``; the frame's angular velocity in ``frame`` known.
    actuators : sequence, optional
        Actuators of ``sympy.physics.mechanics`` (anything with
        ``to_loads()``); their loads are read as ``loads``.
    frame : ReferenceFrame, optional
        The inertial frame (needed with ``bodies``, ``loads`` or ``actuators``).
    origin : Point, optional
        A point fixed in ``frame`` from which positions are measured.
    u : sequence of dynamicsymbols, optional
        Generalized speeds; default: every function of time in ``kd_eqs``
        that is not a coordinate.
    kd_eqs : sequence of sympy.Expr, optional
        Kinematic differential equations (each = 0), affine in u and q',
        one per speed.
    velocity_constraints : sequence of sympy.Expr, optional
        Constraints in u (or q'), each = 0: affine, or nonlinear ones taken with
        Chetaev's rule (the kd_eqs are affine, so the rule is the same in u and q').
    configuration_constraints : sequence of sympy.Expr, optional
        Holonomic constraints in q.
    inputs : sequence of dynamicsymbols, sympy.Symbol or str, optional
        Inputs (controls; sympy's "specified" symbols) the loads may use. A
        dynamicsymbol ``T(t)`` becomes the plain input symbol ``T``
        (:attr:`System.inputs`), set at run time by the numeric layer; a
        Symbol or name ``T`` is that input too, for ``T`` and ``T(t)`` alike.
        Inputs may not appear in L nor in the constraints.
    drop_redundant : bool, optional
        Passed to :class:`System`: drop velocity constraints that are combinations
        of the others instead of refusing them (default False).

    Returns
    -------
    System
        With ``forces`` (Q per coordinate) and ``inputs`` when loads other
        than gravity-type forces are given.

    Problems found by :class:`System` name the constraints as given here
    (``nonholonomic_constraints[3]``, ``nonhol_coneqs[0]``, ``hol_coneqs[1]``).

    Raises
    ------
    ValidationError
        (an :class:`InputError`) naming each term nhham cannot express:
        explicit time dependence or inputs in L or the constraints,
        accelerations, functions of time that are not coordinates (nor, in a
        load, speeds or inputs), speeds that no kinematic equation defines,
        plain symbols named like a coordinate or velocity, a constraint or
        kinematic equation not affine in u, an object that is not a load or
        an actuator, a load on a point with no position from the origin or on
        a frame with no angular velocity in ``frame``, a load depending on
        accelerations or on a function of time not listed in ``inputs``, a
        body whose mass centre has no position from the origin; then
        whatever :class:`System` finds (non-affine constraints...).

    Examples
    --------
    A particle on a line with viscous friction and a driving force F(t):

    >>> import sympy as sp, sympy.physics.mechanics as me
    >>> from nhham import from_mechanics
    >>> x, F = me.dynamicsymbols("x F")
    >>> m, c = sp.symbols("m c")
    >>> N, O = me.ReferenceFrame("N"), me.Point("O")
    >>> P = O.locatenew("P", x * N.x)
    >>> s = from_mechanics(q=[x], bodies=[me.Particle("p", P, m)],
    ...                    loads=[(P, (F - c * x.diff()) * N.x)], frame=N, origin=O,
    ...                    inputs=[F])
    >>> s.generalized_forces.T, s.inputs
    (Matrix([[F - c*x_dot]]), (F,))
    """
    if isinstance(lagrangian, (me.System, me.LagrangesMethod)):
        given = dict(q=q, hol_coneqs=hol_coneqs, nonhol_coneqs=nonhol_coneqs, bodies=bodies,
                     loads=loads, actuators=actuators, frame=frame, origin=origin, u=u,
                     kd_eqs=kd_eqs, velocity_constraints=velocity_constraints,
                     configuration_constraints=configuration_constraints)
        extra = [k for k, v in given.items() if v is not None and v != ()]
        kind = type(lagrangian).__name__
        if extra:
            raise InputError(f"from_mechanics: with a sympy.physics.mechanics.{kind} give only "
                             f"parameters, name, inputs and drop_redundant (also given: "
                             f"{', '.join(extra)})")
        if isinstance(lagrangian, me.LagrangesMethod):
            return from_lagranges_method(lagrangian, parameters, name, inputs=inputs,
                                         drop_redundant=drop_redundant)
        return _from_me_system(lagrangian, parameters, name, drop_redundant, inputs)
    if isinstance(lagrangian, me.KanesMethod):
        raise InputError(
            "from_mechanics: a KanesMethod holds the equations of motion, not the energies "
            "nor the point positions are measured from; pass the "
            "sympy.physics.mechanics.System it is formed from (system.form_eoms() makes "
            "the KanesMethod), or its pieces: from_mechanics(q=q, u=u, kd_eqs=kdes, "
            "bodies=bodies, loads=loads, frame=N, origin=O, velocity_constraints=...)")
    if q is None:
        raise InputError(f"from_mechanics: the coordinates q are required (got a "
                         f"{type(lagrangian).__name__} and no q)" if lagrangian is not None
                         else "from_mechanics: the coordinates q are required")
    return _from_pieces(lagrangian, q, hol_coneqs, nonhol_coneqs, parameters, name,
                        bodies=bodies, loads=loads, actuators=actuators, frame=frame,
                        origin=origin, u=u, kd_eqs=kd_eqs,
                        velocity_constraints=velocity_constraints,
                        configuration_constraints=configuration_constraints, inputs=inputs,
                        drop_redundant=drop_redundant, labels=_ARGUMENT_LABELS)


# How the constraints and kinematic equations are called in messages: the keyword
# arguments of from_mechanics, or the attributes of a sympy.physics.mechanics.System.
_ARGUMENT_LABELS = {"velocity": "velocity_constraints",
                    "configuration": "configuration_constraints", "kd": "kd_eqs"}
_SYSTEM_LABELS = {"velocity": "nonholonomic_constraints",
                  "configuration": "holonomic_constraints", "kd": "kdes"}


def _from_pieces(lagrangian, q, hol_coneqs, nonhol_coneqs, parameters, name, *, bodies, loads,
                 actuators, frame, origin, u, kd_eqs, velocity_constraints,
                 configuration_constraints, inputs, drop_redundant, labels) -> System:
    """:func:`from_mechanics` once the way in is known (``labels``: names in messages)."""
    coords = coordinate_functions(q)
    t = me.dynamicsymbols._t
    problems: list[str] = []
    to_q = speed_substitution(coords, u, kd_eqs, t, problems, labels["kd"])
    inputs_in, plain_inputs = input_map(inputs, coords, to_q, problems)
    if lagrangian is None:
        if not bodies and not loads and not actuators:
            raise InputError("from_mechanics: give a Lagrangian, or bodies (and loads)")
        lagrangian = sp.S.Zero
    else:
        lagrangian = as_expr("lagrangian", lagrangian)
    forces = None
    if bodies or loads or actuators:
        items = load_items(loads, actuators, problems)
        if frame is None or origin is None:
            problems.append("frame, origin: bodies and loads need the inertial frame and a "
                            "point fixed in it (frame=N, origin=O)")
        else:
            as_given = {k for k in inputs_in if isinstance(k, sp.Symbol)}
            potential, forced = split_loads(items, frame, as_given | set(plain_inputs),
                                            problems)
            lagrangian = lagrangian + lagrangian_of(bodies, potential, frame, origin,
                                                    problems)

            def velocity_of(label, point, problems):
                return free_velocity(label, point, frame, origin, problems, "the point")

            forces = generalized_forces(forced, coords, frame, velocity_of, to_q,
                                        inputs_in, problems)
    vcons = []
    for i, c in enumerate(velocity_constraints):
        c = as_expr(f"{labels['velocity']}[{i}]", c)
        vcons.append(c)
    if problems:
        raise ValidationError(problems)
    if to_q:
        lagrangian = lagrangian.xreplace(to_q)
        vcons = [c.xreplace(to_q) for c in vcons]
    rename = plain_map(coords, t)
    speeds = {s: sp.sympify(e).xreplace(rename) for s, e in to_q.items()}
    return _from_lagrangian(lagrangian, coords, list(hol_coneqs) + list(configuration_constraints),
                            list(nonhol_coneqs) + vcons, parameters, name,
                            hol_labels=[f"hol_coneqs[{i}]" for i in range(len(hol_coneqs))]
                            + [f"{labels['configuration']}[{i}]"
                               for i in range(len(configuration_constraints))],
                            nonhol_labels=[f"nonhol_coneqs[{i}]" for i in range(len(nonhol_coneqs))]
                            + [f"{labels['velocity']}[{i}]" for i in range(len(vcons))],
                            drop_redundant=drop_redundant, forces=forces, inputs=plain_inputs,
                            speeds=speeds)


def _from_lagrangian(lagrangian, coords, hols, nonhols, parameters, name, hol_labels,
                     nonhol_labels, drop_redundant=False, forces=None, inputs=(),
                     speeds=None) -> System:
    """The System of L and the constraints in dynamicsymbols; ``forces``: Q per coordinate
    already in plain symbols (or None), ``inputs``: the plain input symbols."""
    t = me.dynamicsymbols._t
    to_plain = plain_map(coords, t)
    reserved = {s.name for s in to_plain.values()}
    items = [("lagrangian", lagrangian)]
    items += list(zip(hol_labels, hols)) + list(zip(nonhol_labels, nonhols))
    problems: list[str] = []
    converted: dict = {}
    input_names = {u.name for u in inputs}
    for label, expr in items:
        converted[label] = convert(label, as_expr(label, expr), to_plain, reserved, t, problems)
        used = sorted({s.name for s in converted[label].free_symbols} & input_names)
        if used:
            problems.append(f"{label}: uses the input(s) {', '.join(used)}; inputs may appear "
                            f"in loads (forces) only")
    if problems:
        raise ValidationError(problems)
    applied = list(forces) if forces is not None and any(f != 0 for f in forces) else None
    if parameters is None:
        parameters = remaining_symbols(list(converted.values()) + (applied or []),
                                       reserved | input_names | {TIME.name})
    try:
        return System(
            [to_plain[f] for f in coords],
            converted["lagrangian"],
            constraints=[converted[label] for label in nonhol_labels],
            holonomic=[converted[label] for label in hol_labels],
            parameters=parameters,
            name=name,
            drop_redundant=drop_redundant,
            forces=applied,
            inputs=tuple(inputs),
            speeds=speeds,
        )
    except ValidationError as exc:  # System's constraints[i] are the user's labels
        names = {"constraints": nonhol_labels, "holonomic": hol_labels}
        raise type(exc)([_CONSTRAINT_LABEL.sub(
            lambda m: names[m.group(1)][int(m.group(2))], p) for p in exc.problems]) from None


# A constraint as System names it (not inside a longer name such as nonhol_coneqs[0]).
_CONSTRAINT_LABEL = re.compile(r"(?<![\w.\[])(constraints|holonomic)\[(\d+)\]")


def _from_me_system(msys, parameters, name, drop_redundant=False, inputs=()) -> System:
    """Read a ``sympy.physics.mechanics.System`` (see :func:`from_mechanics`)."""
    q = list(msys.q)
    if not q:
        raise InputError("from_mechanics: the System has no coordinates (add_coordinates)")
    u = list(msys.u)
    return _from_pieces(
        None, q, (), (), parameters, name,
        bodies=list(msys.bodies), loads=list(msys.loads),
        actuators=list(getattr(msys, "actuators", ()) or ()), frame=msys.frame,
        origin=msys.fixed_point, u=u or None, kd_eqs=list(msys.kdes),
        velocity_constraints=list(msys.nonholonomic_constraints),
        configuration_constraints=list(msys.holonomic_constraints), inputs=inputs,
        drop_redundant=drop_redundant, labels=_SYSTEM_LABELS,
    )

def from_lagranges_method(lm: me.LagrangesMethod, parameters=None, name: str = "", *,
                          inputs: Sequence = (), drop_redundant: bool = False) -> System:
    """Build a :class:`System` from a ``LagrangesMethod`` object.

    Uses the Lagrangian ``lm._L``, the coordinates ``lm.q``, the applied
    forces ``lm.forcelist`` and the constraints the object was built with:
    ``lm._hol_coneqs`` (holonomic) and the rest of ``lm.coneqs`` (whose first
    entries are the time derivatives of the holonomic ones; sympy 1.14 stores
    no other copy of ``nonhol_coneqs``).

    The forcelist, ``(Point, Vector)`` and ``(ReferenceFrame, Vector)`` pairs,
    gives the generalized forces as ``LagrangesMethod`` computes them:
    Q_A = F . d(P.vel(N))/dq'_A and T . d(B.ang_vel_in(N))/dq'_A with N =
    ``lm.inertial``, the velocities being those of the points as set
    (``set_vel``) or found by ``Point.vel``; the equations are
    d/dt(dL/dv) - dL/dq = Q - mu^T lambda (``DESIGN.md`` §2). Every force
    becomes a generalized force (none goes into L). Time
    ``dynamicsymbols._t`` becomes nhham's ``t``; other functions of time in a
    force must be listed in ``inputs``.

    Parameters
    ----------
    lm : sympy.physics.mechanics.LagrangesMethod
    parameters : mapping or sequence, optional
        As for :func:`from_mechanics`.
    name : str, optional
    inputs : sequence of dynamicsymbols or sympy.Symbol, optional
        As for :func:`from_mechanics`: the inputs the forces use (``T(t)``
        becomes the input ``T``).
    drop_redundant : bool, optional
        As for :func:`from_mechanics`.

    Raises
    ------
    InputError
        If ``lm`` is not a ``LagrangesMethod``, or has forces but no frame.
    ValidationError
        Naming ``forcelist[i]`` for a force nhham cannot express (a point
        without a velocity in the frame, accelerations, a function of time
        not listed in ``inputs``); otherwise as :func:`from_mechanics`.

    Examples
    --------
    A particle in the plane on y' = x x', pulled back to y = 0 by a spring:

    >>> import sympy as sp, sympy.physics.mechanics as me
    >>> from nhham import from_lagranges_method
    >>> x, y = me.dynamicsymbols("x y")
    >>> m, k = sp.symbols("m k")
    >>> N, O = me.ReferenceFrame("N"), me.Point("O")
    >>> P = O.locatenew("P", x * N.x + y * N.y)
    >>> P.set_vel(N, P.pos_from(O).dt(N))
    >>> L = me.Lagrangian(N, me.Particle("p", P, m))
    >>> lm = me.LagrangesMethod(L, [x, y], nonhol_coneqs=[y.diff() - x * x.diff()],
    ...                         forcelist=[(P, -k * y * N.y)], frame=N)
    >>> s = from_lagranges_method(lm, parameters={"m": 1.0, "k": 2.0})
    >>> s.lagrangian, s.phi, s.generalized_forces.T
    (m*(x_dot**2 + y_dot**2)/2, (-x*x_dot + y_dot,), Matrix([[0, -k*y]]))
    """
    if not isinstance(lm, me.LagrangesMethod):
        raise InputError(f"from_lagranges_method: expected a LagrangesMethod, got "
                         f"{type(lm).__name__}")
    coords = coordinate_functions(list(lm.q))
    problems: list[str] = []
    inputs_in, plain_inputs = input_map(inputs, coords, {}, problems)
    forces = None
    if lm.forcelist:
        frame = lm.inertial
        if frame is None:
            raise InputError("from_lagranges_method: the LagrangesMethod has a forcelist but "
                             "no inertial frame (LagrangesMethod(..., frame=N))")
        items = load_items(lm.forcelist, (), problems, kind="forcelist")
        forced = []
        for label, where, vector in items:
            comps = components(label, vector, frame, problems)
            if comps is not None:
                forced.append((label, where, vector, comps))

        def point_velocity(label, point, problems):
            try:
                return point.vel(frame)
            except ValueError:
                problems.append(f"{label}: the point {point} has no velocity in {frame} "
                                f"(set_vel, or locate it from a point whose velocity is set)")
                return None

        forces = generalized_forces(forced, coords, frame, point_velocity, {}, inputs_in,
                                    problems)
    if problems:
        raise ValidationError(problems)
    hol = list(lm._hol_coneqs)
    nonhol = list(lm.coneqs)[len(hol):]
    return _from_lagrangian(as_expr("lagrangian", lm._L[0]), coords, hol, nonhol, parameters,
                            name, hol_labels=[f"hol_coneqs[{i}]" for i in range(len(hol))],
                            nonhol_labels=[f"nonhol_coneqs[{i}]" for i in range(len(nonhol))],
                            drop_redundant=drop_redundant, forces=forces, inputs=plain_inputs)


# ------------------------------------------------------------------- out of
def to_lagranges_method(system: System) -> MechanicsForm:
    """The same system as a ``sympy.physics.mechanics.LagrangesMethod``.

    Holonomic constraints go in as ``hol_coneqs`` (LagrangesMethod
    differentiates them itself), affine constraints as ``nonhol_coneqs``.
    Parameters stay symbols; substitute ``system.parameter_values`` for
    numbers. ``form_lagranges_equations`` is not called.

    Forces: for each coordinate q_A with a generalized force Q_A != 0
    (:attr:`System.generalized_forces`, the dissipation's included) the
    ``forcelist`` has a point ``P_<q_A>`` whose velocity in the inertial
    frame ``N`` (``lm.inertial``) is set to q_A'(t) N.x and the force
    Q_A N.x on it: its partial velocities are N.x along q_A' and 0 along the
    others, so LagrangesMethod's generalized force is exactly Q_A and
    ``lm.eom`` reads d/dt(dL/dq') - dL/dq - Q + mu^T lam (nhham's
    d/dt(dL/dv) - dL/dq = Q - mu^T lambda, ``DESIGN.md`` §2). Inputs become
    dynamicsymbols of the same name (``u -> u(t)``), the time ``t`` is
    ``dynamicsymbols._t``.

    Parameters
    ----------
    system : System

    Returns
    -------
    MechanicsForm
        ``(lm, q, maps)``: the LagrangesMethod, the coordinate dynamicsymbols
        (in ``system.coordinates`` order) and the :class:`Substitutions`
        (inputs included).
    """
    t = me.dynamicsymbols._t
    # Function(name)(t) equals dynamicsymbols(name) but does not run the
    # name through symbols()' range and comma syntax.
    qs = tuple(sp.Function(q.name)(t) for q in system.coordinates)
    to_mech: dict = {}
    for q, v, f in zip(system.coordinates, system.velocities, qs):
        to_mech[q] = f
        to_mech[v] = f.diff(t)
    for u in system.inputs:
        to_mech[u] = sp.Function(u.name)(t)
    back: dict = {}
    for q, v, f in zip(system.coordinates, system.velocities, qs):
        back[f] = q
        back[f.diff(t)] = v
        back[f.diff(t, 2)] = acceleration_symbol(q)
    for u in system.inputs:
        back[to_mech[u]] = u
    for i in range(1, system.m + 1):
        back[sp.Function(f"lam{i}")(t)] = multiplier_symbol(i)
    forcelist, frame = [], None
    if system.has_forces:
        frame = me.ReferenceFrame("N")
        for q, f, force in zip(system.coordinates, qs, system.generalized_forces):
            if force == 0:
                continue
            point = me.Point(f"P_{q.name}")
            point.set_vel(frame, f.diff(t) * frame.x)
            forcelist.append((point, force.xreplace(to_mech) * frame.x))
    lm = me.LagrangesMethod(
        system.lagrangian.xreplace(to_mech), list(qs),
        forcelist=forcelist or None, frame=frame,
        hol_coneqs=[g.xreplace(to_mech) for g in system.holonomic] or None,
        nonhol_coneqs=[c.xreplace(to_mech) for c in system.constraints] or None,
    )
    maps = Substitutions(MappingProxyType(to_mech), MappingProxyType(back))
    return MechanicsForm(lm, qs, maps)
