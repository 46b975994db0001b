"""The first/second-class split of a set of constraints on T*Q: the result object."""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from nhham.hamiltonian.side import HamiltonianSide
from nhham.lagrangian.decision import Decision
from nhham.lagrangian.submanifold import Submanifold

__all__ = ["ConstraintClasses"]


# --------------------------------------------------------------- results
@dataclass(frozen=True)
class ConstraintClasses:
    """Classification of the final constraints chi_a on M_f (in T*Q).

    Attributes
    ----------
    labels : tuple of str
        Names of the chi_a.
    constraints_TQ : tuple of sympy.Expr
        chi_a on TQ, functions of (q, v).
    constraints : tuple of sympy.Expr or None
        chi_a o Leg^{-1} in (q, p) (None in sampled mode without a symbolic inverse).
    bracket_matrix : sympy.Matrix or None
        B_ab = {chi_a, chi_b} reduced on M_f (exact mode), shape (k, k).
    bracket_samples : tuple of numpy.ndarray
        B at the sample points of M_f (sampled mode, or the pivot evidence).
    rank : int
        rank B on M_f = number of second-class constraints.
    first_class, second_class : int
    second_class_set : tuple of str
        Labels of a maximal second-class set R (B_RR invertible on M_f).
    first_class_combinations : tuple of sympy.Expr or None
        A basis gamma_k = chi_k - sum_{a in R} (B_RR^{-1} B_Rk)_a chi_a (in
        (q, p)), one per constraint outside R.
    combination_coefficients : tuple of dict
        ``{label: coefficient}`` of each gamma_k (expressions on M_f in
        exact mode; in sampled mode a tuple of values, one per sample point).
    individually_first_class : tuple of str
        Labels whose whole row of B vanishes on M_f.
    blocks : tuple of tuple of str
        Connected components of the nonzero pattern of B on M_f.
    decisions : dict
        Named :class:`Decision` objects: ``"rank"``, ``"B[a,b]"`` per entry,
        ``"gamma[k]"`` for the check that each combination is first class.
    method : str
        ``"exact"`` (symbolic B reduced on M_f), ``"exact at points"`` (B at
        exact points of M_f: each decision says whether it is a proof or carries
        a Schwartz–Zippel error bound; no symbolic B) or ``"sampled"``.
    manifold : Submanifold or None
        M_f in T*Q (exact mode).
    side : HamiltonianSide
    analysis : object or None
        The ConstraintAnalysis the constraints came from.

    Examples
    --------
    The rolling disk's constraints p_x/m - R cos(theta) p_phi/I2 and p_y/m - R sin(theta)
    p_phi/I2 commute (neither depends on p_theta): both first class.

    >>> from nhham import classify_constraints, models
    >>> classes = classify_constraints(models.rolling_disk())
    >>> classes
    <ConstraintClasses: 2 final constraint(s), 0 second class, 2 first class (exact)>
    >>> classes.bracket_matrix
    Matrix([
    [0, 0],
    [0, 0]])
    """

    labels: tuple
    constraints_TQ: tuple
    constraints: tuple | None
    bracket_matrix: sp.Matrix | None
    bracket_samples: tuple
    rank: int
    first_class: int
    second_class: int
    second_class_set: tuple
    first_class_combinations: tuple | None
    combination_coefficients: tuple
    individually_first_class: tuple
    blocks: tuple
    decisions: dict
    method: str
    manifold: Submanifold | None
    side: HamiltonianSide
    analysis: object = None

    @property
    def second_class_indices(self) -> tuple:
        return tuple(self.labels.index(lab) for lab in self.second_class_set)

    @property
    def second_class_constraints(self) -> tuple | None:
        """The chi_a of the maximal second-class set, in (q, p)."""
        if self.constraints is None:
            return None
        return tuple(self.constraints[a] for a in self.second_class_indices)

    @property
    def rank_decision(self) -> Decision:
        return self.decisions["rank"]

    @property
    def warnings(self) -> tuple:
        """Warnings of every decision, prefixed by what was decided."""
        return tuple(f"{name}: {w}" for name, d in self.decisions.items() for w in d.warnings)

    def __repr__(self) -> str:
        return (f"<ConstraintClasses: {len(self.labels)} final constraint(s), "
                f"{self.second_class} second class, {self.first_class} first class "
                f"({self.method})>")

    def _repr_latex_(self) -> str:
        """The classification table (for notebooks)."""
        kinds = {lab: "in the maximal second-class set" for lab in self.second_class_set}
        rows = [rf"\text{{{lab}}} & \text{{{kinds.get(lab, 'gives a first-class combination')}}}"
                for lab in self.labels]
        head = (rf"\operatorname{{rank}} \{{\chi_a, \chi_b\}} = {self.rank}:\ "
                rf"{self.second_class}\ \text{{second class}},\ {self.first_class}\ "
                rf"\text{{first class}}")
        return "$$" + head + r"\\ \begin{array}{ll}" + r" \\ ".join(rows) + r"\end{array}$$"

    def describe(self) -> str:
        lines = [f"{len(self.labels)} final constraints: {self.second_class} second class, "
                 f"{self.first_class} first class (rank of the bracket matrix on M_f: "
                 f"{self.rank_decision.describe()})"]
        if self.second_class_set:
            lines.append("maximal second-class set: " + ", ".join(self.second_class_set))
        if self.first_class_combinations is not None:
            for g in self.first_class_combinations:
                lines.append(f"first class: {g}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready summary (expressions as sympy-parsable strings)."""
        def coeffs(c):
            return {k: (str(v) if isinstance(v, sp.Basic) else [float(x) for x in v])
                    for k, v in c.items()}
        return {
            "constraints": [str(c) for c in self.constraints] if self.constraints else None,
            "labels": list(self.labels),
            "rank": self.rank,
            "first_class": self.first_class,
            "second_class": self.second_class,
            "second_class_set": list(self.second_class_set),
            "first_class_combinations": (None if self.first_class_combinations is None
                                         else [str(g) for g in self.first_class_combinations]),
            "combination_coefficients": [coeffs(c) for c in self.combination_coefficients],
            "individually_first_class": list(self.individually_first_class),
            "blocks": [list(b) for b in self.blocks],
            "method": self.method,
            "decisions": {k: {"value": d.value if isinstance(d.value, (bool, int)) else str(d.value),
                              "method": d.method, "detail": d.detail, "precision": d.precision,
                              "warnings": list(d.warnings)}
                          for k, d in self.decisions.items()},
        }
