"""The paper's §4 projection, written once for every side that has one.

A field ξ, vertical fields Z_i (one per multiplier λ^i) and constraints φ_i give
(``DESIGN.md`` §2)::

    C_ij = Z_i(φ_j),     λ^j = −C^{ij} ξ(φ_i),     P(ξ) = ξ + λ^j Z_j,
    Q = C^{ij} Z_j ⊗ dφ_i,     P = id − Q          (P² = P, P(Z_i) = 0).

:class:`Projection` takes the components only (ξ, the rows Z_i and dφ_i in one list of
N variables), never L: on TQ Z_i = −W^{AB} μ_iB ∂/∂v^A
(:class:`~nhham.lagrangian.geometry.LagrangianGeometry`), on T*Q Z_i^H = −μ_iA ∂/∂p_A
(:class:`~nhham.hamiltonian.side.HamiltonianSide`); on M_f of the constraint algorithm
(:class:`~nhham.lagrangian.records.AlgorithmRun`) the constraints are the rows J and the
fields the columns I of a regular block of (Z_i(χ_j)), with the free multipliers in ξ.
:class:`Projected` gives ``projector_P`` and ``project`` from ``projector_Q`` to every
result that has a projector (the two sides, the run, the whole-system analysis).

:func:`tangency_equations` is the one home of the symbolic tangency equations
A λ + b = 0 of constraints χ_j: A_ji = Z_i(χ_j), b_j = ξ(χ_j) (the constraint loop,
the records and C here all read it). Their inverse-free form at points, the bordered
matrix and its right-hand side, is :func:`nhham.lagrangian.formulas.bordered_system`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Callable, Sequence, cast

import sympy as sp

from nhham.errors import ComputationError
from nhham.lagrangian.algebra import cancel, guard_closed_form, solve_linear

__all__ = ["Projection", "Projected", "tangency_equations", "gradient_rows", "time_rates"]


def gradient_rows(functions: Sequence, variables: Sequence) -> sp.Matrix:
    """dχ_j as rows in the basis of ``variables``, shape (len(functions), N).

    Examples
    --------
    >>> import sympy as sp
    >>> x, y = sp.symbols("x y")
    >>> gradient_rows([x * y, x + y], (x, y))
    Matrix([
    [y, x],
    [1, 1]])
    """
    if not functions:
        return sp.zeros(0, len(variables))
    return sp.Matrix([[sp.diff(f, s) for s in variables] for f in functions])


def tangency_equations(gradients: sp.Matrix, field: sp.Matrix | None, vertical: sp.Matrix | None,
                  normal: Callable = cancel, rates: sp.Matrix | None = None
                  ) -> tuple[sp.Matrix | None, sp.Matrix | None]:
    """(A, b) of the tangency equations A λ + b = 0 of constraints χ_j for X = ξ + λ^i Z_i.

    A_ji = Z_i(χ_j) = dχ_j · Z_i and b_j = ξ(χ_j) + ∂χ_j/∂t = dχ_j · ξ + ``rates``_j, each
    entry passed through ``normal`` (:func:`~nhham.lagrangian.algebra.cancel` for rational
    entries, :func:`sympy.expand` for the polynomial rows of scaled fields). With χ = φ,
    A is Cᵀ and b the ξ(φ_i) (+ ∂φ_i/∂t) of the multipliers.

    Parameters
    ----------
    gradients : sympy.Matrix, shape (k, N)
        The rows dχ_j (:func:`gradient_rows`).
    field : sympy.Matrix of shape (N, 1), or None
        ξ; None: b is not formed (returned as None).
    vertical : sympy.Matrix of shape (m, N), or None
        The rows Z_i; None: A is not formed (returned as None).
    normal : callable, optional
    rates : sympy.Matrix of shape (k, 1), or None
        ∂χ_j/∂t for constraints that depend on the time (times δ for scaled fields,
        :func:`time_rates`); None: autonomous constraints.

    Returns
    -------
    A : sympy.Matrix, shape (k, m), or None
    b : sympy.Matrix, shape (k, 1), or None

    Examples
    --------
    The disk of DESIGN.md §2 reduced to one constraint: φ = x_dot − R θ_dot,
    ξ = (x_dot, θ_dot, 0, 0), Z = −W⁻¹ μᵀ with W = diag(m, I):

    >>> import sympy as sp
    >>> x, th, xd, thd, m, I, R = sp.symbols("x theta x_dot theta_dot m I R")
    >>> A, b = tangency_equations(sp.Matrix([[0, 0, 1, -R]]), sp.Matrix([xd, thd, 0, 0]),
    ...                      sp.Matrix([[0, 0, -1 / m, R / I]]))
    >>> A
    Matrix([[(-I - R**2*m)/(I*m)]])
    >>> b
    Matrix([[0]])
    """
    k = gradients.rows
    A = b = None
    if vertical is not None:
        A = sp.Matrix(k, vertical.rows, lambda j, i: normal(
            (gradients.row(j) * vertical.row(i).T)[0])) if k else sp.zeros(0, vertical.rows)
    if field is not None:
        b = sp.Matrix(k, 1, lambda j, _: normal((gradients.row(j) * field)[0]
                                                + (rates[j] if rates is not None else 0))) \
            if k else sp.zeros(0, 1)
    return A, b


def time_rates(functions: Sequence, time, scale=1) -> sp.Matrix | None:
    """δ ∂χ_j/∂t as a column, the time's part of b_j in :func:`tangency_equations`
    (``DESIGN.md`` §2: on ℝ × TQ the field is ∂/∂t + ξ); None when ``time`` is None.

    Examples
    --------
    >>> import sympy as sp
    >>> x, t = sp.symbols("x t")
    >>> time_rates([x - sp.sin(t), x], t).T
    Matrix([[-cos(t), 0]])
    """
    if time is None:
        return None
    return sp.Matrix([scale * sp.diff(f, time) for f in functions]) if functions \
        else sp.zeros(0, 1)


def _same(expr):
    return expr


class Projected:
    """``projector_P`` and ``project`` from ``projector_Q``: one home for every result
    with the paper's almost product structure (:class:`Projection`, the constraint
    algorithm's :class:`~nhham.lagrangian.records.AlgorithmRun` and
    :class:`~nhham.lagrangian.analysis.ConstraintAnalysis`). ``projector_Q`` is None
    where the problem is inconsistent (no projector)."""

    @property
    def projector_Q(self) -> sp.Matrix | None:
        """Q (given by each result)."""
        raise NotImplementedError

    @cached_property
    def projector_P(self) -> sp.Matrix | None:
        """P = id − Q (N x N; P² = P); None when there is no projector."""
        Q = self.projector_Q
        return None if Q is None else sp.eye(Q.rows) - Q

    def project(self, X) -> sp.Matrix:
        """P(X) for a vector field X (N-vector), each entry cancelled.

        For X = ξ + λ^i Z_i with any λ this is the constrained dynamics.

        Raises
        ------
        ComputationError
            When the problem is inconsistent (no projector).
        """
        P = self.projector_P
        if P is None:
            raise ComputationError("the problem is inconsistent: there is no projector")
        return (P * sp.Matrix(X)).applyfunc(cancel)


@dataclass(frozen=True, eq=False)
class Projection(Projected):
    """Q, P, the multipliers and P(ξ) of a field ξ for vertical fields Z_i and constraints φ_i.

    Every derived object is formed on first use; nothing here knows L, W or H, only
    components in one list of N variables.

    Attributes
    ----------
    field : sympy.Matrix of shape (N, 1), callable or None
        ξ, or a function forming it on first use (None when only Q is asked for;
        ``derivatives`` must then be given for the multipliers).
    vertical : sympy.Matrix, shape (m, N)
        The rows Z_i.
    gradients : sympy.Matrix, shape (m, N)
        The rows dφ_i.
    matrix : sympy.Matrix of shape (m, m), or None
        C_ij = Z_i(φ_j) when the caller has it in a better form (on TQ
        −μ W⁻¹ μᵀ); None: from :func:`tangency_equations`.
    derivatives : sympy.Matrix of shape (m, 1), callable or None
        ξ(φ_i) in a better form, or a function forming it on first use; None: from
        :func:`tangency_equations`.
    solve : callable, optional
        ``solve(A, B) -> A⁻¹ B`` (default :func:`~nhham.lagrangian.algebra.solve_linear`;
        on M_f a solve that picks pivots nonzero on M_f).
    normal : callable or None, optional
        Applied to every entry of C and ξ(φ) formed here and of λ, P(ξ) and Q
        (None: left as formed).
    owner : str or None, optional
        Set: λ and Q are refused beyond the closed-form size guard
        (:func:`~nhham.lagrangian.algebra.guard_closed_form`, naming ``owner``).

    Examples
    --------
    One particle in the plane with the constraint φ = y_dot − x_dot (W = I, no force):
    ξ = (x_dot, y_dot, 0, 0), Z = −W⁻¹ μᵀ = (0, 0, 1, −1), C = −2, and P removes the Z part:

    >>> import sympy as sp
    >>> x, y, xd, yd = sp.symbols("x y x_dot y_dot")
    >>> pr = Projection(sp.Matrix([xd, yd, 0, 0]), sp.Matrix([[0, 0, 1, -1]]),
    ...                 sp.Matrix([[0, 0, -1, 1]]))
    >>> pr.constraint_matrix, pr.multipliers
    (Matrix([[-2]]), Matrix([[0]]))
    >>> pr.project(sp.Matrix([0, 0, 1, -1])).T
    Matrix([[0, 0, 0, 0]])
    >>> pr.projector_P * pr.projector_P == pr.projector_P
    True
    """

    field: object
    vertical: sp.Matrix
    gradients: sp.Matrix
    matrix: sp.Matrix | None = None
    derivatives: object = None
    solve: Callable = solve_linear
    normal: Callable | None = None
    owner: str | None = None

    @cached_property
    def xi(self) -> sp.Matrix | None:
        """ξ (``field``, formed on first use when given as a function)."""
        return self.field() if callable(self.field) else cast("sp.Matrix | None", self.field)

    @property
    def m(self) -> int:
        """Number of vertical fields (multipliers)."""
        return self.vertical.rows

    @property
    def N(self) -> int:
        """Number of variables."""
        return self.gradients.cols

    def _normal(self, M: sp.Matrix) -> sp.Matrix:
        return M if self.normal is None else M.applyfunc(self.normal)

    def _guard(self, what: str) -> None:
        if self.owner is not None:
            guard_closed_form(self.constraint_matrix, what, self.owner)

    @cached_property
    def constraint_matrix(self) -> sp.Matrix:
        """C_ij = Z_i(φ_j), shape (m, m)."""
        if self.matrix is not None:
            return self.matrix
        A, _ = tangency_equations(self.gradients, None, self.vertical, self.normal or _same)
        return cast(sp.Matrix, A).T

    @cached_property
    def constraint_derivatives(self) -> sp.Matrix:
        """ξ(φ_i), shape (m, 1)."""
        d = self.derivatives
        if d is None:
            if self.xi is None:
                raise ComputationError("a projection without a field has no multipliers")
            _, d = tangency_equations(self.gradients, self.xi, None, self.normal or _same)
        elif callable(d):
            d = d()
        return d

    @cached_property
    def multipliers(self) -> sp.Matrix:
        """λ^j = −C^{ij} ξ(φ_i): a solve with Cᵀ, shape (m, 1)."""
        if not self.m:
            return sp.zeros(0, 1)
        self._guard("multipliers")
        return self._normal(-self.solve(self.constraint_matrix.T, self.constraint_derivatives))

    @cached_property
    def projected_field(self) -> sp.Matrix:
        """P(ξ) = ξ − C^{ij} ξ(φ_i) Z_j = ξ + λ^j Z_j, shape (N, 1)."""
        if not self.m:
            return self.xi
        return self._normal(self.xi + self.vertical.T * self.multipliers)

    @cached_property
    def projector_Q(self) -> sp.Matrix:
        """Q = C^{ij} Z_j ⊗ dφ_i = Zᵀ C⁻ᵀ dφ as an N x N matrix acting on columns."""
        if not self.m:
            return sp.zeros(self.N, self.N)
        self._guard("projector_Q")
        return self._normal(self.vertical.T * self.solve(self.constraint_matrix.T,
                                                         self.gradients))
