"""The results of the Lagrangian <-> Hamiltonian cross-check: one check, the report.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["CheckResult", "CrossCheckReport", "stage_summaries"]


# ------------------------------------------------------------------ results
@dataclass(frozen=True)
class CheckResult:
    """One comparison of the cross-check.

    Attributes
    ----------
    name : str
    agree : bool
    exact : bool
        True when agreement was decided exactly (the symbolic difference
        cancels, or reduces to zero on M_f by exact reduction).
    max_abs_difference, max_rel_difference : float
        Over the sample points (0 when the check has no numeric part).
    samples : int
    detail : str
    decisions : tuple of Decision
        Decisions on M_f behind ``exact`` (when a difference had to be reduced).
    method : str
        How the numbers were compared: ``"exact"`` (symbolic), ``"points"``
        (exact arithmetic modulo p at exact points: each difference is exactly 0,
        which is a proof at those points, not of the identity) or ``"sampled"``.
    """

    name: str
    agree: bool
    exact: bool
    max_abs_difference: float = 0.0
    max_rel_difference: float = 0.0
    samples: int = 0
    detail: str = ""
    decisions: tuple = ()
    method: str = ""

    @property
    def how(self) -> str:
        """``method``, defaulting to "exact" or "sampled" from ``exact``."""
        return self.method or ("exact" if self.exact else "sampled")

    def to_dict(self) -> dict:
        return {"agree": self.agree, "exact": self.exact,
                "max_abs_difference": self.max_abs_difference,
                "max_rel_difference": self.max_rel_difference, "samples": self.samples,
                "detail": self.detail, "method": self.how}


@dataclass(frozen=True)
class CrossCheckReport:
    """Lagrangian <-> Hamiltonian agreement through the Legendre map.

    Attributes
    ----------
    agree : bool
        Every check agrees.
    exact : bool
        Every check was decided exactly.
    max_abs_difference, max_rel_difference : float
        Largest over the checks' sampled differences.
    samples : int
        Number of seeded points of M_f.
    tolerance : float
        Relative tolerance of sampled agreement.
    precision : str
        ``"float64"``, ``"mpmath:<digits>"`` or ``"exact mod p = 2^61 - 1"``.
    method : str
        ``"exact"``, ``"points"`` or ``"sampled"``.
    checks : tuple of CheckResult
    lagrangian_stages, hamiltonian_stages : tuple of dict
        Per stage: index, number of constraints, rank, augmented rank, labels.
    statuses : tuple of str
        (TQ status, T*Q status).
    seconds : float
        Wall time of the cross-check.
    skipped_points : int
        Seeded points dropped because C is not of its generic rank there.

    Examples
    --------
    >>> from nhham import cross_check, models
    >>> report = cross_check(models.rolling_disk())
    >>> [(check.name, check.agree) for check in report.checks]
    [('stages', True), ('legendre inverse', True), ('field', True), ('multipliers', True),
     ('symplectic form', True), ('Poisson map', True)]
    """

    agree: bool
    exact: bool
    max_abs_difference: float
    max_rel_difference: float
    samples: int
    tolerance: float
    precision: str
    method: str
    checks: tuple
    lagrangian_stages: tuple
    hamiltonian_stages: tuple
    statuses: tuple
    seconds: float
    skipped_points: int = 0

    @property
    def detail(self) -> dict:
        """``{check name: CheckResult}``."""
        return {c.name: c for c in self.checks}

    def describe(self) -> str:
        head = (f"cross-check ({self.method}, {self.precision}): "
                f"{'AGREE' if self.agree else 'DISAGREE'}"
                f"{' exactly' if self.exact and self.agree else ''}; max |difference| "
                f"{self.max_abs_difference:.3g} (relative {self.max_rel_difference:.3g}) at "
                f"{self.samples} seeded points of M_f, tolerance {self.tolerance:g}"
                + (f" ({self.skipped_points} non-generic point(s) skipped)"
                   if self.skipped_points else ""))
        lines = [head]
        for c in self.checks:
            lines.append(f"  {c.name}: {'agrees' if c.agree else 'DIFFERS'} "
                         f"({c.how}): {c.detail}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready (keys used by ``nhham compare --json``)."""
        return {
            "agree": self.agree, "exact": self.exact,
            "max_abs_difference": self.max_abs_difference,
            "max_rel_difference": self.max_rel_difference,
            "samples": self.samples, "tolerance": self.tolerance,
            "precision": self.precision, "method": self.method,
            "checks": {c.name: c.to_dict() for c in self.checks},
            "lagrangian_stages": [dict(s) for s in self.lagrangian_stages],
            "hamiltonian_stages": [dict(s) for s in self.hamiltonian_stages],
            "statuses": list(self.statuses),
            "seconds": self.seconds, "skipped_points": self.skipped_points,
        }


def stage_summaries(stages) -> tuple:
    return tuple({"index": st.index, "constraints": len(st.constraints), "rank": st.rank,
                  "augmented_rank": st.augmented_rank, "labels": list(st.labels)}
                 for st in stages)
