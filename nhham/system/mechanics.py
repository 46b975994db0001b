"""Bridges to :mod:`sympy.physics.mechanics`.

:func:`from_mechanics` and :func:`from_lagranges_method` turn a Lagrangian
and constraints written in dynamicsymbols q(t), q(t).diff(t) into an
:class:`nhham.System`; :func:`to_lagranges_method` goes the other way, so
that tests and benchmarks can run ``LagrangesMethod`` on exactly the system
nhham sees.

Names: the dynamicsymbol ``q1(t)`` becomes the coordinate ``q1`` and its
derivative the velocity ``q1_dot``.

Multipliers: ``LagrangesMethod.eom`` is d/dt(dL/dq') - dL/dq - lam_coeffs^T lam
with lam_coeffs = -d(coneqs)/dq', i.e. d/dt(dL/dv) - dL/dq + mu^T lam = 0,
nhham's convention (``DESIGN.md`` §2); its constraint order (time
derivatives of the holonomic constraints first, then the nonholonomic ones)
is nhham's order of :attr:`System.phi`. So ``lam<i>(t)`` in ``lm.eom``
corresponds to ``lambda_<i>``. Beware: sympy 1.14's ``mass_matrix`` appends
``lam_coeffs.T`` itself, so the multipliers solved from
``mass_matrix_full``/``rhs()`` are the negatives of those in ``lm.eom``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from types import MappingProxyType
from typing import Mapping, NamedTuple, Sequence

import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.physics import mechanics as me

from nhham.errors import InputError, ValidationError
from nhham.system.expressions import short
from nhham.system.naming import acceleration_symbol, multiplier_symbol, velocity_symbol
from nhham.system.description import System

__all__ = [
    "from_mechanics",
    "from_lagranges_method",
    "to_lagranges_method",
    "MechanicsForm",
    "Substitutions",
]

# Longest expression quoted in an error message.
_QUOTE = 80


@dataclass(frozen=True)
class Substitutions:
    """Maps between nhham's plain symbols and dynamicsymbols.

    Attributes
    ----------
    to_mechanics : mapping
        ``q -> q(t)``, ``q_dot -> q(t).diff(t)`` for every coordinate.
    from_mechanics : mapping
        ``q(t) -> q``, ``q'(t) -> q_dot``, ``q''(t) -> q_ddot`` and the
        multipliers ``lam<i>(t) -> lambda_<i>``. Use with ``xreplace`` (not
        ``subs``: a derivative must be replaced as a whole).
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
                   bodies: Sequence = (), loads: Sequence = (), frame=None, origin=None,
                   u: Sequence | None = None, kd_eqs: Sequence = (),
                   velocity_constraints: Sequence = (),
                   configuration_constraints: Sequence = (),
                   drop_redundant: bool = False) -> System:
    """Build a :class:`System` from a ``sympy.physics.mechanics`` description.

    Three ways in, which may be combined:

    1. a Lagrangian: ``from_mechanics(L, q, hol_coneqs, nonhol_coneqs)``
       (as ``LagrangesMethod`` takes them);
    2. bodies and loads: ``from_mechanics(q=q, bodies=..., loads=...,
       frame=N, origin=O)``; L = T - V with T the kinetic energy of every
       body in ``frame`` and V the potential of every constant force
       (gravity type);
    3. a ``sympy.physics.mechanics.System`` as the first argument: its
       frame, fixed point, bodies, loads, coordinates ``q``, speeds ``u``,
       kinematic differential equations ``kdes``, ``holonomic_constraints``
       and ``nonholonomic_constraints`` are read as in 2.

    A ``LagrangesMethod`` is read as :func:`from_lagranges_method` reads it. A
    ``KanesMethod`` is refused with a pointer to the ``System`` it is formed
    from: it holds the equations of motion, not the energies nor the point from
    which positions are measured.

    Constraints written in generalized speeds u, with kinematic differential
    equations ``kd_eqs`` as ``KanesMethod`` takes them (affine in u and in
    q'; e.g. ``q1' - u1``), are brought to nhham's (q, q') form by solving
    the ``kd_eqs`` for u; ``velocity_constraints`` (affine in u) become
    affine constraints, ``configuration_constraints`` holonomic ones.
    Angular velocities and point velocities given in u are converted the
    same way.

    Parameters
    ----------
    lagrangian : sympy.Expr or sympy.physics.mechanics.System, optional
        L in the dynamicsymbols ``q`` and their first time derivatives (and
        u when ``kd_eqs`` are given), or a ``System`` (then every other
        argument but ``parameters`` and ``name`` must be left out).
    q : sequence of dynamicsymbols
        Generalized coordinates, each an undefined function of time
        (``dynamicsymbols('x')``); ``x(t)`` becomes coordinate ``x`` with
        velocity ``x_dot``.
    hol_coneqs : sequence of sympy.Expr, optional
        Holonomic constraints g(q(t)) = 0 (as for ``LagrangesMethod``).
    nonhol_coneqs : sequence of sympy.Expr, optional
        Constraints affine in q'(t) (each = 0). ``Eq`` objects are read as
        lhs - rhs.
    parameters : mapping or sequence, optional
        Passed to :class:`System`. Default: every remaining free symbol
        except time, sorted by name, without values.
    name : str, optional
    bodies : sequence of RigidBody or Particle, optional
        Their kinetic energies in ``frame`` are added to L. A mass centre's
        velocity is taken as the time derivative of its position from
        ``origin``: the free velocity, never one that a constraint was
        substituted into.
    loads : sequence, optional
        ``Force(point, vector)`` or ``(point, vector)`` with a vector
        constant in ``frame`` (gravity type): potential -F . r(point).
        Anything else (torques, forces depending on the state or on time,
        actuators) is refused with an error naming the load.
    frame : ReferenceFrame, optional
        The inertial frame (needed with ``bodies`` or ``loads``).
    origin : Point, optional
        A point fixed in ``frame`` from which positions are measured.
    u : sequence of dynamicsymbols, optional
        Generalized speeds; default: every function of time in ``kd_eqs``
        that is not a coordinate.
    kd_eqs : sequence of sympy.Expr, optional
        Kinematic differential equations (each = 0), affine in u and q',
        one per speed.
    velocity_constraints : sequence of sympy.Expr, optional
        Constraints affine in u (or q'), each = 0.
    configuration_constraints : sequence of sympy.Expr, optional
        Holonomic constraints in q.
    drop_redundant : bool, optional
        Passed to :class:`System`: drop velocity constraints that are combinations
        of the others instead of refusing them (default False).

    Returns
    -------
    System

    Problems found by :class:`System` name the constraints as given here
    (``nonholonomic_constraints[3]``, ``nonhol_coneqs[0]``, ``hol_coneqs[1]``).

    Raises
    ------
    ValidationError
        (an :class:`InputError`) naming each term nhham cannot express:
        explicit time dependence, accelerations, functions of time that are
        not coordinates, speeds that no kinematic equation defines, plain
        symbols named like a coordinate or velocity, a constraint or
        kinematic equation not affine in u, a load that is not a constant
        force, a body whose mass centre has no position from the origin;
        then whatever :class:`System` finds (non-affine constraints...).
    """
    if isinstance(lagrangian, (me.System, me.LagrangesMethod)):
        given = dict(q=q, hol_coneqs=hol_coneqs, nonhol_coneqs=nonhol_coneqs, bodies=bodies,
                     loads=loads, frame=frame, origin=origin, u=u, kd_eqs=kd_eqs,
                     velocity_constraints=velocity_constraints,
                     configuration_constraints=configuration_constraints)
        extra = [k for k, v in given.items() if v is not None and v != ()]
        kind = type(lagrangian).__name__
        if extra:
            raise InputError(f"from_mechanics: with a sympy.physics.mechanics.{kind} give only "
                             f"parameters, name and drop_redundant (also given: "
                             f"{', '.join(extra)})")
        if isinstance(lagrangian, me.LagrangesMethod):
            return from_lagranges_method(lagrangian, parameters, name,
                                         drop_redundant=drop_redundant)
        return _from_me_system(lagrangian, parameters, name, drop_redundant)
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
                        bodies=bodies, loads=loads, frame=frame, origin=origin, u=u,
                        kd_eqs=kd_eqs, velocity_constraints=velocity_constraints,
                        configuration_constraints=configuration_constraints,
                        drop_redundant=drop_redundant, labels=_ARGUMENT_LABELS)


