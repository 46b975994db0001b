"""The system description: coordinates, Lagrangian, constraints, forces, parameters.

A :class:`System` is frozen and validated on construction. Every problem found
is collected and raised once as a :class:`~nhham.errors.ValidationError`
subclass whose message names the offending key (``lagrangian``,
``constraints[1]``, ``holonomic[0]``, ``parameters``) or expression.

Conventions (``DESIGN.md`` §2): coordinates q^A (A = 1..n) with velocities
``<q>_dot``; affine constraints phi_i = mu_iA(q) v^A + h_i(q); a holonomic
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

from nhham.errors import (
    BudgetExceeded,
    NonAffineConstraintError,
    RedundantConstraintError,
    SingularLagrangianError,
    ValidationError,
)
from nhham.autonomy import time_slot
from nhham.settings import PARAMETER_BOX, STATE_BOX
from nhham.system.force_checks import dissipation_problems
from nhham.system.naming import TIME, as_symbol, velocity_symbol
from nhham.system.rank import float_rank, precise_ranks
from nhham.system.screening import coordinate_symbols, expression_problems
from nhham.system.velocities import QuadraticParts, non_affine_terms, one_forms, quadratic_parts

__all__ = ["System", "DroppedConstraint"]

# Random points used for generic-rank decisions are drawn from this seed so
# that validation is reproducible run to run.
_VALIDATION_SEED = 20261121
_VALIDATION_SAMPLES = 4


@dataclass(frozen=True)
class DroppedConstraint:
    """A constraint removed because its one-form is a combination of others.

    Attributes
    ----------
    label : str
        Key path of the dropped constraint (``constraints[2]``).
    expression : sympy.Expr
        The dropped phi.
    combination : dict
        ``{label: coefficient}`` with phi_dropped = sum coefficient * phi_label
        (coefficients are functions of q).
    """

    label: str
    expression: sp.Expr
    combination: Mapping[str, sp.Expr]


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
        Affine constraints phi_i = mu_i(q).v + h_i(q) (each = 0).
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

    Raises
    ------
    ValidationError
        With every problem found: unknown symbols, dynamicsymbols (pointed to
        :func:`nhham.from_mechanics`), numbers that are not real, functions
        that are not smooth in the state (``Abs``, ``sign``), expressions too
        large to expand (see :mod:`nhham.system.screening`), non-affine
        constraints, holonomic constraints with velocities, m >= n, dependent
        constraint one-forms, a singular Hessian W.

    Notes
    -----
    A frozen dataclass: its fields (``dataclasses.fields(System)``, ``name`` to
    ``constraint_labels``) are what ``__init__`` makes of the raw inputs once they are
    validated and normalised; derived quantities are computed on first use and kept.
    Compared and hashed by identity (``eq=False``): systems are keys of caches. No
    field is an argument of a generated ``__init__``, so ``dataclasses.replace`` does
    not apply (it raises): build a new ``System(...)`` from changed inputs instead.
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
        if uses_time or ins:
            params = params + ins + ((TIME,) if uses_time else ())

        before = len(problems)
        lag = _to_expr(lagrangian, table, "lagrangian", problems)
        cons = tuple(
            _to_expr(c, table, f"constraints[{i}]", problems) for i, c in enumerate(constraints)
        )
        hols = tuple(
            _to_expr(g, table, f"holonomic[{i}]", problems) for i, g in enumerate(holonomic)
        )
        problems[before:] = [_input_hint(p, ins) for p in problems[before:]]
        if problems:
            raise ValidationError(problems)

        known = set(table.values())
        for label, expr in [("lagrangian", lag)] + _labelled(cons, hols):
            problems += expression_problems(label, expr, coords + vels, known)
        forced = known | set(ins) | {TIME}
        for label, expr in _force_labels(applied, coords, diss):
            problems += expression_problems(label, expr, coords + vels + ins + (TIME,), forced)
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

        nonaffine = []
        for i, c in enumerate(cons):
            bad = non_affine_terms(c, vels)
            if bad:
                nonaffine.append(
                    f"constraints[{i}]: {c} is not affine in the velocities "
                    f"(offending term {bad[0]}); nonlinear (Chetaev-type) constraints are "
                    f"outside nhham's scope"
                )
        if nonaffine:
            raise NonAffineConstraintError(nonaffine)

        _set_fields(self, name=str(name), coordinates=coords, velocities=vels,
                    parameters=params, parameter_values=MappingProxyType(dict(values)),
                    lagrangian=lag, holonomic=hols, forces=applied, dissipation=diss,
                    inputs=ins)

        kept, dropped, mu = _check_dependence(self, cons, hols, drop_redundant)
        if mu is not None and not dropped:
            # the one-forms of phi = lifts + constraints, already read; keep them
            self.__dict__["mu"] = mu
        _set_fields(self, constraints=kept, dropped=dropped,
                    constraint_labels=tuple(f"holonomic[{i}]" for i in range(len(hols)))
                    + tuple(_kept_labels(cons, dropped)))
        m, n = len(self.phi), len(coords)
        if m >= n:
            raise ValidationError(
                [f"constraints: m = {m} independent velocity constraints (holonomic ones "
                 f"counted by their complete lifts) but n = {n} coordinates; nhham needs m < n"]
            )
        _check_regular_lagrangian(self)

    def __repr__(self):
        label = f"{self.name!r}, " if self.name else ""
        forced = f", inputs={len(self.inputs)}" if self.inputs else ""
        forced = (", forced" if self.has_forces else "") + forced
        return (f"System({label}n={self.n}, m={self.m}, holonomic={len(self.holonomic)}"
                f"{forced})")

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
        """The time ``t`` when the forces depend on it (a parameter then), else None."""
        return TIME if TIME in self.parameters[len(self.parameters) - 1:] else None

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
        """g^c = (dg/dq^A) v^A for every holonomic constraint g."""
        return tuple(
            sum((sp.diff(g, q) * v for q, v in zip(self.coordinates, self.velocities)), sp.S.Zero)
            for g in self.holonomic
        )

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
        """The m x n matrix of one-form coefficients mu_iA(q) = d phi_i / d v^A."""
        return one_forms(self.phi, self.velocities) if self.phi else sp.zeros(0, self.n)

    @cached_property
    def h(self) -> sp.Matrix:
        """The m-vector h_i(q) = phi_i at v = 0."""
        zero = {v: 0 for v in self.velocities}
        return sp.Matrix([f.subs(zero) for f in self.phi]) if self.phi else sp.zeros(0, 1)

    @cached_property
    def is_linear(self) -> bool:
        """True when every h_i vanishes (constraints linear in v)."""
        return all(sp.simplify(x) == 0 for x in self.h)

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


# ----------------------------------------------------- numeric sample values
class _NoFastEvaluation(Exception):
    """The fast evaluator met something it does not handle; use sympy's evalf."""


