"""The Lagrangian side of the paper (Sections 2 and 4): geometry on TQ.

Conventions are those of ``DESIGN.md`` §2, restated where each object is
defined. Vectors on TQ are sympy column matrices of length 2n in the order
(q^1..q^n, v^1..v^n); (1,1) tensors are 2n x 2n matrices acting on them; a
2-form is the antisymmetric matrix Omega with omega(X, Y) = X^T Omega Y.

Nothing is computed before it is asked for. The symbolic inverse of W is
never written out: every product W^{-1} b is a linear solve, and the
multipliers come from a solve with the m x m matrix C.

Fast path: when L is quadratic in the velocities, L = v^T W(q) v / 2 +
b(q) . v - V(q) (every natural Lagrangian), W, b and V are read from the
terms of L (:func:`nhham.system.velocities.quadratic_parts`) and the momenta, the mixed
Hessian and the forcing are assembled from derivatives of the small entries
of W, b and V instead of differentiating L twice::

    F_B = 1/2 v^T (dW/dq^B) v - (dW_BA/dq^C) v^A v^C
          + (db_A/dq^B - db_B/dq^A) v^A - dV/dq^B.

Each entry is differentiated term by term and only by the coordinates the
term contains. Other Lagrangians take the general path (derivatives of L);
both give the same expressions up to algebraic rearrangement.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from functools import cached_property

import sympy as sp

from nhham.settings import SEED
from nhham.lagrangian.adjugate import (CLOSED_FORM_WORK, ScaledInverse, closed_form_size,
                                       scaled_inverse)
from nhham.lagrangian.algebra import solve_linear
from nhham.lagrangian.decision import Decision, DecisionSettings
from nhham.lagrangian.engine import Policy, policy_of
from nhham.lagrangian.projection import Projection
from nhham.lagrangian.submanifold import Submanifold
from nhham.system.expressions import derivative
from nhham.system.naming import acceleration_symbol, multiplier_symbol
from nhham.system.velocities import quadratic_parts

__all__ = ["LagrangianGeometry", "lagrangian_geometry", "ConstraintMatrixRank",
           "DynamicsIngredients"]


@dataclass(frozen=True)
class DynamicsIngredients:
    """The pieces from which the constrained accelerations are solved.

    With accelerations a and multipliers lambda, the constrained
    Euler-Lagrange equations are the saddle-point system::

        [ W   mu^T ] [ a      ]   [ forcing ]
        [ mu  0    ] [ lambda ] = [ -drift  ]

    Attributes
    ----------
    W : sympy.Matrix, shape (n, n)
        Hessian d2L/dv^A dv^B.
    forcing : sympy.Matrix, shape (n, 1)
        F_B = dL/dq^B - (d2L/dq^C dv^B) v^C.
    mu : sympy.Matrix, shape (m, n)
        Constraint one-forms.
    drift : sympy.Matrix, shape (m, 1)
        (d phi_i / d q^A) v^A, so that xi(phi_i) = drift_i + mu_i . a.

    Examples
    --------
    >>> from nhham import lagrangian_geometry, models
    >>> parts = lagrangian_geometry(models.rolling_disk()).ingredients
    >>> parts.W, parts.mu
    (Matrix([
    [m, 0,  0,  0],
    [0, m,  0,  0],
    [0, 0, I1,  0],
    [0, 0,  0, I2]]), Matrix([
    [1, 0, 0, -R*cos(theta)],
    [0, 1, 0, -R*sin(theta)]]))
    >>> parts.drift.T, parts.forcing.T      # d(-R cos(theta) phi')/dtheta theta', ...
    (Matrix([[R*phi_dot*theta_dot*sin(theta), -R*phi_dot*theta_dot*cos(theta)]]),
     Matrix([[0, 0, 0, 0]]))
    """

    W: sp.Matrix
    forcing: sp.Matrix
    mu: sp.Matrix
    drift: sp.Matrix


def lagrangian_geometry(system, precision: int | None = None, samples: int = 6,
                        seed: int = SEED, closed_form: bool | None = False, *,
                        policy: Policy | None = None) -> "LagrangianGeometry":
    """The Lagrangian-side objects of ``system``, computed lazily.

    Parameters
    ----------
    system : nhham.System
    precision, samples, seed : optional
        Deprecated (a ``DeprecationWarning``; removed in the next release): give them in
        ``policy``.
    policy : nhham.Policy, optional
        The decision settings; its ``precision`` (None: float64; an integer: mpmath
        digits), ``samples`` and ``seed`` are those of the sampled "on M_1" decisions.
    closed_form : bool, optional
        True: form the closed forms that need a symbolic solve with C (``multipliers``,
        ``projected_field``, ``projector_Q``) whatever their size. False (default): refuse
        them beyond a size guard (:func:`nhham.lagrangian.algebra.guard_closed_form`) with
        a :class:`~nhham.errors.ClosedFormTooLarge` naming the implicit form. None:
        either, for a caller that forms no closed form (the constraint analysis): the
        geometry already built with these settings, else a new one with False.

    Returns
    -------
    LagrangianGeometry
        One object per system and settings: a second call with the same arguments
        returns the first call's geometry, so that what it has formed (W, the
        forcing, the fibre derivatives) is formed once per command. A System is
        frozen, so its geometry cannot go stale.

    Examples
    --------
    The rolling disk's C = -mu W^-1 mu^T at theta = 0 with m = 1, R = 1, I2 = 0.5:
    diag(-1/m - R**2/I2, -1/m) = diag(-3, -1).

    >>> from nhham import lagrangian_geometry, models
    >>> disk = models.rolling_disk()
    >>> geometry = lagrangian_geometry(disk)
    >>> geometry is lagrangian_geometry(disk)
    True
    >>> geometry.constraint_matrix.subs(disk.parameter_values).subs("theta", 0)
    Matrix([
    [-3.0,    0],
    [   0, -1.0]])
    """
    policy = policy_of(policy, "lagrangian_geometry", precision=precision, samples=samples,
                       seed=seed)
    system.require_regular_lagrangian("the Lagrangian geometry (xi_L, Z_i, C, P)")
    precision, samples, seed = policy.precision, policy.samples, policy.seed
    # Kept on the system itself (a cycle the collector frees with it); a weak-keyed
    # table would keep every system alive through its geometry's reference to it.
    shared = system.__dict__.setdefault("_lagrangian_geometries", {})
    if closed_form is None:  # either will do: the one built already, else a plain one
        closed_form = (precision, samples, seed, True) in shared and \
            (precision, samples, seed, False) not in shared
    key = (precision, samples, seed, bool(closed_form))
    if key not in shared:
        geometry = LagrangianGeometry(system, precision=precision, samples=samples,
                                      seed=seed, closed_form=closed_form)
        # closed_form only decides whether a closed form is refused, never its value:
        # a geometry differing in it alone starts from what the other has formed.
        sibling = shared.get(key[:3] + (not key[3],))
        if sibling is not None:
            settings = {f.name for f in fields(LagrangianGeometry)}  # the arguments
            formed = {k: v for k, v in vars(sibling).items()
                      if k not in settings and k != "projection"}
            vars(geometry).update(formed)
            if "projection" in vars(sibling):  # its closed forms, not its size guard
                inputs = {f.name for f in fields(Projection)}
                vars(geometry.projection).update(
                    {k: v for k, v in vars(sibling.projection).items() if k not in inputs})
        shared[key] = geometry
    return shared[key]


@dataclass(frozen=True, eq=False, repr=False)
class ConstraintMatrixRank(DecisionSettings):
    """The rank of the constraint matrix on M_1 and whether C is regular there: one home
    for both sides, :class:`LagrangianGeometry` (C on TQ) and
    :class:`~nhham.hamiltonian.side.HamiltonianSide` (C^H on T*Q), each of which gives
    ``M1`` and ``constraint_matrix``.

    "Regular" alone, here and in every classification result
    (``ConstraintAnalysis.regular``, ``Verdict.regular``, the ``regular`` key of the
    command's JSON, its "C regular on M_1"), means C regular on M_1: rank C = m, the
    multipliers determined there. The other regularity, of the Lagrangian (W = d2L/dv dv
    invertible), is always named with its noun: every :class:`~nhham.System` has a
    regular Lagrangian (checked on construction), so no property asks for it.
    """

    @property
    def M1(self) -> Submanifold:
        """M_1 = {g = 0, phi = 0} on this side (given by each side)."""
        raise NotImplementedError

    @property
    def constraint_matrix(self) -> sp.Matrix:
        """C on this side, shape (m, m) (given by each side)."""
        raise NotImplementedError

    @cached_property
    def constraint_rank(self) -> Decision:
        """rank of C on M_1, with how it was decided."""
        return self.M1.rank(self.constraint_matrix)

    @property
    def regular(self) -> bool:
        """True when C is regular on M_1: rank C = m (not the Lagrangian's regularity)."""
        return self.constraint_rank.value == self.m


@dataclass(frozen=True, eq=False, repr=False)
class LagrangianGeometry(ConstraintMatrixRank):
    """Lagrangian-side geometry of a constrained system (frozen, lazy).

    Every attribute is computed on first access and then kept. Arguments as
    :func:`lagrangian_geometry`, plus ``fast`` (default True): use the
    quadratic fast path when L is quadratic in the velocities; False always
    differentiates L (the general path, for comparisons).

    Examples
    --------
    A particle on y' = x x': with x'' = x lambda and y'' = -lambda, y'' = x'^2 + x x''
    gives lambda = -x'^2/(1 + x^2).

    >>> import sympy as sp
    >>> from nhham import System, lagrangian_geometry
    >>> s = System(["x", "y"], "(x_dot**2 + y_dot**2)/2", constraints=["y_dot - x*x_dot"])
    >>> geometry = lagrangian_geometry(s)
    >>> geometry.regular, geometry.constraint_matrix
    (True, Matrix([[-x**2 - 1]]))
    >>> [sp.factor(a) for a in geometry.projected_field[2:]]     # x'', y''
    [-x*x_dot**2/(x**2 + 1), x_dot**2/(x**2 + 1)]
    """

    # fast=False forces the general path (differentiate L) even for a
    # Lagrangian quadratic in the velocities: for tests and comparisons.
    fast: bool = True
    closed_form: bool = False

    # ------------------------------------------------------------ basics

    @cached_property
    def _v(self):
        return sp.Matrix(self.system.velocities)

    @cached_property
    def _parts(self):
        """QuadraticParts of L (fast path) or None (general path)."""
        if not self.fast:
            return None
        if getattr(type(self.system), "quadratic_parts", None) is not None:
            return self.system.quadratic_parts
        return quadratic_parts(self.system.lagrangian, self.system.velocities)

    @cached_property
    def _qidx(self):
        return {q: i for i, q in enumerate(self.system.coordinates)}

    @cached_property
    def _dW(self):
        """{(A, C): {B: dW_AC/dq^B}} for A <= C, nonzero derivatives only."""
        W, n = self._parts.W, self.n
        out = {}
        for A in range(n):
            for C in range(A, n):
                if W[A, C] != 0:
                    d = _coordinate_derivatives(W[A, C], self._qidx)
                    if d:
                        out[A, C] = d
        return out

    @cached_property
    def _db(self):
        """{A: {B: db_A/dq^B}}, nonzero derivatives only."""
        out = {}
        for A, bA in enumerate(self._parts.b):
            if bA != 0:
                d = _coordinate_derivatives(bA, self._qidx)
                if d:
                    out[A] = d
        return out

    @property
    def state(self) -> tuple:
        """The coordinates of TQ, (q, v) (``system.state``)."""
        return tuple(self.system.state)

    @cached_property
    def momenta(self) -> sp.Matrix:
        """Fibre derivative p_A = dL/dv^A, shape (n, 1)."""
        parts = self._parts
        if parts is not None:
            W, v = parts.W, self.system.velocities
            return sp.Matrix([
                sp.Add(parts.b[A], *[W[A, C] * v[C] for C in range(self.n) if W[A, C] != 0])
                for A in range(self.n)])
        L = self.system.lagrangian
        return sp.Matrix([sp.diff(L, v) for v in self.system.velocities])

    @cached_property
    def energy(self) -> sp.Expr:
        """E_L = v^A dL/dv^A - L.

        For L = v^T W v / 2 + b . v - V (Euler's theorem on the homogeneous parts):
        E_L = sum_A W_AA (v^A)^2 / 2 + sum_{A<C} W_AC v^A v^C + V, read from the terms
        and kept in that form, a coefficient per velocity monomial (expanding it cost
        0.2 s on the bicycle and reads worse).
        """
        parts = self._parts
        if parts is None:
            return sp.expand((self._v.T * self.momenta)[0] - self.system.lagrangian)
        W, v, n = parts.W, self.system.velocities, self.n
        return sp.Add(*[W[A, A] / 2 * v[A] ** 2 for A in range(n)],
                      *[W[A, C] * v[A] * v[C] for A in range(n) for C in range(A + 1, n)
                        if W[A, C] != 0],
                      parts.V)

    @cached_property
    def hessian(self) -> sp.Matrix:
        """W_AB = d2L/dv^A dv^B, shape (n, n)."""
        if not self.fast:
            return sp.hessian(self.system.lagrangian, self.system.velocities)
        return self.system.hessian

    @cached_property
    def mixed_hessian(self) -> sp.Matrix:
        """M_AB = d2L/dv^A dq^B = d p_A / d q^B, shape (n, n).

        Fast path: M_AB = (dW_AC/dq^B) v^C + db_A/dq^B.
        """
        if self._parts is None:
            return self.momenta.jacobian(self.system.coordinates)
        n, v = self.n, self.system.velocities
        terms: list[list[list]] = [[[] for _ in range(n)] for _ in range(n)]
        for (A, C), dW in self._dW.items():
            for B, d in dW.items():
                terms[A][B].append(d * v[C])
                if A != C:
                    terms[C][B].append(d * v[A])
        for A, db in self._db.items():
            for B, d in db.items():
                terms[A][B].append(d)
        return sp.Matrix(n, n, lambda A, B: sp.Add(*terms[A][B]))

    @cached_property
    def poincare_cartan_1form(self) -> sp.Matrix:
        """alpha_L = J*(dL) = (dL/dv^A) dq^A as a 2n-vector of coefficients."""
        return sp.Matrix.vstack(self.momenta, sp.zeros(self.n, 1))

    @cached_property
    def poincare_cartan_2form(self) -> sp.Matrix:
        """omega_L = -d alpha_L = dq^A ^ d(dL/dv^A) as a 2n x 2n matrix Omega.

        Blocks: Omega_qq = M - M^T, Omega_qv = W, Omega_vq = -W, Omega_vv = 0,
        with omega(X, Y) = X^T Omega Y.
        """
        M, W, n = self.mixed_hessian, self.hessian, self.n
        return sp.Matrix(sp.BlockMatrix([[M - M.T, W], [-W, sp.zeros(n, n)]]))

    @cached_property
    def liouville_field(self) -> sp.Matrix:
        """Liouville field C = v^A d/dv^A as a 2n-vector."""
        return sp.Matrix.vstack(sp.zeros(self.n, 1), self._v)

    @cached_property
    def almost_tangent_structure(self) -> sp.Matrix:
        """J = d/dv^A (x) dq^A as a 2n x 2n matrix (maps d/dq^A to d/dv^A)."""
        n = self.n
        return sp.Matrix(sp.BlockMatrix([[sp.zeros(n, n), sp.zeros(n, n)],
                                         [sp.eye(n), sp.zeros(n, n)]]))

    # --------------------------------------------------------- solves with W
    @cached_property
    def closed_form_affordable(self) -> bool:
        """True when W^-1 in closed form is small: W diagonal or free of the state, or
        n times the operations of δ W⁻¹ at most
        :data:`~nhham.lagrangian.adjugate.CLOSED_FORM_WORK`
        (:func:`~nhham.lagrangian.adjugate.closed_form_size`: bounded by the size of the
        work, not by n alone).

        Otherwise the closed forms (ξ_L, Z_i, C, λ, P(ξ_L)) are formed only when asked
        for; decisions are made at points.
        """
        # A determinant of more than CLOSED_FORM_WORK / 2n terms (bounded before it is
        # formed) leaves no room for the adjugate: not formed.
        size = closed_form_size(self.hessian, self.state, lambda: self.scaled_inverse,
                                max_terms=CLOSED_FORM_WORK // (2 * self.n))
        return size is not None and size * self.n <= CLOSED_FORM_WORK

    @cached_property
    def _W_is_diagonal(self):
        # Structural zeros (W's entries are expanded): no assumption queries.
        W = self.hessian
        return all(W[i, j] == 0 for i in range(W.rows) for j in range(W.cols) if i != j)

    def _solve_W(self, rhs: sp.Matrix) -> sp.Matrix:
        """W^{-1} rhs by a linear solve (no symbolic inverse)."""
        W = self.hessian
        if self._W_is_diagonal:
            return sp.Matrix(rhs.rows, rhs.cols, lambda i, j: rhs[i, j] / W[i, i])
        return solve_linear(W, rhs, simplify=None)

    @cached_property
    def forcing(self) -> sp.Matrix:
        """F_B = dL/dq^B - (d2L/dq^C dv^B) v^C + Q_B, shape (n, 1).

        Q_B are the system's generalized forces (``System.generalized_forces``:
        applied forces and -dR/dv of a dissipation function), so every field built
        from F (ξ_L, P(ξ_L), the multipliers, the tangency equations, the generated
        code) is the forced one: ξ_L + F^v with F^v = W^{AB} Q_B ∂/∂v^A.

        Fast path (L quadratic in v), collected by velocity monomial::

            F_B = 1/2 d_B W_AC v^A v^C - d_C W_BA v^A v^C
                  + (d_B b_A - d_A b_B) v^A - d_B V (+ Q_B)
        """
        if self._parts is None:
            L = self.system.lagrangian
            dLdq = sp.Matrix([sp.diff(L, q) for q in self.system.coordinates])
            free = dLdq - self.mixed_hessian * self._v
        else:
            free = self._quadratic_forcing()
        t = getattr(self.system, "time", None)
        if t is not None and t in self.system.lagrangian.free_symbols:
            # d/dt(dL/dv) has the term d2L/dv dt when L depends on t (DESIGN.md §2)
            free -= sp.Matrix([sp.diff(p, t) for p in self.momenta])
        if self.system.has_forces:
            return free + self.system.generalized_forces
        return free

    def _quadratic_forcing(self) -> sp.Matrix:
        n, v, half = self.n, self.system.velocities, sp.Rational(1, 2)
        # quad[B][(A, C)]: summands of the coefficient of v^A v^C (A <= C) in F_B
        quad: list[dict] = [dict() for _ in range(n)]
        lin: list[dict] = [dict() for _ in range(n)]

        def put(table, key, value):
            table.setdefault(key, []).append(value)

        for (P, Q), dW in self._dW.items():
            for B, d in dW.items():
                # 1/2 d_B W_AC v^A v^C: (P, Q) and (Q, P) for P != Q
                put(quad[B], (P, Q), d if P != Q else half * d)
                # - d_C W_{B'A} v^A v^C with C = B, {B', A} = {P, Q}
                put(quad[P], tuple(sorted((Q, B))), -d)
                if P != Q:
                    put(quad[Q], tuple(sorted((P, B))), -d)
        for A, db in self._db.items():
            for B, d in db.items():
                put(lin[B], A, d)     # d_B b_A v^A in F_B
                put(lin[A], B, -d)    # -d_A' b_B' v^A' in F_B' (B' = A, A' = B)
        dV = _coordinate_derivatives(self._parts.V, self._qidx)
        out = []
        for B in range(n):
            terms = [sp.Add(*c) * v[A] * v[C] for (A, C), c in sorted(quad[B].items())]
            terms += [sp.Add(*c) * v[A] for A, c in sorted(lin[B].items())]
            if B in dV:
                terms.append(-dV[B])
            out.append(sp.Add(*terms))
        return sp.Matrix(out)

    @cached_property
    def drift(self) -> sp.Matrix:
        """(d phi_i / d q^A) v^A + d phi_i / dt, shape (m, 1) (term by term, only by the q a
        term has; the time's term when phi_i depends on t, DESIGN.md §2), so that
        d/dt phi_i = drift_i + mu_i . a along a motion."""
        sysm = self.system
        if not sysm.phi:
            return sp.zeros(0, 1)
        v = sysm.velocities
        if not self.fast:
            drift = sp.Matrix([
                sum((sp.diff(f, q) * w for q, w in zip(sysm.coordinates, v)), sp.S.Zero)
                for f in sysm.phi])
        else:
            drift = sp.Matrix([
                sp.Add(*[d * v[A] for A, d in
                         sorted(_coordinate_derivatives(f, self._qidx).items())])
                for f in sysm.phi])
        t = getattr(sysm, "time", None)
        if t is not None:
            drift += sp.Matrix([sp.diff(f, t) for f in sysm.phi])
        return drift

    @cached_property
    def ingredients(self) -> DynamicsIngredients:
        """W, forcing, mu and drift: what numeric evaluation solves with."""
        return DynamicsIngredients(self.hessian, self.forcing, self.system.mu, self.drift)

    # --------------------------------------------------- Euler-Lagrange field
    @cached_property
    def accelerations(self) -> sp.Matrix:
        """xi^A = W^{AB} F_B: the free accelerations, shape (n, 1)."""
        return self._solve_W(self.forcing)

    @cached_property
    def euler_lagrange_field(self) -> sp.Matrix:
        """xi_L = v^A d/dq^A + xi^A d/dv^A (solution of i_X omega_L = dE_L - Q_A dq^A).

        With forces this is the forced field ξ_L + F^v (``System.generalized_forces``).
        """
        return sp.Matrix.vstack(self._v, self.accelerations)

    # ------------------------------------------- inverse-free (scaled) fields
    @cached_property
    def scaled_inverse(self) -> ScaledInverse:
        """δ W⁻¹ as diagonal blocks of polynomial entries (:mod:`nhham.lagrangian.adjugate`).

        δ (``field_scale``) is 1 when W does not depend on the state, else the lcm of
        the determinants of the state-dependent diagonal blocks of W.
        """
        return scaled_inverse(self.hessian, self.state)

    @property
    def field_scale(self) -> sp.Expr:
        """δ, the factor of the scaled fields (nonzero wherever W is regular)."""
        return self.scaled_inverse.scale

    @cached_property
    def scaled_euler_lagrange_field(self) -> sp.Matrix:
        """ξ̃ = δ ξ_L = (δ v, δ W⁻¹ F) with polynomial entries (no division).

        Used by the constraint algorithm instead of ξ_L: the tangency condition
        ξ̃(χ) + λ^i Z̃_i(χ) = 0 is δ times ξ_L(χ) + λ^i Z_i(χ) = 0.
        """
        S = self.scaled_inverse
        return sp.Matrix.vstack((S.scale * self._v).applyfunc(sp.expand),
                                S.apply(self.forcing))

    @cached_property
    def scaled_vertical_fields(self) -> sp.Matrix:
        """Z̃_i = δ Z_i = −δ W^{AB} μ_iB ∂/∂v^A as rows (m x 2n), polynomial entries."""
        m, n = self.m, self.n
        if m == 0:
            return sp.zeros(0, 2 * n)
        return sp.Matrix.hstack(sp.zeros(m, n), -self.scaled_inverse.apply(self.system.mu.T).T)

    def gradient(self, f) -> sp.Matrix:
        """df as a 2n-vector (d/dq, d/dv)."""
        return sp.Matrix([sp.diff(f, s) for s in self.system.state])

    def apply(self, field: sp.Matrix, f) -> sp.Expr:
        """X(f) = df(X) for a vector field X given as a 2n-vector."""
        return (self.gradient(f).T * field)[0]

    def hamiltonian_field(self, f) -> sp.Matrix:
        """X_f with i_{X_f} omega_L = df, shape (2n, 1).

        X_f = (W^{-1} f_v, -W^{-1} f_q - W^{-1} A W^{-1} f_v) with A = M - M^T.
        """
        n = self.n
        grad = self.gradient(f)
        fq, fv = grad[:n, 0], grad[n:, 0]
        a = self._solve_W(fv)
        A = self.mixed_hessian - self.mixed_hessian.T
        return sp.Matrix.vstack(a, -self._solve_W(fq + A * a))

    def bracket(self, f, g) -> sp.Expr:
        """{f, g}_L = omega_L(X_f, X_g); so that xi_L(f) = {f, E_L}_L.

        Computed as f_q . W^{-1} g_v - W^{-1} f_v . g_q - (W^{-1} f_v)^T A (W^{-1} g_v).
        """
        n = self.n
        gf, gg = self.gradient(f), self.gradient(g)
        a = self._solve_W(gf[n:, 0])
        b = self._solve_W(gg[n:, 0])
        A = self.mixed_hessian - self.mixed_hessian.T
        return sp.expand((gf[:n, 0].T * b)[0] - (a.T * gg[:n, 0])[0] - (a.T * A * b)[0])

    # -------------------------------------------------------- constraints
    @cached_property
    def constraint_gradients(self) -> sp.Matrix:
        """d phi_i as rows, shape (m, 2n)."""
        if not self.system.phi:
            return sp.zeros(0, 2 * self.n)
        return sp.Matrix([self.gradient(f).T for f in self.system.phi])

    @cached_property
    def _W_inv_mu_T(self) -> sp.Matrix:
        return self._solve_W(self.system.mu.T)

    @cached_property
    def vertical_fields(self) -> sp.Matrix:
        """Z_i with i_{Z_i} omega_L = tau*mu_i, as rows: Z_i = -W^{AB} mu_iB d/dv^A.

        Shape (m, 2n); the q-components are zero.
        """
        m, n = self.m, self.n
        return sp.Matrix.hstack(sp.zeros(m, n), -self._W_inv_mu_T.T)

    @cached_property
    def constraint_matrix(self) -> sp.Matrix:
        """C_ij = Z_i(phi_j) = -(mu W^{-1} mu^T)_ij, shape (m, m)."""
        return -(self.system.mu * self._W_inv_mu_T)

    @cached_property
    def constraint_derivatives(self) -> sp.Matrix:
        """xi_L(phi_i) (= {phi_i, E_L}_L without forces), shape (m, 1)."""
        ing = self.ingredients
        return ing.drift + ing.mu * self.accelerations

    @cached_property
    def projection(self) -> Projection:
        """The §4 projection of ξ_L by Z_i and dφ_i (:class:`~nhham.lagrangian.projection.
        Projection`): C = −μ W⁻¹ μᵀ and ξ_L(φ) from the ingredients, solves without
        cancellation, refused beyond the closed-form size unless ``closed_form``."""
        return Projection(lambda: self.euler_lagrange_field,
                          self.vertical_fields, self.constraint_gradients,
                          matrix=self.constraint_matrix,
                          derivatives=lambda: self.constraint_derivatives,
                          solve=_solve_unsimplified,
                          owner=None if self.closed_form else "lagrangian_geometry")

    @property
    def multipliers(self) -> sp.Matrix:
        """lambda^j = -C^{ij} xi_L(phi_i), from a solve with C^T (size m)."""
        return self.projection.multipliers

    @cached_property
    def multiplier_symbols(self) -> tuple[sp.Symbol, ...]:
        """``lambda_1 .. lambda_m``."""
        return tuple(multiplier_symbol(i + 1) for i in range(self.m))

    @property
    def projected_field(self) -> sp.Matrix:
        """P(xi_L) = xi_L - C^{ij} xi_L(phi_i) Z_j = xi_L + lambda^j Z_j."""
        return self.projection.projected_field

    @property
    def projector_Q(self) -> sp.Matrix:
        """Q = C^{ij} Z_j (x) d phi_i as a 2n x 2n matrix: Z^T C^{-T} dphi."""
        return self.projection.projector_Q

    @property
    def projector_P(self) -> sp.Matrix:
        """P = id - Q (P^2 = P); P(xi_L) is the constrained dynamics."""
        return self.projection.projector_P

    def project(self, X) -> sp.Matrix:
        """P(X) for a field X on TQ (2n-vector), each entry cancelled."""
        return self.projection.project(X)

    @cached_property
    def acceleration_symbols(self) -> tuple[sp.Symbol, ...]:
        """``<q>_ddot`` for every coordinate."""
        return tuple(acceleration_symbol(q) for q in self.system.coordinates)

    @cached_property
    def equations_of_motion(self) -> tuple[sp.Expr, ...]:
        """d/dt(dL/dv^A) - dL/dq^A + lambda^i mu_iA (each = 0).

        In the acceleration symbols ``<q>_ddot`` and multiplier symbols
        ``lambda_i``; d/dt(dL/dv) = W a + M v.
        """
        a = sp.Matrix(self.acceleration_symbols)
        lam = sp.Matrix(self.multiplier_symbols)
        eq = self.hessian * a - self.forcing
        if self.m:
            eq += self.system.mu.T * lam
        return tuple(sp.expand(e) for e in eq)

    @cached_property
    def modified_lagrangian(self) -> sp.Expr:
        """The paper's Section 4 Lagrangian 𝕃 = L - Lambda^i g_i.

        Lambda^i are the multipliers of the complete lifts g_i^c (the first
        len(holonomic) constraints); Z = L when there are no holonomic ones.
        """
        k = len(self.system.holonomic)
        lam = self.multipliers
        return self.system.lagrangian - sum(
            (lam[i] * g for i, g in enumerate(self.system.holonomic)), sp.S.Zero) if k else \
            self.system.lagrangian

    # -------------------------------------------------------------- on M_1
    @cached_property
    def M1(self) -> Submanifold:
        """M_1 = {phi_i = 0, g = 0} with this geometry's precision settings."""
        return Submanifold(self.system, self.system.holonomic + self.system.phi,
                           precision=self.precision, samples=self.samples, seed=self.seed)


def _solve_unsimplified(A: sp.Matrix, B: sp.Matrix) -> sp.Matrix:
    """A⁻¹ B without cancelling the entries (the closed forms of TQ are cancelled by
    whoever prints them)."""
    return solve_linear(A, B, simplify=None)


def _coordinate_derivatives(expr, qidx) -> dict:
    """{B: d expr / d q^B} for the coordinates expr depends on, nonzero only.

    Term by term, each term differentiated only by the coordinates it
    contains (no derivative of a term by a symbol it lacks).
    """
    parts: dict = {}
    for term in sp.Add.make_args(expr):
        for q in term.free_symbols & qidx.keys():
            d = derivative(term, q)
            if d != 0:
                parts.setdefault(qidx[q], []).append(d)
    out = {}
    for B, ds in parts.items():
        d = sp.Add(*ds)
        if d != 0:
            out[B] = d
    return out