# How the constraints and kinematic equations are called in messages: the keyword
# arguments of from_mechanics, or the attributes of a sympy.physics.mechanics.System.
_ARGUMENT_LABELS = {"velocity": "velocity_constraints",
                    "configuration": "configuration_constraints", "kd": "kd_eqs"}
_SYSTEM_LABELS = {"velocity": "nonholonomic_constraints",
                  "configuration": "holonomic_constraints", "kd": "kdes"}


def _from_pieces(lagrangian, q, hol_coneqs, nonhol_coneqs, parameters, name, *, bodies, loads,
                 frame, origin, u, kd_eqs, velocity_constraints, configuration_constraints,
                 drop_redundant, labels) -> System:
    """:func:`from_mechanics` once the way in is known (``labels``: names in messages)."""
    coords = _coordinate_functions(q)
    t = me.dynamicsymbols._t
    problems: list[str] = []
    to_q = _speed_substitution(coords, u, kd_eqs, t, problems, labels["kd"])
    if lagrangian is None:
        if not bodies and not loads:
            raise InputError("from_mechanics: give a Lagrangian, or bodies (and loads)")
        lagrangian = sp.S.Zero
    else:
        lagrangian = _as_expr("lagrangian", lagrangian)
    if bodies or loads:
        lagrangian = lagrangian + _lagrangian_of(bodies, loads, frame, origin, problems)
    speeds = tuple(to_q) if to_q else ()
    vcons = []
    for i, c in enumerate(velocity_constraints):
        c = _as_expr(f"{labels['velocity']}[{i}]", c)
        _check_affine(f"{labels['velocity']}[{i}]", c, speeds, problems)
        vcons.append(c)
    if problems:
        raise ValidationError(problems)
    if to_q:
        lagrangian = lagrangian.xreplace(to_q)
        vcons = [c.xreplace(to_q) for c in vcons]
    return _from_lagrangian(lagrangian, coords, list(hol_coneqs) + list(configuration_constraints),
                            list(nonhol_coneqs) + vcons, parameters, name,
                            hol_labels=[f"hol_coneqs[{i}]" for i in range(len(hol_coneqs))]
                            + [f"{labels['configuration']}[{i}]"
                               for i in range(len(configuration_constraints))],
                            nonhol_labels=[f"nonhol_coneqs[{i}]" for i in range(len(nonhol_coneqs))]
                            + [f"{labels['velocity']}[{i}]" for i in range(len(vcons))],
                            drop_redundant=drop_redundant)