_NUMPY_FUNCTIONS = {
    sp.sin: np.sin, sp.cos: np.cos, sp.tan: np.tan, sp.exp: np.exp, sp.log: np.log,
    sp.sinh: np.sinh, sp.cosh: np.cosh, sp.tanh: np.tanh,
    sp.asin: np.arcsin, sp.acos: np.arccos, sp.atan: np.arctan,
    sp.cot: lambda z: 1 / np.tan(z), sp.sec: lambda z: 1 / np.cos(z),
    sp.csc: lambda z: 1 / np.sin(z),
}


def _evaluate_at(exprs, points):
    """Values of ``exprs`` at all ``points`` at once, shape (len(exprs), len(points)).

    Complex float64 arithmetic over one walk of the expression trees (shared
    subexpressions evaluated once). Raises :class:`_NoFastEvaluation` for any
    node it does not know and for non-finite values, so that the caller falls
    back to ``xreplace(...).evalf()`` and keeps its exact behaviour there.
    """
    symbols = set().union(*(p.keys() for p in points)) if points else set()
    env = {s: np.array([complex(p[s]) for p in points]) for s in symbols}
    memo: dict = {}

    def ev(e):
        hit = memo.get(e)
        if hit is not None:
            return hit
        if e.is_Symbol:
            if e not in env:
                raise _NoFastEvaluation
            val = env[e]
        elif e.is_Atom:
            if not e.is_number:
                raise _NoFastEvaluation
            try:
                val = np.complex128(complex(e))
            except (TypeError, ValueError, OverflowError):
                raise _NoFastEvaluation from None
        elif e.is_Add:
            val = ev(e.args[0])
            for a in e.args[1:]:
                val = val + ev(a)
        elif e.is_Mul:
            val = ev(e.args[0])
            for a in e.args[1:]:
                val = val * ev(a)
        elif e.is_Pow:
            base, exp = ev(e.base), e.exp
            if exp.is_Integer and abs(int(exp)) <= 64:
                k = int(exp)
                val = base ** k if k >= 0 else 1 / base ** (-k)
            else:
                val = base ** ev(exp)
        elif e.func in _NUMPY_FUNCTIONS and len(e.args) == 1:
            val = _NUMPY_FUNCTIONS[e.func](ev(e.args[0]))
        else:
            raise _NoFastEvaluation
        memo[e] = val
        return val

    try:
        with np.errstate(all="ignore"):
            out = np.array([np.broadcast_to(ev(sp.sympify(e)), (len(points),)) for e in exprs],
                           dtype=complex).reshape(len(exprs), len(points))
    except (ArithmeticError, TypeError, ValueError):
        raise _NoFastEvaluation from None
    if not np.all(np.isfinite(out)):
        raise _NoFastEvaluation
    return out


