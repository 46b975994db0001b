"""The verdicts of a classification: at one parameter case, for every case, at values.

The classify command's answer is a :class:`Verdict` (the keys of ``nhham classify``);
:func:`nhham.verdict.parametric.parametric_classification` gives one for generic
parameters and one for every :class:`Case` where it changes (a
:class:`ParametricVerdict`); :func:`nhham.verdict.values.classification_at_values`
gives the one that holds at the scene's values (a :class:`ValuesVerdict`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import sympy as sp

from nhham.system.expressions import short

__all__ = ["Verdict", "Case", "ParametricVerdict", "SearchReport", "ValuesVerdict",
           "exact_value", "NEAR", "MAX_DEPTH"]

# Default relative distance below which parameter values count as "near" an exceptional set.
NEAR = 1e-8
# Default bound on the depth of the recursion over cases.
MAX_DEPTH = 3


@dataclass(frozen=True)
class Verdict:
    """The classification at one parameter case (the keys of ``nhham classify``).

    Attributes
    ----------
    status : {"determined", "underdetermined", "inconsistent", "invalid"}
        ``"invalid"`` where nhham does not apply (the Lagrangian is singular, the
        system description fails validation, or a secondary constraint depends on an
        input); ``note`` says why.
    regular : bool or None
        C regular on M_1.
    rank_C : int or None
        rank C on M_1.
    stages : int
        Number of stages of the constraint algorithm.
    free_multipliers : int
    integrable : bool or None
        Frobenius integrability of the constraint distribution.
    first_class, second_class : int or None
        Counts of the final constraints on T*Q (None when inconsistent or not decided).
    redundant : tuple of str
        Labels of the constraints dropped as redundant.
    final_constraints : int
        Number of constraints defining M_f.
    dimension : int or None
        dim M_f.
    note : str or None
        Why the case is ``"invalid"``.
    system, analysis, classes
        The system the verdict was computed on (the case's condition substituted), its
        :class:`~nhham.lagrangian.analysis.ConstraintAnalysis` and, when a ``classes``
        function was given, its first/second-class result (not compared).

    Examples
    --------
    >>> from nhham import classification_at_values, models
    >>> verdict = classification_at_values(models.rolling_disk()).verdict
    >>> verdict.status, verdict.rank_C, verdict.integrable, verdict.first_class
    ('determined', 2, False, 2)
    """

    status: str
    regular: bool | None
    rank_C: int | None
    stages: int
    free_multipliers: int
    integrable: bool | None
    first_class: int | None
    second_class: int | None
    redundant: tuple = ()
    final_constraints: int = 0
    dimension: int | None = None
    note: str | None = None
    system: object = field(default=None, compare=False, repr=False)
    analysis: object = field(default=None, compare=False, repr=False)
    classes: object = field(default=None, compare=False, repr=False)

    FIELDS = ("status", "regular", "rank_C", "stages", "free_multipliers", "integrable",
              "first_class", "second_class", "redundant", "final_constraints", "dimension")

    def differences(self, other: "Verdict") -> tuple:
        """Names of the fields in which this verdict differs from ``other``."""
        return tuple(f for f in self.FIELDS if getattr(self, f) != getattr(other, f))

    def describe(self) -> str:
        """One line: the verdict's fields."""
        if self.status == "invalid":
            return f"invalid: {self.note}"
        yn = {True: "yes", False: "no", None: "undecided"}
        integrable = yn[self.integrable]
        if self.integrable is None and not getattr(self.system, "is_affine", True):
            integrable = "not applicable (nonlinear constraints)"
        text = (f"C regular {yn[self.regular]} (rank {self.rank_C}), {self.status}, "
                f"{self.stages} stage(s), {self.free_multipliers} free multiplier(s), "
                f"integrable {integrable}")
        if self.first_class is not None:
            text += f", {self.first_class} first class, {self.second_class} second class"
        if self.redundant:
            text += f", redundant {', '.join(self.redundant)}"
        return text

    def to_dict(self) -> dict:
        """The verdict's fields as JSON-ready data."""
        # Counts get their own names: "stages" and "final_constraints" are lists in
        # classify's JSON (one type per key across the output).
        rename = {"rank_C": "rank_c", "stages": "stage_count",
                  "final_constraints": "final_constraint_count"}
        out = {rename.get(f, f): getattr(self, f) for f in self.FIELDS}
        out["redundant"] = list(self.redundant)
        out["note"] = self.note
        return out


@dataclass(frozen=True)
class Case:
    """A set of parameter values with its own verdict.

    Attributes
    ----------
    conditions : tuple of sympy.Expr
        Equations (each = 0) in the parameters, factored.
    excluding : tuple of sympy.Expr
        Inequations (each != 0) that exclude the cases listed before this one. A
        sum of squares stands for "not all of these vanish".
    verdict : Verdict
    substitution : Mapping
        Parameter -> expression: how the case's system was obtained.
    reasons : tuple of str
        The generic decisions that fail on this set.
    """

    conditions: tuple
    excluding: tuple
    verdict: Verdict
    substitution: Mapping = field(default_factory=dict, compare=False)
    reasons: tuple = ()

    def holds_at(self, values: Mapping) -> bool | None:
        """Whether parameter values satisfy the conditions and inequations.

        ``values`` maps parameters (symbols or names) to numbers, read exactly (floats as
        their decimal text). None when a condition involves a parameter without a value.
        """
        values = {(k if isinstance(k, sp.Symbol) else sp.Symbol(str(k))): v
                  for k, v in values.items()}
        exprs = tuple(self.conditions) + tuple(self.excluding)
        if any(s not in values for e in exprs for s in sp.sympify(e).free_symbols):
            return None
        at = {p: exact_value(v) for p, v in values.items()}
        return (all(sp.sympify(e).xreplace(at) == 0 for e in self.conditions)
                and all(sp.sympify(e).xreplace(at) != 0 for e in self.excluding))

    def describe(self) -> str:
        text = " and ".join(f"{short(e)} = 0" for e in self.conditions)
        if self.excluding:
            text += " (excluding " + ", ".join(f"{short(e)} = 0" for e in self.excluding) + ")"
        return text


@dataclass(frozen=True)
class SearchReport:
    """How the search for the exceptional cases went (after the generic verdict).

    Attributes
    ----------
    complete : bool
        Every exceptional set found was followed (within the depth bound).
    seconds : float
        The time the whole classification took (the generic run and the search).
    allowed : float or None
        The seconds the search was given (what the budget in force left after the
        generic run, less a share kept for the report); None: no budget in force.
    cut : tuple of (str, str)
        Each search that was cut: what was running, and why.
    pending : tuple of tuple of sympy.Expr
        Exceptional sets found but not examined (each a list of conditions = 0).
    unsolved : tuple of str
        The lower-dimensional searches not made (where, which data, their size).
    failed : tuple of (str, str)
        The runs of a case that failed (an error that is not the input's), with the
        error: the other verdicts stand.

    Examples
    --------
    >>> SearchReport().complete, SearchReport().warning()
    (True, None)
    """

    complete: bool = True
    seconds: float = 0.0
    allowed: float | None = None
    cut: tuple = ()
    pending: tuple = ()
    unsolved: tuple = ()
    failed: tuple = ()

    def warning(self) -> str | None:
        """One line when the search was cut or a run failed: what, why, what was left
        (None if complete)."""
        if self.complete:
            return None
        left = []
        if self.pending:
            left.append(f"{len(self.pending)} exceptional set"
                        f"{'s' if len(self.pending) != 1 else ''} found but not examined")
        if self.unsolved:
            left.append(f"{len(self.unsolved)} lower-dimensional search"
                        f"{'es' if len(self.unsolved) != 1 else ''} not made")
        parts = []
        if self.cut:
            what, why = self.cut[0]
            more = f" and {len(self.cut) - 1} more" if len(self.cut) > 1 else ""
            parts.append(f"was cut during '{short(what, 120)}'{more} ({why})")
        parts += [f"failed in '{short(what, 120)}' ({error})" for what, error in self.failed]
        return ("the search for exceptional cases " + "; it ".join(parts)
                + ": the generic verdict is complete, the cases listed are those found"
                + (f" ({', '.join(left)})" if left else "")
                + ("; allow more time with a larger budget (the command's --budget)"
                   if self.cut else ""))


@dataclass(frozen=True)
class ParametricVerdict:
    """Verdicts for every parameter value (see :func:`nhham.verdict.parametric.parametric_classification`).

    Attributes
    ----------
    generic : Verdict
        The verdict where no case's conditions hold.
    cases : tuple of Case
        The exceptional cases; a parameter point belongs to the first case whose
        conditions it satisfies (the ``excluding`` inequations say so explicitly).
    scene_case : int or None
        Index of the case the system's parameter values fall in (None: generic, or
        no values).
    dropped : tuple of (tuple of sympy.Expr, str)
        Conditions with no real solution under the declared signs, with the reason.
    notes : tuple of str
        Limits hit (depth bound, data not computed and why).
    warnings : tuple of str
        Parameter values near an exceptional set.
    parameters : tuple of sympy.Symbol
    positive : tuple of sympy.Symbol
        Parameters declared positive.
    values : Mapping
        The system's parameter values (of the parameters kept symbolic).
    held : Mapping
        The parameters held at their values (``symbolic=``), with those values.
    search : SearchReport
        Whether the search for cases was complete, and what a budget cut.

    Examples
    --------
    >>> import nhham
    >>> system = nhham.System(["q1", "q2", "q3"], "(a*q1_dot**2 + q2_dot**2 - q3_dot**2)/2",
    ...                       ["q2_dot + b*q3_dot"], parameters={"a": 1.0, "b": 1.0})
    >>> print(nhham.parametric_classification(system, positive=["a"]))
    parameters: a, b (positive: a)
    generic: C regular yes (rank 1), determined, 1 stage(s), 0 free multiplier(s), ...
    case 0: b - 1 = 0
      verdict: C regular no (rank 0), underdetermined, 1 stage(s), 1 free multiplier(s), ...
      why: the rank of (Z_i(chi_j)) on M_1 drops below 1 (C singular)
    case 1: b + 1 = 0
    ...
    values a = 1.0, b = 1.0: case 0
    """

    generic: Verdict
    cases: tuple
    scene_case: int | None
    dropped: tuple
    notes: tuple
    warnings: tuple
    parameters: tuple
    positive: tuple
    values: Mapping = field(default_factory=dict)
    held: Mapping = field(default_factory=dict)
    search: SearchReport = field(default_factory=SearchReport)

    @property
    def scene_verdict(self) -> Verdict:
        """The verdict at the system's parameter values."""
        return self.generic if self.scene_case is None else self.cases[self.scene_case].verdict

    def report(self) -> str:
        """The generic verdict, the cases, dropped conditions and where the values fall."""
        names = ", ".join(p.name for p in self.parameters) or "none"
        lines = [f"parameters: {names}"
                 + (f" (positive: {', '.join(p.name for p in self.positive)})"
                    if self.positive else "")]
        lines.append(f"generic: {self.generic.describe()}")
        for i, case in enumerate(self.cases):
            lines.append(f"case {i}: {case.describe()}")
            lines.append(f"  verdict: {case.verdict.describe()}")
            if case.reasons:
                lines.append(f"  why: {'; '.join(case.reasons)}")
        for eqs, why in self.dropped:
            lines.append(f"dropped: {', '.join(f'{short(e)} = 0' for e in eqs)} ({why})")
        if self.values:
            where = "generic" if self.scene_case is None else f"case {self.scene_case}"
            lines.append("values " + ", ".join(f"{p.name} = {v}" for p, v in self.values.items())
                         + f": {where}")
        lines += [f"note: {n}" for n in self.notes]
        lines += [f"warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def __str__(self):
        return self.report()


@dataclass(frozen=True)
class ValuesVerdict:
    """The verdict at a system's parameter values (see :func:`classification_at_values`).

    Attributes
    ----------
    verdict : Verdict
        The verdict that holds at the values.
    generic : Verdict
        The verdict for generic parameters (what the exact decisions give when they
        treat the parameters as indeterminates).
    conditions : tuple of sympy.Expr
        The exceptional conditions the values satisfy (empty: the values are generic).
    system : System
        The system the verdict was computed on (the conditions substituted).
    warnings : tuple of str
        Values near an exceptional set; the depth bound hit; every check that was not
        made and why (no exact points, a datum not evaluable): an unchecked answer is
        not silently a checked one.

    Examples
    --------
    >>> import nhham
    >>> system = nhham.System(["q1", "q2", "q3"], "(a*q1_dot**2 + q2_dot**2 - q3_dot**2)/2",
    ...                       ["q2_dot + b*q3_dot"], parameters={"a": 1.0, "b": 1.0})
    >>> at = nhham.classification_at_values(system)
    >>> at.verdict.free_multipliers, at.generic.free_multipliers, at.conditions
    (1, 0, (b - 1,))
    """

    verdict: Verdict
    generic: Verdict
    conditions: tuple
    system: object = field(compare=False, repr=False)
    warnings: tuple = ()

    @property
    def differs(self) -> bool:
        """True when the verdict at the values is not the generic one."""
        return self.verdict != self.generic


# ================================================================ entry points

def exact_value(value):
    return sp.Rational(str(value)) if not isinstance(value, sp.Basic) else value