def _from_lagrangian(lagrangian, coords, hols, nonhols, parameters, name, hol_labels,
                     nonhol_labels, drop_redundant=False) -> System:
    t = me.dynamicsymbols._t
    to_plain = _plain_map(coords, t)
    reserved = {s.name for s in to_plain.values()}
    items = [("lagrangian", lagrangian)]
    items += list(zip(hol_labels, hols)) + list(zip(nonhol_labels, nonhols))
    problems, converted = [], {}
    for label, expr in items:
        converted[label] = _convert(label, _as_expr(label, expr), to_plain, reserved, t, problems)
    if problems:
        raise ValidationError(problems)
    if parameters is None:
        parameters = _remaining_symbols(converted.values(), reserved)
    try:
        return System(
            [to_plain[f] for f in coords],
            converted["lagrangian"],
            constraints=[converted[label] for label in nonhol_labels],
            holonomic=[converted[label] for label in hol_labels],
            parameters=parameters,
            name=name,
            drop_redundant=drop_redundant,
        )
    except ValidationError as exc:  # System's constraints[i] are the user's labels
        names = {"constraints": nonhol_labels, "holonomic": hol_labels}
        raise type(exc)([_CONSTRAINT_LABEL.sub(
            lambda m: names[m.group(1)][int(m.group(2))], p) for p in exc.problems]) from None


# A constraint as System names it (not inside a longer name such as nonhol_coneqs[0]).
_CONSTRAINT_LABEL = re.compile(r"(?<![\w.\[])(constraints|holonomic)\[(\d+)\]")