def _numeric_samples(matrix, points, label="lagrangian"):
    """``[_numeric(matrix, p, label) for p in points]``, by one fast numeric pass.

    Falls back to :func:`_numeric` (sympy evalf, with its error messages)
    whenever the fast pass cannot give finite values.
    """
    rows, cols = matrix.shape
    if rows * cols and points:
        try:
            values = _evaluate_at(list(matrix), points).real
        except _NoFastEvaluation:
            pass
        else:
            return [values[:, k].reshape(rows, cols).astype(float) for k in range(len(points))]
    return [_numeric(matrix, p, label) for p in points]


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


def _sample_q(system, rng, count):
    """Random numeric substitutions for coordinates and parameters."""
    points = []
    for _ in range(count):
        sub = {q: rng.uniform(*STATE_BOX) for q in system.coordinates}
        sub.update({v: rng.uniform(*STATE_BOX) for v in system.velocities})
        for p in system.parameters:
            sub[p] = system.parameter_values.get(p, rng.uniform(*PARAMETER_BOX))
        points.append(sub)
    return points


def _numeric(matrix, sub, label="lagrangian"):
    """Evaluate a symbolic matrix at a sample point; non-numeric results are input errors."""
    try:
        return np.array(matrix.xreplace(sub).evalf(), dtype=complex).real.astype(float)
    except (TypeError, ValueError) as exc:
        raise ValidationError([
            f"{label}: cannot evaluate second derivatives at a sample point "
            f"({' '.join(str(exc).split())}); the "
            f"Lagrangian must be smooth in the velocities (no Abs, sign or other kinks)"
        ]) from None


def _check_dependence(system, cons, hols, drop_redundant):
    """Find affine constraints whose mu row is a combination of earlier rows.

    The generic rank over functions of q is decided at seeded random points
    (a row is dependent when it is dependent at every sample); the exact
    combination is then solved symbolically to name it.

    Returns (kept constraints, dropped, mu of lifts + constraints or None
    when a row was dropped or there are none).
    """
    rows = list(system.complete_lifts) + list(cons)  # holonomic is set before this runs
    labels = [f"holonomic[{i}]" for i in range(len(hols))] + [
        f"constraints[{i}]" for i in range(len(cons))
    ]
    if not rows:
        return tuple(cons), (), None
    vels = system.velocities
    mu = one_forms(rows, vels)
    rng = np.random.default_rng(_VALIDATION_SEED)
    points = _sample_q(system, rng, _VALIDATION_SAMPLES)
    samples = _numeric_samples(mu, points)
    independent: list[int] = []
    dependent: list[tuple[int, dict]] = []
    for i in range(len(rows)):
        trial = independent + [i]
        full = len(trial)
        # A float64 deficiency may come from the units: confirm it in high precision.
        if (max(float_rank(S[trial]) for S in samples) == full
                or precise_ranks(mu, points, [trial])[0] == full):
            independent.append(i)
            continue
        dependent.append((i, _combination(mu, rows, independent, i, vels)))
    if not dependent:
        return tuple(cons), (), mu
    problems, dropped = [], []
    points = _sample_q(system, np.random.default_rng(_VALIDATION_SEED + 2), _VALIDATION_SAMPLES)
    for i, coeffs in dependent:
        combo = " + ".join(f"({c})*{labels[j]}" for j, c in coeffs.items()) or "0"
        # Redundant only if h is the same combination; otherwise phi_i minus
        # the combination is a function of q alone: a hidden position constraint.
        rest = sp.expand(rows[i] - sum((c * rows[j] for j, c in coeffs.items()), sp.S.Zero))
        position_part = rest.xreplace({v: 0 for v in vels})
        if not _vanishes_at(position_part, points):
            problems.append(
                f"{labels[i]}: its one-form is {combo} but the affine parts differ: together "
                f"they imply the position constraint {sp.trigsimp(position_part)} = 0; give "
                f"that as a holonomic constraint instead"
            )
        elif labels[i].startswith("holonomic"):  # drop_redundant drops velocity constraints
            problems.append(
                f"{labels[i]}: the complete lift {rows[i]} is a combination of the others: "
                f"{labels[i]} = {combo}; the constraint is redundant: remove it from holonomic"
            )
        elif not drop_redundant:
            problems.append(
                f"{labels[i]}: {rows[i]} is redundant, a combination of the others: "
                f"{labels[i]} = {combo} ({RedundantConstraintError.ADVICE})"
            )
        else:
            dropped.append(DroppedConstraint(labels[i], rows[i],
                                             MappingProxyType({labels[j]: c for j, c in coeffs.items()})))
    if problems:
        raise RedundantConstraintError(problems)
    gone = {d.label for d in dropped}
    kept = tuple(c for k, c in enumerate(cons) if f"constraints[{k}]" not in gone)
    return kept, tuple(dropped), None


