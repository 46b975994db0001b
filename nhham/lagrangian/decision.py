"""How a rank or a vanishing on M_k was decided: the Decision record.

Every decision of the exact layers names its method (``exact``, ``exact at points``,
``sampled``), its precision, the points it used and its error bound, so a verdict can say
how far it can be trusted.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, is_dataclass, replace
from typing import TYPE_CHECKING

from nhham.settings import SEED, check_options

if TYPE_CHECKING:
    from nhham.system.description import System

__all__ = ["Assumption", "Decision", "DecisionSettings", "scoped"]


@dataclass(frozen=True, eq=False, repr=False)
class DecisionSettings:
    """A system with the settings of the decisions taken on it (frozen; the base of
    :class:`~nhham.lagrangian.geometry.LagrangianGeometry` and
    :class:`~nhham.hamiltonian.side.HamiltonianSide`).

    Attributes
    ----------
    system : nhham.System
    precision : int or None
        Sampled decisions in float64 (None) or mpmath with this many digits.
    samples, seed : int
        Number and seed of the sample points of sampled decisions.
    """

    system: "System"
    precision: int | None = None
    samples: int = 6
    seed: int = SEED

    def __post_init__(self):
        check_options(type(self).__name__, precision=self.precision, samples=self.samples,
                      seed=self.seed)

    def __repr__(self):
        return f"{type(self).__name__}({self.system!r})"

    @property
    def n(self) -> int:
        """Number of coordinates."""
        return self.system.n

    @property
    def m(self) -> int:
        """Number of affine constraints (lifts of the holonomic ones included)."""
        return self.system.m


@dataclass(frozen=True)
class Decision:
    """How a vanishing or rank question on a submanifold was answered.

    Attributes
    ----------
    value : bool or int
        ``True``/``False`` for "vanishes on M", or the rank for rank questions.
    method : {"exact", "exact at points", "sampled"}
        Exact reduction (or a rank proved at an exact point), exact evaluation at
        random exact points (a probabilistic verdict with ``error_bound``), or
        evaluation at floating-point sample points (``precision``).
    detail : str
        Human-readable evidence.
    precision : str
        ``"exact"``, ``"float64"`` or ``"mpmath:<digits>"``.
    samples : int
        Number of sample points used (0 for exact decisions).
    max_abs : float or None
        Largest absolute value found at the samples (vanishing questions).
    singular_values : tuple of tuple of float
        Singular values at each sample (rank questions).
    point_residual : float or None
        Largest constraint residual of the sample points.
    warnings : tuple of str
        Reasons to distrust the answer (rank not constant, values near the
        tolerance).
    points : tuple of tuple
        The sample points of a sampled decision, each a tuple of
        ``(variable name, float)`` pairs (rounded for the record).
    error_bound : float or None
        For "exact at points": the Schwartz–Zippel bound on the probability that
        the verdict is wrong (0.0 for a proof); None for other methods.
    scope : str
        Where an exact answer holds when that is less than all of M for all parameter
        values: a proof at a point of a curved M holds on the component of M through
        the point, at the parameter values ("" otherwise). Also ends ``detail``.

    Examples
    --------
    On the rolling disk's M_1 = {phi = 0}: twice a constraint vanishes there, x' does not.

    >>> from nhham import Submanifold, models
    >>> disk = models.rolling_disk(symbolic=True)
    >>> M1 = Submanifold(disk, disk.phi)
    >>> decision = M1.vanishes(2 * disk.phi[0])
    >>> decision.value, decision.method
    (True, 'exact')
    >>> M1.vanishes(disk.velocities[0]).value
    False
    """

    value: object
    method: str
    detail: str
    precision: str = "exact"
    samples: int = 0
    max_abs: float | None = None
    singular_values: tuple = ()
    point_residual: float | None = None
    warnings: tuple = ()
    points: tuple = field(default=(), compare=False)
    error_bound: float | None = None
    scope: str = ""

    def __bool__(self):
        return bool(self.value)

    def to_dict(self, value: bool = True) -> dict:
        """Method, precision, samples, error bound and detail (and the value), JSON-ready
        (non-finite numbers as strings)."""
        from nhham.settings import json_number

        out = {"value": self.value} if value else {}
        out.update(method=self.method, precision=str(self.precision),
                   samples=int(self.samples or 0), error_bound=json_number(self.error_bound),
                   detail=self.detail)
        if self.scope:
            out["scope"] = self.scope
        return out

    def describe(self) -> str:
        """One line saying what was decided and how (with the numeric evidence)."""
        how = self.method if self.method != "exact at points" else (
            f"exact at {self.samples} points, error <= {self.error_bound:.1e}")
        text = f"{self.value} ({how}, {self.precision}): {self.detail}"
        if self.singular_values:
            smallest = [min(sv) if sv else 0.0 for sv in self.singular_values]
            text += f"; smallest singular value per point {_floats(smallest)}"
        if self.point_residual is not None and self.method == "sampled":
            text += f"; point residual <= {self.point_residual:.2g}"
        if self.warnings:
            text += " WARNING: " + "; ".join(self.warnings)
        return text


def scoped(answer, scope: str):
    """``answer`` with ``scope`` on every exact :class:`Decision` in it (through frozen
    dataclasses, tuples and lists); the answer itself when ``scope`` is empty.

    The decision engine calls it for proofs at points of a curved M, whose quantities
    build their Decisions without knowing where the point came from.
    """
    if not scope:
        return answer
    if isinstance(answer, Decision):
        if answer.method == "sampled" or answer.scope:
            return answer
        return replace(answer, scope=scope, detail=f"{answer.detail}; {scope}")
    if isinstance(answer, (tuple, list)):
        items = [scoped(x, scope) for x in answer]
        if all(a is b for a, b in zip(items, answer)):
            return answer
        return type(answer)(*items) if hasattr(answer, "_fields") else type(answer)(items)
    if is_dataclass(answer) and not isinstance(answer, type):
        changes = {}
        for f in fields(answer):
            value = getattr(answer, f.name)
            if f.init and isinstance(value, (Decision, tuple, list)):
                new = scoped(value, scope)
                if new is not value:
                    changes[f.name] = new
        return replace(answer, **changes) if changes else answer
    return answer


def _floats(values):
    return "[" + ", ".join(f"{v:.3g}" for v in values) + "]"


@dataclass(frozen=True)
class Assumption:
    """A function a generic decision assumed not identically zero on M_k.

    The verdict at parameter values (:mod:`nhham.lagrangian.exceptional`) evaluates
    these records, with the parameters symbolic or at their values, instead of
    deriving them again.

    Attributes
    ----------
    reason : str
        What changes where the function vanishes identically (``"the Lagrangian is
        singular (det W = 0)"``).
    formula : {"det", "maximal minors", "bordered det", "value", "Frobenius terms"}
        How the function is formed from ``data`` (:mod:`nhham.lagrangian.formulas`):
        det of the matrix; the maximal minors of μ; det [[W, μ_Iᵀ], [∂χ_J/∂v, 0]]
        from ``(W, μ_I, ∂χ_J/∂v)``; the expression itself; dμ_i(X_a, X_b) on ker μ.
    data : tuple
        The rows (tuples of sympy expressions) or the expression the formula takes.
    on : tuple of sympy.Expr
        The constraints of M_k, where the function is evaluated.
    stage : int
        k.
    """

    reason: str
    formula: str
    data: tuple
    on: tuple
    stage: int