def _from_me_system(msys, parameters, name, drop_redundant=False) -> System:
    """Read a ``sympy.physics.mechanics.System`` (see :func:`from_mechanics`)."""
    problems = []
    actuators = list(getattr(msys, "actuators", ()) or ())
    for i, act in enumerate(actuators):
        problems.append(f"actuators[{i}]: {short(act, _QUOTE)} is an actuator; nhham takes "
                        f"conservative loads only (forces are not supported yet)")
    if problems:
        raise ValidationError(problems)
    q = list(msys.q)
    if not q:
        raise InputError("from_mechanics: the System has no coordinates (add_coordinates)")
    u = list(msys.u)
    return _from_pieces(
        None, q, (), (), parameters, name,
        bodies=list(msys.bodies), loads=list(msys.loads), frame=msys.frame,
        origin=msys.fixed_point, u=u or None, kd_eqs=list(msys.kdes),
        velocity_constraints=list(msys.nonholonomic_constraints),
        configuration_constraints=list(msys.holonomic_constraints),
        drop_redundant=drop_redundant, labels=_SYSTEM_LABELS,
    )


def _speed_substitution(coords, u, kd_eqs, t, problems, kd="kd_eqs") -> dict:
    """{u_k: expression in q, q'} from the kinematic differential equations (``kd``: their
    name in messages)."""
    if not kd_eqs:
        if u:
            problems.append(f"{kd}: speeds u were given but no kinematic differential "
                            f"equations define them")
        return {}
    qset = set(coords) | {f.diff(t) for f in coords}
    eqs = [_as_expr(f"{kd}[{i}]", e) for i, e in enumerate(kd_eqs)]
    if u is None:
        found = set()
        for e in eqs:
            found |= {f for f in e.atoms(AppliedUndef) if f.args == (t,) and f not in qset}
        u = sorted(found, key=lambda f: f.func.__name__)
    u = list(u)
    bad = [f for f in u if not (isinstance(f, AppliedUndef) and f.args == (t,))]
    for f in bad:
        problems.append(f"u: {f} is not a dynamicsymbol")
    if bad:
        return {}
    if len(eqs) != len(u):
        problems.append(f"{kd}: {len(eqs)} kinematic differential equations for {len(u)} "
                        f"speeds {', '.join(map(str, u))}; one per speed is needed")
        return {}
    for i, e in enumerate(eqs):
        _check_affine(f"{kd}[{i}]", e, tuple(u), problems)
    if problems:
        return {}
    B = sp.Matrix([[sp.diff(e, s) for s in u] for e in eqs])
    rest = sp.Matrix([e.xreplace({s: 0 for s in u}) for e in eqs])
    try:
        sol = B.LUsolve(-rest)
    except (ValueError, ZeroDivisionError, sp.matrices.exceptions.NonInvertibleMatrixError):
        problems.append(f"{kd}: cannot be solved for the speeds {', '.join(map(str, u))} "
                        f"(the coefficient matrix of u is singular)")
        return {}
    return {s: sp.simplify(x) if B != -sp.eye(len(u)) else sp.expand(x) for s, x in zip(u, sol)}


def _check_affine(label, expr, speeds, problems) -> None:
    """Record the terms of ``expr`` that are not affine in the speeds."""
    if not speeds:
        return
    sset = set(speeds)
    for term in sp.Add.make_args(sp.expand(expr)):
        for s in speeds:
            d = sp.diff(term, s)
            if d.atoms(AppliedUndef) & sset:
                problems.append(f"{label}: the term {short(term, _QUOTE)} is not affine in the "
                                f"speeds ({s} appears nonlinearly); nhham needs constraints "
                                f"affine in u")
                return