def _combination(mu, rows, independent, i, vels):
    """Coefficients c_j(q) with mu_i = sum_j c_j mu_j over the independent rows.

    Solves the square subsystem on the k velocity columns where the rows are
    best conditioned at a sample point (an overdetermined symbolic solve
    would miss trigonometric identities), then tidies each coefficient.
    """
    if not independent:
        return {}
    A = mu.extract(independent, list(range(mu.cols)))  # k x n
    rng = np.random.default_rng(_VALIDATION_SEED + 3)
    sample = {s: rng.uniform(*STATE_BOX) for s in A.free_symbols}
    An = np.array(A.xreplace(sample).evalf(), dtype=float)
    import scipy.linalg

    cols = sorted(scipy.linalg.qr(An, pivoting=True)[2][: len(independent)])
    block = A.extract(list(range(len(independent))), cols)  # k x k, invertible
    target = mu.extract([i], cols)
    coeffs = block.T.LUsolve(target.T)
    out = {}
    for j, c in zip(independent, coeffs):
        c = sp.trigsimp(sp.cancel(c))
        if c != 0:
            out[j] = c
    return out


def _vanishes_at(expr, points, tol=1e-9):
    """True when ``expr`` is numerically zero at every sample point."""
    for pt in points:
        value = complex(sp.sympify(sp.sympify(expr).xreplace(pt)).evalf())
        if abs(value) > tol * max(1.0, abs(value)):
            return False
    return True


def _check_regular_lagrangian(system):
    """Raise unless the Lagrangian is regular: W = d2L/dv dv invertible (generic rank n;
    singular at every sampled point raises). Not C's regularity on M_1, which is a
    verdict (``LagrangianGeometry.regular``), never an input error."""
    W = system.hessian
    n = system.n
    if not W.free_symbols:
        rank = W.rank()
        if rank < n:
            W = sp.hessian(system.lagrangian, system.velocities)  # as the message always showed it
            raise SingularLagrangianError([_singular_message(W, rank, W.nullspace())])
        return
    rng = np.random.default_rng(_VALIDATION_SEED + 1)
    points = _sample_q(system, rng, _VALIDATION_SAMPLES)
    ranks = [float_rank(S) for S in _numeric_samples(W, points)]
    if max(ranks) < n:
        # A float64 deficiency may come from the units (m = 1e-16): confirm it.
        ranks = precise_ranks(W, points, [list(range(n))])
    if max(ranks) < n:
        W = sp.hessian(system.lagrangian, system.velocities)  # as the message always showed it
        try:
            null = W.nullspace(simplify=True)
        except BudgetExceeded:
            raise
        except Exception:  # pragma: no cover - sympy failure; message still useful
            null = []
        raise SingularLagrangianError([_singular_message(W, max(ranks), null)])


def _singular_message(W, rank, null):
    direction = f"; null direction {list(null[0])}" if null else ""
    return (
        f"lagrangian: the Hessian W = d2L/dv dv is singular (rank {rank} of {W.rows}"
        f"{direction}); singular Lagrangians are outside the paper's scope"
    )
