"""The system description: coordinates, Lagrangian, constraints, forces, parameters.

A :class:`System` is frozen and validated on construction. Every problem found
is collected and raised once as a :class:`~nhham.errors.ValidationError`
subclass whose message names the offending key (``lagrangian``,
``constraints[1]``, ``holonomic[0]``, ``parameters``) or expression.

Conventions (``DESIGN.md`` §2): coordinates q^A (A = 1..n) with velocities
``<q>_dot``; affine constraints phi_i = mu_iA(q) v^A + h_i(q), or constraints
phi_i(q, v) not affine in v taken with Chetaev's rule (mu_i = d phi_i/d v, a function of
q and v; :mod:`nhham.system.chetaev`); a holonomic
constraint g(q) = 0 contributes its complete lift g^c = (dg/dq^A) v^A as an
affine constraint (paper §4) and g = 0 is imposed on Q. In :attr:`System.phi`
the complete lifts come first (the paper's Example 4.1 order), then the user's
affine constraints in the order given.

Forces (``DESIGN.md`` §2): generalized forces Q_A(q, v, t, u) (the components of a
semibasic 1-form Q_A dq^A) and a Rayleigh dissipation function R(q, v), which adds
-dR/dv^A; the equations become d/dt(dL/dv) - dL/dq = Q - mu^T lambda. Named inputs u and
the time ``t`` may appear in forces only; for the geometry they are parameters without
values (a verdict holds for generic constant inputs, at any instant), listed last in
:attr:`System.parameters`; the numeric layer sets them at run time.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType
from typing import Mapping, Sequence

import numpy as np
import sympy as sp

from nhham.errors import NonAffineConstraintError, SingularLagrangianError, ValidationError
from nhham.autonomy import time_slot
from nhham.system.force_checks import dissipation_problems
from nhham.system.numbers import value_problem
from nhham.system.naming import TIME, as_symbol, velocity_symbol
from nhham.system.sampled_checks import (
    DroppedConstraint,
    check_dependence,
    singular_message,
    singular_rank,
)
from nhham.system.screening import coordinate_symbols, expression_problems
from nhham.system.chetaev import AFFINE, constraint_kind, degenerate_reactions
from nhham.system.velocities import (QuadraticParts, one_forms, quadratic_parts,
                                     velocity_free_part)

__all__ = ["System", "DroppedConstraint"]


@dataclass(frozen=True, eq=False, init=False, repr=False)
class System:
    """A Lagrangian system with affine and holonomic constraints.

    Parameters
    ----------
    coordinates : sequence of str or sympy.Symbol
        Names of the n coordinates q^A. Velocities ``<q>_dot`` are made for them.
    lagrangian : sympy.Expr or str
        L(q, v) in coordinates, velocities and parameters. Strings are parsed
        against the symbol table, never evaluated as Python.
    constraints : sequence of sympy.Expr or str, optional
        Velocity constraints phi_i(q, v) = 0: affine ones mu_i(q).v + h_i(q), or any
        smooth phi_i, taken with Chetaev's rule (reaction lambda^i d phi_i/d v).
    holonomic : sequence of sympy.Expr or str, optional
        Holonomic constraints g(q) = 0; no velocities allowed.
    parameters : mapping or sequence, optional
        Parameter names, or ``{name: value}`` where value is a float or
        ``None`` (symbolic; a value is needed only for numbers later).
    name : str, optional
        A human-readable name.
    drop_redundant : bool, optional
        If True, affine constraints whose one-form is a combination of the
        previous ones (and whose h is the same combination) are dropped and
        recorded in :attr:`dropped`; if False (default) they are an error.
    forces : mapping, sequence or expression, optional
        Generalized forces Q_A: ``{coordinate: expression}`` (the components of the
        1-form Q_A dq^A; coordinates not named get 0), one expression per coordinate,
        or the 1-form itself, an expression (or string) linear in the differentials
        ``d<q>`` (``"-k*x*dx + u*dy"``). Functions of the coordinates, velocities,
        parameters, the ``inputs`` and the time ``t``.
    dissipation : sympy.Expr or str, optional
        A Rayleigh dissipation function R; it adds the force -dR/dv^A.
    inputs : sequence of str or sympy.Symbol, optional
        Names of inputs u (controls): symbols the forces may use, set at run time
        (``simulate``'s control laws, ``linearize``'s B).
    speeds : mapping, optional
        The generalized speeds of the ``sympy.physics.mechanics`` model it was made from
        (:func:`~nhham.system.mechanics.from_mechanics` fills it): ``{u(t): u as an
        expression in the coordinates and velocities}``, so that a state may be given by
        them (:mod:`nhham.system.state_keys`).

    Raises
    ------
    ValidationError
        With every problem found: unknown symbols, dynamicsymbols (pointed to
        :func:`nhham.from_mechanics`), numbers that are not real, functions
        that are not smooth in the state (``Abs``, ``sign``), expressions too
        large to expand (see :mod:`nhham.system.screening`), a nonlinear
        constraint whose d phi/d v vanishes on M_1 (``NonAffineConstraintError``), holonomic constraints with velocities, m >= n, dependent
        constraint one-forms, a singular Hessian W.

    Notes
    -----
    A frozen dataclass: its fields (``dataclasses.fields(System)``, ``name`` to
    ``constraint_labels``) are what ``__init__`` makes of the raw inputs once they are
    validated and normalised; derived quantities are computed on first use and kept.
    Compared and hashed by identity (``eq=False``): systems are keys of caches. No
    field is an argument of a generated ``__init__``, so ``dataclasses.replace`` does
    not apply (it raises): build a new ``System(...)`` from changed inputs instead.

    Examples
    --------
    A particle in the plane whose velocity must satisfy y' = x x' (phi = mu.v + h):

    >>> from nhham import System
    >>> s = System(["x", "y"], "m*(x_dot**2 + y_dot**2)/2", constraints=["y_dot - x*x_dot"],
    ...            parameters={"m": 1.0}, name="particle")
    >>> s
    System('particle', n=2, m=1, holonomic=0)
    >>> s.velocities, s.phi, s.mu, s.hessian
    ((x_dot, y_dot), (-x*x_dot + y_dot,), Matrix([[-x, 1]]), Matrix([
    [m, 0],
    [0, m]]))
    >>> System(["x", "y"], "(x_dot**2 + y_dot**2)/2", constraints=["(x_dot - y_dot)**2"])
    ... # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    nhham.errors.NonAffineConstraintError: constraints[0]: d phi/d v = ... vanishes on M_1 ...
    """

    # Set once by __init__ from the validated inputs (see Notes).
    name: str = field(init=False)
    coordinates: tuple[sp.Symbol, ...] = field(init=False)
    velocities: tuple[sp.Symbol, ...] = field(init=False)
    parameters: tuple[sp.Symbol, ...] = field(init=False)
    parameter_values: Mapping[sp.Symbol, float] = field(init=False)
    lagrangian: sp.Expr = field(init=False)
    holonomic: tuple[sp.Expr, ...] = field(init=False)
    constraints: tuple[sp.Expr, ...] = field(init=False)
    dropped: tuple[DroppedConstraint, ...] = field(init=False)
    constraint_labels: tuple[str, ...] = field(init=False)
    forces: tuple[sp.Expr, ...] = field(init=False)
    dissipation: sp.Expr = field(init=False)
    inputs: tuple[sp.Symbol, ...] = field(init=False)
    speeds: Mapping = field(init=False, repr=False)

    def __init__(
        self,
        coordinates: Sequence,
        lagrangian,
        constraints: Sequence = (),
        holonomic: Sequence = (),
        parameters: Mapping | Sequence = (),
        name: str = "",
        drop_redundant: bool = False,
        forces: Mapping | Sequence | None = None,
        dissipation=None,
        inputs: Sequence = (),
        speeds: Mapping | None = None,
    ):
        # Long on purpose: every check appends to one list of problems, so that the
        # user sees them all at once, in the order the pieces were given.
        problems: list[str] = []
        coords = coordinate_symbols(coordinates, problems)
        if not coords and not problems:
            problems.append("coordinates: at least one coordinate is needed")
        dupes = sorted({q.name for q in coords if coords.count(q) > 1})
        if dupes:
            problems.append(f"coordinates: duplicate names {', '.join(dupes)}")
        vels = tuple(velocity_symbol(q) for q in coords)
        params, values = _normalise_parameters(parameters, problems)
        clash = sorted({p.name for p in params} & {s.name for s in coords + vels})
        if clash:
            problems.append(
                "parameters: names also used as coordinates or velocities: " + ", ".join(clash)
            )
        table = {s.name: s for s in coords + vels + params}
        ins = _input_symbols(inputs, table, problems)
        applied, diss, uses_time = _forces(forces, dissipation, coords, vels, table, ins,
                                           problems)

        before = len(problems)
        # t is the time in L and the constraints too, unless a parameter is named t
        timed = table if "t" in table else dict(table, t=TIME)
        lag = _to_expr(lagrangian, timed, "lagrangian", problems)
        cons = tuple(
            _to_expr(c, timed, f"constraints[{i}]", problems) for i, c in enumerate(constraints)
        )
        hols = tuple(
            _to_expr(g, timed, f"holonomic[{i}]", problems) for i, g in enumerate(holonomic)
        )
        problems[before:] = [_input_hint(p, ins) for p in problems[before:]]
        if problems:
            raise ValidationError(problems)
        uses_time = uses_time or (timed is not table and any(
            TIME in e.free_symbols for e in (lag,) + cons + hols))
        if uses_time or ins:
            params = params + ins + ((TIME,) if uses_time else ())
        self.__dict__["_time_appended"] = uses_time  # read by the property ``time``

        known = set(timed.values())
        for label, expr in [("lagrangian", lag)] + _labelled(cons, hols):
            # smooth in t too: nhham differentiates L and the constraints in it
            problems += expression_problems(label, expr, coords + vels + (TIME,), known)
        forced = known | set(ins) | {TIME}
        for label, expr in _force_labels(applied, coords, diss):
            problems += expression_problems(label, expr, coords + vels + ins + (TIME,), forced)
        if not problems:  # each expression a real, finite datum at the parameter values
            for label, expr in ([("lagrangian", lag)] + _labelled(cons, hols)
                                + _force_labels(applied, coords, diss)):
                wrong = value_problem(expr, values)
                if wrong:
                    problems.append(f"{label}: {wrong}; give the parameters values where it "
                                    f"is defined")
        for i, g in enumerate(hols):
            used = sorted(v.name for v in g.free_symbols & set(vels))
            if used:
                problems.append(
                    f"holonomic[{i}]: a holonomic constraint must not involve velocities; "
                    f"{g} uses {', '.join(used)} (give it as an affine constraint instead)"
                )
        problems += dissipation_problems(diss, coords, vels, values)
        if problems:
            raise ValidationError(problems)

        _set_fields(self, name=str(name), coordinates=coords, velocities=vels,
                    parameters=params, parameter_values=MappingProxyType(dict(values)),
                    lagrangian=lag, holonomic=hols, forces=applied, dissipation=diss,
                    inputs=ins, speeds=MappingProxyType(dict(speeds or {})))

        kept, dropped, mu = check_dependence(self, cons, hols, drop_redundant)
        if mu is not None and not dropped:
            # the one-forms of phi = lifts + constraints, already read; keep them
            self.__dict__["mu"] = mu
        _set_fields(self, constraints=kept, dropped=dropped,
                    constraint_labels=tuple(f"holonomic[{i}]" for i in range(len(hols)))
                    + tuple(_kept_labels(cons, dropped)))
        m, n = len(self.phi), len(coords)
        degenerate = degenerate_reactions(self, self.m1_labels[len(hols):], self.phi,
                                          self.constraint_kinds)
        if degenerate:
            raise NonAffineConstraintError(degenerate)
        if m >= n:
            raise ValidationError(
                [f"constraints: m = {m} independent velocity constraints (holonomic ones "
                 f"counted by their complete lifts) but n = {n} coordinates; nhham needs m < n"]
            )
        rank = singular_rank(self)
        if rank is not None:
            # Accepted: the Dirac-Bergmann chain answers it; the routes that need W^-1
            # refuse it through require_regular_lagrangian (its message formed then).
            self.__dict__["_singular_lagrangian"] = rank

    def __repr__(self):
        label = f"{self.name!r}, " if self.name else ""
        forced = f", inputs={len(self.inputs)}" if self.inputs else ""
        forced = (", forced" if self.has_forces else "") + forced
        return (f"System({label}n={self.n}, m={self.m}, holonomic={len(self.holonomic)}"
                f"{forced})")

    # ------------------------------------------------------------ regularity
    @property
    def regular_lagrangian(self) -> bool:
        """True when W = d2L/dv dv is invertible (generic rank n); False for a singular
        Lagrangian, which the Dirac-Bergmann chain answers (``DESIGN.md`` §2)."""
        return "_singular_lagrangian" not in self.__dict__

    def require_regular_lagrangian(self, what: str) -> None:
        """Raise :class:`~nhham.errors.SingularLagrangianError` unless L is regular.

        ``what`` (``"simulate"``) is named in the message.

        Examples
        --------
        >>> from nhham import System
        >>> s = System(["x", "y"], "x_dot**2/2 - y")
        >>> s.regular_lagrangian
        False
        >>> s.require_regular_lagrangian("simulate")   # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        nhham.errors.SingularLagrangianError: lagrangian: the Hessian W = d2L/dv dv is singular (rank 1 of 2; null direction [0, 1]); simulate needs W invertible ...
        """
        rank = self.__dict__.get("_singular_lagrangian")
        if rank is not None:
            raise SingularLagrangianError([
                f"{singular_message(self, rank)}; {what} needs W invertible (the Dirac-Bergmann "
                f"chain answers a singular Lagrangian in classify, derive, compare, simulate and "
                f"linearize)"])

    # ----------------------------------------------------------------- sizes
    @property
    def n(self) -> int:
        """Number of coordinates."""
        return len(self.coordinates)

    @property
    def m(self) -> int:
        """Number of affine constraints phi_i (complete lifts included)."""
        return len(self.phi)

    @property
    def time(self) -> sp.Symbol | None:
        """The time ``t`` when L, a constraint or a force depends on it (the last parameter
        then), else None (a parameter declared under the name t is no time)."""
        return TIME if self.__dict__.get("_time_appended") else None

    @property
    def time_slot(self) -> int | None:
        """The index of ``t`` in :attr:`parameters` (to the generated code's time slot), or
        None: the one datum "this system depends on t" (:mod:`nhham.autonomy`)."""
        return time_slot(self.parameters, self.time)

    @property
    def has_forces(self) -> bool:
        """True when a force or a dissipation function is given."""
        return any(f != 0 for f in self.forces) or self.dissipation != 0

    @cached_property
    def generalized_forces(self) -> sp.Matrix:
        """Q_A - dR/dv^A, shape (n, 1): the applied forces and the dissipation's.

        The force F = Q_A dq^A is semibasic; its vertical lift F^v = W^{AB} Q_B d/dv^B
        (i_{F^v} omega_L = -F, ``DESIGN.md`` §2) is added to xi_L.
        """
        R = self.dissipation
        return sp.Matrix([f - (sp.diff(R, v) if R != 0 else 0)
                          for f, v in zip(self.forces, self.velocities)])

    @property
    def declared_parameters(self) -> tuple[sp.Symbol, ...]:
        """The parameters as declared: :attr:`parameters` without the inputs and ``t``."""
        extra = set(self.inputs) | {TIME}
        return tuple(p for p in self.parameters if p not in extra)

    def closed_loop(self, laws: Mapping) -> "System":
        """The system with inputs replaced by control laws (feedback or open loop).

        Parameters
        ----------
        laws : mapping
            ``{input: expression}`` in ``t``, the coordinates, velocities and
            parameters (strings go through the safe parser). Inputs not named stay
            inputs.

        Returns
        -------
        System
            The same Lagrangian and constraints, the forces with the laws substituted
            (compiled with the field by the numeric layer).

        Raises
        ------
        ValidationError
            A key that is not an input, or a law using an unknown name or an input.
        """
        problems: list[str] = []
        by_name = {u.name: u for u in self.inputs}
        table = {s.name: s for s in self.state + self.declared_parameters}
        table["t"] = TIME
        subs = _keyed(laws, by_name, "control", f"not an input of the system (inputs: "
                      f"{', '.join(by_name) or 'none'})", table, problems)
        if problems:
            raise ValidationError(problems)
        known = set(table.values())
        for u, law in subs.items():
            problems += expression_problems(f"control.{u.name}", law, self.state + (TIME,),
                                            known)
        if problems:
            raise ValidationError(problems)
        return System(self.coordinates, self.lagrangian,
                      constraints=self.constraints, holonomic=self.holonomic,
                      parameters={p: self.parameter_values.get(p)
                                  for p in self.declared_parameters},
                      name=self.name,
                      forces=[f.xreplace(subs) for f in self.forces],
                      dissipation=self.dissipation.xreplace(subs),
                      inputs=[u for u in self.inputs if u not in subs])

    @property
    def state(self) -> tuple[sp.Symbol, ...]:
        """Coordinates on TQ in order (q^1..q^n, v^1..v^n)."""
        return self.coordinates + self.velocities

    @cached_property
    def exact_parameter_values(self) -> Mapping[sp.Symbol, sp.Rational]:
        """The parameter values as the exact decimals they were written as (``0.1`` is
        1/10): the values every exact decision at the values uses."""
        return MappingProxyType({p: sp.Rational(str(v)) for p, v in
                                 self.parameter_values.items()})

    # ----------------------------------------------------- constraint pieces
    @cached_property
    def complete_lifts(self) -> tuple[sp.Expr, ...]:
        """g^c = (dg/dq^A) v^A (+ dg/dt when g depends on the time) for every holonomic
        constraint g: d/dt g along a motion, an affine constraint (``DESIGN.md`` §2)."""
        t = self.time
        return tuple(
            sum((sp.diff(g, q) * v for q, v in zip(self.coordinates, self.velocities)),
                sp.diff(g, t) if t is not None else sp.S.Zero)
            for g in self.holonomic
        )

    @cached_property
    def time_dependent(self) -> tuple[bool, ...]:
        """Whether each constraint of :attr:`m1_labels` (the g, then the rows of phi)
        depends explicitly on the time t."""
        t = self.time
        return tuple(t is not None and t in sp.sympify(e).free_symbols
                     for e in self.holonomic + self.phi)

    @property
    def lagrangian_depends_on_time(self) -> bool:
        """True when L depends explicitly on the time t (dE_L/dt then gains -dL/dt)."""
        return self.time is not None and self.time in self.lagrangian.free_symbols

    @cached_property
    def phi(self) -> tuple[sp.Expr, ...]:
        """All affine constraints phi_i: complete lifts first, then the user's."""
        return self.complete_lifts + self.constraints

    @property
    def m1_labels(self) -> tuple[str, ...]:
        """Labels of the constraints defining M_1 = {g = 0, phi = 0}, in that order:
        ``holonomic[i]``, then the rows of phi (lifts ``holonomic[i].lift`` first)."""
        nh = len(self.holonomic)
        return tuple(f"holonomic[{i}]" for i in range(nh)) + tuple(
            f"{lab}.lift" if k < nh else lab for k, lab in enumerate(self.constraint_labels))

    @cached_property
    def mu(self) -> sp.Matrix:
        """The m x n matrix mu_iA = d phi_i / d v^A: one-form coefficients mu_iA(q) for affine
        constraints, functions of q and v for nonlinear (Chetaev) ones."""
        return one_forms(self.phi, self.velocities) if self.phi else sp.zeros(0, self.n)

    @cached_property
    def constraint_kinds(self) -> tuple[str, ...]:
        """The kind of every row of :attr:`phi`: ``"affine"``, or ``"nonlinear (Chetaev)"``
        for a constraint not affine in v (its reaction lambda d phi/d v, ``DESIGN.md`` §2).

        Examples
        --------
        >>> from nhham import System
        >>> System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2",
        ...        constraints=["z_dot - y*x_dot", "x_dot**2 + y_dot**2 - 1"]).constraint_kinds
        ('affine', 'nonlinear (Chetaev)')
        """
        # complete lifts are affine by construction (and may be long: not read again)
        return (AFFINE,) * len(self.complete_lifts) + tuple(
            constraint_kind(f, self.velocities) for f in self.constraints)

    @property
    def is_affine(self) -> bool:
        """True when every velocity constraint is affine in v (mu depends on q only)."""
        return all(k == AFFINE for k in self.constraint_kinds)

    @cached_property
    def h(self) -> sp.Matrix:
        """The m-vector h_i(q) = phi_i at v = 0."""
        rows = [velocity_free_part(f, self.velocities) for f in self.phi]
        return sp.Matrix(rows) if rows else sp.zeros(0, 1)

    @cached_property
    def h_vanishes(self) -> tuple[bool, ...]:
        """Whether each h_i vanishes identically (simplified to 0)."""
        return tuple(sp.simplify(x) == 0 for x in self.h)

    @property
    def is_linear(self) -> bool:
        """True when every h_i vanishes (constraints linear in v)."""
        return all(self.h_vanishes)

    @cached_property
    def quadratic_parts(self) -> QuadraticParts | None:
        """W, b, V with L = v^T W v / 2 + b . v - V, or None.

        None when L is not (structurally) a polynomial of degree <= 2 in the
        velocities; see :func:`quadratic_parts`.
        """
        return quadratic_parts(self.lagrangian, self.velocities)

    @cached_property
    def hessian(self) -> sp.Matrix:
        """W_AB = d2L / dv^A dv^B (n x n).

        Read from the terms of L when L is quadratic in the velocities (no
        differentiation of L); otherwise ``sympy.hessian``.
        """
        parts = self.quadratic_parts
        if parts is not None:
            return sp.Matrix(parts.W)
        return sp.hessian(self.lagrangian, self.velocities)

    def numeric_parameters(self, required=None) -> dict[sp.Symbol, float]:
        """Parameter values as ``{symbol: float}``.

        Parameters
        ----------
        required : iterable of sympy.Symbol, optional
            Parameters that must have a value; default all.

        Raises
        ------
        MissingParameterValueError
            Naming every required parameter without a value.
        """
        from nhham.errors import MissingParameterValueError

        need = self.parameters if required is None else tuple(required)
        missing = [p.name for p in need if p not in self.parameter_values]
        if missing:
            raise MissingParameterValueError(
                f"parameters: no numeric value for {', '.join(missing)} (needed for numbers)"
            )
        return dict(self.parameter_values)


# ---------------------------------------------------------------- helpers
def _set_fields(system, **values):
    """Set fields of a :class:`System` under construction: a frozen dataclass refuses
    assignment, so its own ``__init__`` goes through ``object.__setattr__``."""
    for key, value in values.items():
        object.__setattr__(system, key, value)


def _input_symbols(inputs, table, problems) -> tuple:
    """The inputs as plain symbols; names must be new (not state, parameter or ``t``)."""
    if isinstance(inputs, (str, sp.Basic)):
        inputs = [inputs]
    out: list = []
    for i, u in enumerate(inputs):
        try:
            sym = as_symbol(u)
        except TypeError as exc:
            problems.append(f"inputs[{i}]: {exc}")
            continue
        if sym.name in table or sym == TIME or sym in out:
            what = ("the time" if sym == TIME else "a coordinate, velocity or parameter"
                    if sym.name in table else "another input")
            problems.append(f"inputs[{i}]: {sym.name!r} is already {what}")
            continue
        out.append(sym)
    return tuple(out)


def _forces(forces, dissipation, coords, vels, table, inputs, problems):
    """(Q_A per coordinate, R, whether t appears), parsed against the state, the
    parameters, the inputs and the time."""
    n = len(coords)
    given = forces is not None and (len(forces) if hasattr(forces, "__len__") else True)
    if not given and dissipation is None:
        return (sp.S.Zero,) * n, sp.S.Zero, False
    if "t" in table:
        where = "forces" if given else "dissipation"
        problems.append(f"{where}: the name t is the time in {where}; rename the "
                        f"{'coordinate' if sp.Symbol('t') in coords else 'parameter'} t")
        return (sp.S.Zero,) * n, sp.S.Zero, False
    full = dict(table, t=TIME, **{u.name: u for u in inputs})
    out = [sp.S.Zero] * n
    if isinstance(forces, (str, sp.Expr)):
        out = _one_form(forces, coords, full, problems)
    elif forces is not None and not hasattr(forces, "__iter__"):
        problems.append(f"forces: expected a table by coordinate, one expression per "
                        f"coordinate or a 1-form in the differentials (e.g. '-k*x*dx'), got "
                        f"{type(forces).__name__} {forces!r}")
    elif isinstance(forces, Mapping):
        index = {q.name: i for i, q in enumerate(coords)}
        for i, f in _keyed(forces, index, "forces", f"not a coordinate (forces are given by "
                           f"coordinate: {', '.join(index)})", full, problems).items():
            out[i] = f
    elif forces is not None:
        items = list(forces)
        if len(items) != n:
            problems.append(f"forces: {len(items)} expressions for {n} coordinates (give one "
                            f"per coordinate, or a table by coordinate)")
        else:
            out = [_to_expr(f, full, f"forces.{q.name}", problems)
                   for f, q in zip(items, coords)]
    R = sp.S.Zero if dissipation is None else _to_expr(dissipation, full, "dissipation",
                                                       problems)
    uses_time = any(TIME in e.free_symbols for e in out + [R])
    return tuple(out), R, uses_time


def differential_symbols(coords) -> dict:
    """``{"d<q>": Symbol}``: the differentials dq^A in which a force may be written as the
    1-form Q_A dq^A."""
    return {f"d{q.name}": sp.Symbol(f"d{q.name}") for q in coords}


def _one_form(form, coords, table, problems) -> list:
    """The components Q_A of a 1-form Q_A dq^A given as an expression in the differentials
    d<q> (a string or a sympy expression)."""
    n = len(coords)
    ds = differential_symbols(coords)
    clash = sorted(d for d in ds if d in table)
    if clash:
        problems.append(f"forces: {', '.join(clash)} is a name of the system, not only a "
                        f"differential; give the forces by coordinate instead")
        return [sp.S.Zero] * n
    expr = _to_expr(form, dict(table, **ds), "forces", problems)
    dsyms = list(ds.values())
    Q = [sp.diff(expr, d) for d in dsyms]
    rest = sp.expand(expr - sum(q * d for q, d in zip(Q, dsyms)))
    if rest != 0 or any(q.has(*dsyms) for q in Q):
        problems.append(f"forces: a 1-form is linear in the differentials "
                        f"{', '.join(ds)} (Q_A dq^A, e.g. '-k*x*dx'); got {expr}")
        return [sp.S.Zero] * n
    return Q


def _input_hint(problem: str, inputs) -> str:
    """A problem about an unknown name that is an input, with what inputs are for."""
    if any(f"unknown name '{u.name}'" in problem for u in inputs):
        return (problem + " (an input may appear in the forces and the dissipation only, "
                "not in L or the constraints)")
    return problem


def _keyed(entries: Mapping, allowed: Mapping, section: str, refusal: str, table,
           problems) -> dict:
    """``{allowed[name]: expression}`` of a table keyed by names (or Symbols); a key not in
    ``allowed`` is the problem ``<section>.<name>: <refusal>``."""
    out = {}
    for key, value in entries.items():
        name = key.name if isinstance(key, sp.Symbol) else str(key)
        if name not in allowed:
            problems.append(f"{section}.{name}: {refusal}")
            continue
        out[allowed[name]] = _to_expr(value, table, f"{section}.{name}", problems)
    return out


def _force_labels(forces, coords, dissipation):
    out = [(f"forces.{q.name}", f) for q, f in zip(coords, forces) if f != 0]
    return out + ([("dissipation", dissipation)] if dissipation != 0 else [])


def _labelled(cons, hols):
    return [(f"constraints[{i}]", c) for i, c in enumerate(cons)] + [
        (f"holonomic[{i}]", g) for i, g in enumerate(hols)
    ]


def _kept_labels(cons, dropped):
    gone = {d.label for d in dropped}
    return [f"constraints[{i}]" for i in range(len(cons)) if f"constraints[{i}]" not in gone]


def _normalise_parameters(parameters, problems):
    params, values = [], {}
    items = parameters.items() if isinstance(parameters, Mapping) else [(p, None) for p in parameters]
    for key, value in items:
        try:
            # A user's Symbol keeps its assumptions (positive=True lets sympy simplify
            # sqrt(m**2) to m); names become plain symbols.
            sym = key if isinstance(key, sp.Symbol) else as_symbol(key)
        except TypeError as exc:
            problems.append(f"parameters: {exc}")
            continue
        if sym in params:
            problems.append(f"parameters: duplicate parameter {sym.name}")
            continue
        params.append(sym)
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
            problems.append(f"parameters.{sym.name}: value must be a real number, got {value!r}")
        elif not np.isfinite(float(value)):
            problems.append(f"parameters.{sym.name}: value must be finite, got {value!r}")
        else:
            values[sym] = float(value)
    return tuple(params), values


def _to_expr(value, table, label, problems):
    """Turn user input into a sympy expression; strings go through the safe parser."""
    if isinstance(value, str):
        from nhham.errors import ParseError
        from nhham.system.expressions import parse_expression

        try:
            return parse_expression(value, table, where=label)
        except ParseError as exc:
            problems.append(str(exc))
            return sp.S.Zero
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return sp.sympify(value)
    if isinstance(value, sp.Basic) and isinstance(value, sp.Expr):
        # Symbols from elsewhere may carry assumptions; map them by name.
        subs = {s: table[s.name] for s in value.free_symbols
                if isinstance(s, sp.Symbol) and s.name in table and s != table[s.name]}
        return value.xreplace(subs) if subs else value
    problems.append(f"{label}: expected an expression, got {type(value).__name__} {value!r}")
    return sp.S.Zero