def _lagrangian_of(bodies, loads, frame, origin, problems) -> sp.Expr:
    """T - V of rigid bodies/particles and constant (gravity-type) forces."""
    if frame is None or origin is None:
        problems.append("frame, origin: bodies and loads need the inertial frame and a point "
                        "fixed in it (frame=N, origin=O)")
        return sp.S.Zero
    T = sp.S.Zero
    for i, body in enumerate(bodies):
        label = f"bodies[{i}] ({getattr(body, 'name', body)})"
        point = getattr(body, "masscenter", None) or getattr(body, "point", None)
        if point is None or not hasattr(body, "mass"):
            problems.append(f"{label}: not a RigidBody or Particle")
            continue
        vel = _free_velocity(label, point, frame, origin, problems)
        if vel is None:
            continue
        T += body.mass * vel.dot(vel) / 2
        body_frame = getattr(body, "frame", None)
        if body_frame is not None and hasattr(body, "central_inertia"):
            w = body_frame.ang_vel_in(frame)
            T += w.dot(body.central_inertia.dot(w)) / 2
    V = sp.S.Zero
    for i, load in enumerate(loads):
        label = f"loads[{i}]"
        where, vector = (load.location, load.vector) if hasattr(load, "location") else (
            tuple(load) if isinstance(load, (tuple, list)) and len(load) == 2 else (None, None))
        if where is None:
            problems.append(f"{label}: {short(load, _QUOTE)} is not a load (point, force)")
            continue
        if isinstance(where, me.ReferenceFrame):
            problems.append(f"{label}: the torque {short(vector, _QUOTE)} on frame {where} is not "
                            f"a potential force; nhham takes gravity-type loads only (forces are "
                            f"not supported yet)")
            continue
        comps = vector.to_matrix(frame) if vector != 0 else sp.zeros(3, 1)
        moving = sorted({str(f) for f in comps.atoms(AppliedUndef)}
                        | ({str(me.dynamicsymbols._t)} if comps.has(me.dynamicsymbols._t) else set()))
        if moving:
            problems.append(f"{label}: the force {short(vector, _QUOTE)} on {where} depends on "
                            f"{', '.join(moving)}; only forces constant in the inertial frame "
                            f"(gravity type) have a potential; other loads are not supported yet")
            continue
        try:
            r = where.pos_from(origin)
        except ValueError:
            problems.append(f"{label}: the point {where} has no position from the origin "
                            f"{origin}; locate it from there (locatenew)")
            continue
        V -= vector.dot(r)
    return T - V


def _free_velocity(label, point, frame, origin, problems):
    """d/dt of the position of ``point`` from ``origin`` in ``frame``."""
    try:
        r = point.pos_from(origin)
    except ValueError:
        problems.append(f"{label}: its mass centre {point} has no position from the origin "
                        f"{origin}; nhham needs the free velocity d/dt(position), not a "
                        f"velocity with constraints already substituted (set_vel): locate "
                        f"the point from the origin")
        return None
    return r.dt(frame)


def from_lagranges_method(lm: me.LagrangesMethod, parameters=None, name: str = "", *,
                          drop_redundant: bool = False) -> System:
    """Build a :class:`System` from a ``LagrangesMethod`` object.

    Uses the Lagrangian ``lm._L``, the coordinates ``lm.q`` and the
    constraints the object was built with: ``lm._hol_coneqs`` (holonomic)
    and the rest of ``lm.coneqs`` (whose first entries are the time
    derivatives of the holonomic ones; sympy 1.14 stores no other copy of
    ``nonhol_coneqs``).

    Parameters
    ----------
    lm : sympy.physics.mechanics.LagrangesMethod
    parameters : mapping or sequence, optional
        As for :func:`from_mechanics`.
    name : str, optional
    drop_redundant : bool, optional
        As for :func:`from_mechanics`.

    Raises
    ------
    InputError
        If ``lm`` carries applied forces (nhham has no force terms) or is
        not a ``LagrangesMethod``; otherwise as :func:`from_mechanics`.
    """
    if not isinstance(lm, me.LagrangesMethod):
        raise InputError(f"from_lagranges_method: expected a LagrangesMethod, got "
                         f"{type(lm).__name__}")
    if lm.forcelist:
        raise InputError("from_lagranges_method: the LagrangesMethod has a forcelist; nhham "
                         "takes conservative forces through the Lagrangian only (write them "
                         "as a potential)")
    hol = list(lm._hol_coneqs)
    nonhol = list(lm.coneqs)[len(hol):]
    return from_mechanics(lm._L[0], list(lm.q), hol, nonhol, parameters=parameters, name=name,
                          drop_redundant=drop_redundant)


def _coordinate_functions(q):
    """Check that every coordinate is a distinct function of time alone."""
    t = me.dynamicsymbols._t
    coords, problems = [], []
    for i, f in enumerate(q):
        if not (isinstance(f, AppliedUndef) and f.args == (t,)):
            problems.append(f"q[{i}]: {f} is not a dynamicsymbol (an undefined function of "
                            f"{t} alone, e.g. dynamicsymbols('x'))")
        else:
            coords.append(f)
    names = [f.func.__name__ for f in coords]
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        problems.append(f"q: duplicate coordinate names {', '.join(dupes)}")
    if problems:
        raise ValidationError(problems)
    return coords


def _plain_map(coords, t):
    """q(t) -> q and q'(t) -> q_dot (coordinates first, then velocities)."""
    plain = {}
    for f in coords:
        plain[f] = sp.Symbol(f.func.__name__)
    for f in coords:
        plain[f.diff(t)] = velocity_symbol(plain[f])
    return plain


def _as_expr(label, expr):
    if isinstance(expr, sp.Equality):
        return expr.lhs - expr.rhs
    if isinstance(expr, sp.MatrixBase) and expr.shape == (1, 1):
        return expr[0, 0]
    try:
        return sp.sympify(expr, strict=True)
    except (sp.SympifyError, TypeError):
        raise InputError(f"{label}: expected a sympy expression, got "
                         f"{type(expr).__name__} {expr!r}") from None


def _convert(label, expr, to_plain, reserved, t, problems):
    """Replace dynamicsymbols by plain symbols; record what cannot be expressed."""
    clash = sorted(s.name for s in expr.free_symbols if s != t and s.name in reserved)
    if clash:
        problems.append(f"{label}: plain symbol(s) {', '.join(clash)} have the name of a "
                        f"coordinate or velocity; rename them")
    for term in sp.Add.make_args(expr):
        reason = _inexpressible(term, to_plain, t)
        if reason:
            problems.append(f"{label}: the term {short(term, _QUOTE)} {reason}")
    # xreplace replaces a Derivative node before looking inside it, so
    # q'(t) becomes q_dot rather than d(q)/dt.
    return expr.xreplace(to_plain)


def _inexpressible(term, to_plain, t):
    """Why a term cannot be part of an autonomous system on TQ, or ''."""
    derivs = [d for d in term.atoms(sp.Derivative) if d not in to_plain]
    if derivs:
        return (f"contains {short(derivs[0], _QUOTE)}: only coordinates and their first "
                f"derivatives may appear")
    funcs = [f for f in term.xreplace(to_plain).atoms(AppliedUndef)]
    if funcs:
        return (f"contains {short(funcs[0], _QUOTE)}, a function of time that is not one of the "
                f"coordinates q")
    if t in term.xreplace(to_plain).free_symbols:
        return f"depends explicitly on time {t}; nhham handles autonomous systems only"
    return ""


def _remaining_symbols(exprs, reserved):
    names = sorted({s.name for e in exprs for s in e.free_symbols} - reserved)
    return names


# ------------------------------------------------------------------- out of
def to_lagranges_method(system: System) -> MechanicsForm:
    """The same system as a ``sympy.physics.mechanics.LagrangesMethod``.

    Holonomic constraints go in as ``hol_coneqs`` (LagrangesMethod
    differentiates them itself), affine constraints as ``nonhol_coneqs``.
    Parameters stay symbols; substitute ``system.parameter_values`` for
    numbers. ``form_lagranges_equations`` is not called.

    Parameters
    ----------
    system : System

    Returns
    -------
    MechanicsForm
        ``(lm, q, maps)``: the LagrangesMethod, the coordinate dynamicsymbols
        (in ``system.coordinates`` order) and the :class:`Substitutions`.
    """
    t = me.dynamicsymbols._t
    # Function(name)(t) equals dynamicsymbols(name) but does not run the
    # name through symbols()' range and comma syntax.
    qs = tuple(sp.Function(q.name)(t) for q in system.coordinates)
    to_mech = {}
    for q, v, f in zip(system.coordinates, system.velocities, qs):
        to_mech[q] = f
        to_mech[v] = f.diff(t)
    back = {}
    for q, v, f in zip(system.coordinates, system.velocities, qs):
        back[f] = q
        back[f.diff(t)] = v
        back[f.diff(t, 2)] = acceleration_symbol(q)
    for i in range(1, system.m + 1):
        back[sp.Function(f"lam{i}")(t)] = multiplier_symbol(i)
    lm = me.LagrangesMethod(
        system.lagrangian.xreplace(to_mech), list(qs),
        hol_coneqs=[g.xreplace(to_mech) for g in system.holonomic] or None,
        nonhol_coneqs=[c.xreplace(to_mech) for c in system.constraints] or None,
    )
    maps = Substitutions(MappingProxyType(to_mech), MappingProxyType(back))
    return MechanicsForm(lm, qs, maps)
