"""The Hamiltonian side (paper Section 6): constrained dynamics on T*Q.

Conventions (``DESIGN.md`` §2): H = E_L o Leg^{-1}; omega_Q = dq^A ^ dp_A;
{f, g} = df/dq dg/dp - df/dp dg/dq; X_H(f) = {f, H}, so X_H = (dH/dp, -dH/dq);
constraints phi_i^H = phi_i o Leg^{-1}; vertical fields Z_i^H = -mu_iA d/dp_A
(i_{Z_i^H} omega_Q = pi^* mu_i); C^H_ij = Z_i^H(phi_j^H); multipliers
lambda^j = -(C^H)^{ij} X_H(phi_i^H); projected field
X = X_H - (C^H)^{ij} X_H(phi_i^H) Z_j^H = X_H + lambda^j Z_j^H, i.e.

    dq/dt = dH/dp,   dp/dt = -dH/dq - lambda^i mu_i.

Fields on T*Q are columns of length 2n in the order (q, p); families of
fields (vertical fields) are matrices whose row i is the i-th field.

Two layers, both lazy:

* symbolic (:class:`HamiltonianSide` attributes): needs an exact Legendre
  inverse; C^H is solved with, never inverted symbolically;
* numeric (:attr:`HamiltonianSide.numeric`): evaluates every object at a
  point of T*Q from symbolic *derivatives* only (no symbolic inverse of W):
  v = Leg^{-1}(q, p) numerically, and for a function chi(q, v) on TQ the
  gradient of chi o Leg^{-1} by the chain rule dv = W^{-1}(dp - M dq). This
  is what large systems (the N-link snake) use.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Sequence

import numpy as np
import sympy as sp

from nhham.hamiltonian.brackets import BracketAlgebra, numeric_bracket_matrix
from nhham.hamiltonian.legendre import LegendreMap
from nhham.lagrangian.algebra import cancel
from nhham.lagrangian.engine import Policy, policy_of
from nhham.lagrangian.geometry import ConstraintMatrixRank, lagrangian_geometry
from nhham.lagrangian.projection import Projection, time_rates
from nhham.lagrangian.submanifold import Submanifold
from nhham.settings import SEED
from nhham.system.evaluation import Backend, Lambdified
from nhham.system.expressions import derivative

__all__ = [
    "HamiltonianSide",
    "hamiltonian_side",
    "NumericHamiltonian",
    "HamiltonianPoint",
]


def hamiltonian_side(system, precision: int | None = None, samples: int = 6,
                     seed: int = SEED, exact: bool = True,
                     closed_form: bool = False, *,
                     policy: Policy | None = None) -> "HamiltonianSide":
    """The Hamiltonian-side objects of ``system`` (frozen, lazy).

    Parameters
    ----------
    system : nhham.System
    precision, samples, seed, exact : optional
        Deprecated (a ``DeprecationWarning``; removed in the next release): give them in
        ``policy``.
    policy : nhham.Policy, optional
        The decision settings on T*Q: ``precision`` (None: float64; int: mpmath digits),
        ``samples`` and ``seed`` of sampled decisions, ``exact`` (False: decisions on
        submanifolds of T*Q are taken at sample points only).
    closed_form : bool, optional
        As for :func:`nhham.lagrangian.geometry.lagrangian_geometry`: True forms the
        closed forms that need a symbolic solve with C^H whatever their size.

    Examples
    --------
    The rolling disk's C^H is its C (the same at every point: C depends on q only), so at
    theta = 0 with m = 1, R = 1, I2 = 0.5 it is diag(-1/m - R**2/I2, -1/m) = diag(-3, -1).

    >>> from nhham import hamiltonian_side, models
    >>> disk = models.rolling_disk()
    >>> side = hamiltonian_side(disk)
    >>> side.state
    (x, y, theta, phi, p_x, p_y, p_theta, p_phi)
    >>> side.constraint_matrix.subs(disk.parameter_values).subs("theta", 0)
    Matrix([
    [-3.0,    0],
    [   0, -1.0]])
    """
    policy = policy_of(policy, "hamiltonian_side", precision=precision, samples=samples,
                       seed=seed, exact=exact)
    return HamiltonianSide(system, precision=policy.precision, samples=policy.samples,
                           seed=policy.seed, exact=policy.exact, closed_form=closed_form)


@dataclass(frozen=True, eq=False, repr=False)
class HamiltonianSide(ConstraintMatrixRank):
    """Constrained Hamiltonian dynamics of a system on T*Q (frozen, lazy).

    It answers the questions of :class:`nhham.lagrangian.geometry.LagrangianGeometry`
    under the same names, on T*Q: ``state`` (q, p), ``energy`` (H), ``vertical_fields``
    (Z_i^H), ``constraint_gradients``, ``constraint_matrix`` (C^H),
    ``constraint_derivatives`` (X_H(phi_i^H)), ``multipliers``, ``multiplier_symbols``,
    ``projected_field`` (P(X_H)), ``projector_Q``, ``projector_P``, ``M1``,
    ``constraint_rank`` and ``regular`` (C^H regular on M_1, as
    :class:`~nhham.lagrangian.geometry.ConstraintMatrixRank` says for both sides); the
    constraint functions are ``constraints`` (phi^H = phi o Leg^-1).

    Examples
    --------
    A particle on y' = x x' (p = v): the multiplier is the Lagrangian one,
    -x'^2/(1 + x^2), written in p.

    >>> from nhham import System, hamiltonian_side
    >>> s = System(["x", "y"], "(x_dot**2 + y_dot**2)/2", constraints=["y_dot - x*x_dot"])
    >>> side = hamiltonian_side(s)
    >>> side.constraints, side.constraint_matrix, side.regular
    ((-p_x*x + p_y,), Matrix([[-x**2 - 1]]), True)
    >>> side.multipliers
    Matrix([[-p_x**2/(x**2 + 1)]])
    """

    exact: bool = True
    closed_form: bool = False

    # --------------------------------------------------------------- basics

    @cached_property
    def legendre(self) -> LegendreMap:
        return LegendreMap(self.system)

    @property
    def coordinates(self) -> tuple:
        return self.legendre.coordinates

    @property
    def momenta(self) -> tuple:
        """Momentum symbols p_A (``p_<q>``)."""
        return self.legendre.momentum_symbols

    @property
    def variables(self) -> tuple:
        """(q^1..q^n, p_1..p_n)."""
        return self.coordinates + self.momenta

    @property
    def state(self) -> tuple:
        """The coordinates of T*Q, (q, p): ``variables`` under the name the Lagrangian
        side uses for (q, v)."""
        return self.variables

    @property
    def multiplier_symbols(self) -> tuple:
        """lambda_1..lambda_m, the same symbols as on the Lagrangian side."""
        from nhham.system.naming import multiplier_symbol

        return tuple(multiplier_symbol(i + 1) for i in range(self.m))

    @cached_property
    def symbolic_affordable(self) -> bool:
        """True when symbolic work on T*Q is cheap: an exact Legendre inverse and W^-1
        small in closed form (``LagrangianGeometry.closed_form_affordable``: W diagonal or
        free of the state, or its scaled inverse small: the size of the work, not n).

        A large q-dependent, non-diagonal W (the N-link snake, the rolling ball, a rigid
        body in Euler angles) makes W^{-1} and everything transported by it large; the
        "auto" methods of the classification and the cross-check then go to points.
        """
        # The cheap test on W first: the exact-inverse test builds polynomials.
        return lagrangian_geometry(self.system).closed_form_affordable \
            and self.legendre.has_exact_inverse

    @cached_property
    def algebra(self) -> BracketAlgebra:
        """Canonical brackets on T*Q (cached)."""
        return BracketAlgebra(self.coordinates, self.momenta)

    @cached_property
    def numeric(self) -> "NumericHamiltonian":
        """Point evaluation without symbolic inverses (see the module docstring)."""
        return NumericHamiltonian(self)

    # ------------------------------------------------------------ H and X_H
    @cached_property
    def H(self) -> sp.Expr:
        """H = E_L o Leg^{-1} in (q, p)."""
        return self.legendre.hamiltonian

    @property
    def energy(self) -> sp.Expr:
        """The energy function on T*Q: H (as ``energy`` is E_L on the Lagrangian side)."""
        return self.H

    @cached_property
    def X_H(self) -> sp.Matrix:
        """X_H = (dH/dp, -dH/dq) (+ F^V with forces), shape (2n, 1).

        With forces (``System.generalized_forces``) this is the forced field
        X_H + F^V, F^V = Q_A(q, Leg^-1(q, p)) d/dp_A (i_{F^V} omega_Q = -Q_A dq^A), the
        image of the Lagrangian side's ξ_L + F^v under Leg: every object built from
        it (the multipliers, the projected field, the constraint algorithm on T*Q)
        is the forced one.
        """
        field = self.algebra.hamiltonian_field(self.H)
        if self.system.has_forces:
            n = self.system.n
            Q = [self.legendre.transport(f) for f in self.system.generalized_forces]
            field = field + sp.Matrix.vstack(sp.zeros(n, 1), sp.Matrix(Q))
        return field.applyfunc(cancel)

    # ------------------------------------------------------------ constraints
    @property
    def holonomic(self) -> tuple:
        """Holonomic constraints g(q) (functions on Q, the same on T*Q)."""
        return tuple(self.system.holonomic)

    @cached_property
    def constraints(self) -> tuple:
        """phi_i^H = phi_i o Leg^{-1}, in the order of ``system.phi``."""
        return tuple(self.legendre.transport(f) for f in self.system.phi)

    @cached_property
    def vertical_fields(self) -> sp.Matrix:
        """Z_i^H = -mu_iA d/dp_A as rows, shape (m, 2n); q-components zero.

        For a nonlinear (Chetaev) constraint mu = d phi/d v is taken at Leg^-1(q, p)."""
        mu = self.system.mu
        if not self.system.is_affine:
            mu = mu.applyfunc(self.legendre.transport)
        return sp.Matrix.hstack(sp.zeros(self.m, self.n), -mu)

    @cached_property
    def constraint_gradients(self) -> sp.Matrix:
        """d phi_i^H as rows in the basis (dq, dp), shape (m, 2n)."""
        if not self.m:
            return sp.zeros(0, 2 * self.n)
        return sp.Matrix([[sp.diff(f, z) for z in self.variables] for f in self.constraints])

    @cached_property
    def projection(self) -> Projection:
        """The §4 projection of X_H by Z_i^H and d phi_i^H
        (:class:`~nhham.lagrangian.projection.Projection`), every entry cancelled; refused
        beyond the closed-form size unless ``closed_form``."""
        return Projection(lambda: self.X_H, self.vertical_fields, self.constraint_gradients,
                          derivatives=lambda: self.constraint_derivatives, normal=cancel,
                          owner=None if self.closed_form else "hamiltonian_side")

    @property
    def constraint_matrix(self) -> sp.Matrix:
        """C^H_ij = Z_i^H(phi_j^H) = -mu_iA d phi_j^H / d p_A, shape (m, m)."""
        if not self.m:
            return sp.zeros(0, 0)
        return self.projection.constraint_matrix

    @cached_property
    def constraint_derivatives(self) -> sp.Matrix:
        """X_H(phi_i^H) = {phi_i^H, H} (+ F^V(phi_i^H) with forces, + d phi_i^H/dt when
        the system depends on the time: the consistency condition on R x T*Q), shape
        (m, 1)."""
        if not self.m:
            return sp.zeros(0, 1)
        if self.system.has_forces:
            out = (self.constraint_gradients * self.X_H).applyfunc(cancel)
        else:
            out = sp.Matrix([self.algebra.bracket(f, self.H) for f in self.constraints])
        rates = time_rates(self.constraints, self.system.time)
        return out if rates is None else (out + rates).applyfunc(cancel)

    @property
    def multipliers(self) -> sp.Matrix:
        """lambda^j = -(C^H)^{ij} X_H(phi_i^H): a solve with (C^H)^T, shape (m, 1).

        Defined where C^H is invertible (the regular case); singular systems
        go through :meth:`analysis`.
        """
        return self.projection.multipliers

    @property
    def projected_field(self) -> sp.Matrix:
        """X = X_H + lambda^j Z_j^H, shape (2n, 1)."""
        return self.projection.projected_field

    @property
    def projector_Q(self) -> sp.Matrix:
        """Q = (C^H)^{ij} Z_j^H (x) d phi_i^H as a (2n, 2n) matrix acting on columns."""
        return self.projection.projector_Q

    @property
    def projector_P(self) -> sp.Matrix:
        """P = id - Q on T*Q; P(X_H) is the projected field."""
        return self.projection.projector_P

    def project(self, X) -> sp.Matrix:
        """P(X) for a field X on T*Q (2n-vector), each entry cancelled."""
        return self.projection.project(X)

    @cached_property
    def equations_of_motion(self) -> tuple:
        """(dq/dt, dp/dt) = (dH/dp, -dH/dq - lambda^i mu_i) as a 2n-tuple of expressions."""
        return tuple(self.projected_field)

    # --------------------------------------------------------------- on M_1
    @cached_property
    def M1(self) -> Submanifold:
        """M_1 on T*Q = {g = 0, phi^H = 0} (decisions with this side's precision)."""
        return self.submanifold(self.holonomic + self.constraints)

    def submanifold(self, equations: Sequence) -> Submanifold:
        """A submanifold of T*Q given by equations in (q, p)."""
        return Submanifold(self.system, tuple(equations), precision=self.precision,
                           samples=self.samples, seed=self.seed, fibre=self.momenta,
                           exact=self.exact)

    # ------------------------------------------------- the constraint algorithm
    def analysis(self, max_stages: int | None = None):
        """The constraint algorithm run on T*Q (X_H, Z^H, phi^H, M_k in T*Q).

        Primary constraints (in this order, as on TQ): the holonomic g, then
        phi^H (complete lifts first); multipliers ``lambda_i`` as on TQ.

        Parameters
        ----------
        max_stages : int, optional
            Default 2n, as on the Lagrangian side.

        Returns
        -------
        nhham.algorithm.AlgorithmRun
            :func:`nhham.hamiltonian.crosscheck.cross_check` compares its stages, ranks
            and multipliers with the Lagrangian run (checked, not assumed).
        """
        return self._analysis(2 * self.n if max_stages is None else int(max_stages))

    @cached_property
    def _analysis_cache(self) -> dict:
        return {}

    def _analysis(self, max_stages):
        if max_stages not in self._analysis_cache:
            self._analysis_cache[max_stages] = _hamiltonian_analysis(self, max_stages)
        return self._analysis_cache[max_stages]


def _hamiltonian_analysis(side: HamiltonianSide, max_stages: int):
    from nhham.lagrangian.algorithm import run_algorithm

    return run_algorithm(**_algorithm_arguments(side, max_stages))


def _algorithm_arguments(side: HamiltonianSide, max_stages: int) -> dict:
    """Keyword arguments of run_algorithm for the T*Q side (kept in one place)."""
    from nhham.system.naming import multiplier_symbol

    sysm = side.system
    labels = sysm.m1_labels  # as analyze_constraints labels them
    return dict(
        base_field=side.X_H,
        vertical_fields=side.vertical_fields,
        primary=side.holonomic + side.constraints,
        labels=labels,
        manifold_factory=side.submanifold,
        max_stages=max_stages,
        multiplier_symbols=[multiplier_symbol(i + 1) for i in range(side.m)],
        variables=side.variables,
        time=sysm.time,
    )


# ======================================================================
# Numeric layer
# ======================================================================
@dataclass(frozen=True)
class HamiltonianPoint:
    """Hamiltonian objects evaluated at one point of T*Q.

    Attributes
    ----------
    q, p, v : array, shape (n,)
        The point, and v = Leg^{-1}(q, p).
    params : list
        Parameter values in ``system.parameters`` order.
    W, M : array, shape (n, n)
        d p / d v and d p / d q at (q, v).
    Hq, Hp : array, shape (n,)
        Gradient of H; with forces Hq is dH/dq - Q (so that X_H = (Hp, -Hq) is the
        forced field X_H + F^V).
    phi : array, shape (m,)
        phi_i^H.
    Phiq, Phip : array, shape (m, n)
        Gradients of the phi_i^H.
    mu : array, shape (m, n)
    round_trip : float
        |Leg(Leg^{-1}(q, p)) - p|: how well the numeric inverse did.
    """

    q: np.ndarray
    p: np.ndarray
    v: np.ndarray
    params: list
    W: np.ndarray
    M: np.ndarray
    Hq: np.ndarray
    Hp: np.ndarray
    phi: np.ndarray
    Phiq: np.ndarray
    Phip: np.ndarray
    mu: np.ndarray
    round_trip: float
    phi_t: object = None  # d phi_i/dt at (q, v) of a time-dependent system, else None

    @property
    def X_H(self) -> np.ndarray:
        """(dH/dp, -dH/dq), shape (2n,)."""
        return np.concatenate([self.Hp, -self.Hq])

    @property
    def C(self) -> np.ndarray:
        """C^H_ij = -mu_i . d phi_j / dp, shape (m, m)."""
        return -(self.mu @ self.Phip.T)

    @property
    def X_H_phi(self) -> np.ndarray:
        """X_H(phi_i^H) = {phi_i^H, H} (+ d phi_i^H/dt), shape (m,)."""
        out = self.Phiq @ self.Hp - self.Phip @ self.Hq
        return out if self.phi_t is None else out + self.phi_t

    def vertical(self) -> np.ndarray:
        """Z_i^H as rows (0, -mu_i), shape (m, 2n)."""
        return np.concatenate([self.mu * 0, -self.mu], axis=1)


class NumericHamiltonian:
    """Evaluate the Hamiltonian side at points without symbolic inverses.

    All functions of T*Q are handled as functions chi(q, v) on TQ composed
    with Leg^{-1}: values and (q, v)-gradients are compiled once, and the
    (q, p)-gradient at a point is d chi/dp = chi_v W^{-1},
    d chi/dq = chi_q - chi_v W^{-1} M (chain rule through dv = W^{-1}(dp - M dq)).
    """

    def __init__(self, side: HamiltonianSide):
        self.side = side
        sysm = side.system
        self.args = tuple(sysm.coordinates) + tuple(sysm.velocities) + tuple(sysm.parameters)
        n, m = sysm.n, sysm.m
        leg = side.legendre
        self._W = Lambdified(self.args, list(leg.hessian), (n, n))
        self._M = Lambdified(self.args, list(leg.mixed_hessian), (n, n))
        self._p = Lambdified(self.args, list(leg.momenta), (n,))
        self._mu = Lambdified(self.args, list(sysm.mu), (m, n))
        # H = E_L o Leg^-1 has dH/dp = v and dH/dq = -dL/dq (at Leg^-1(q, p)): only
        # dL/dq is compiled (differentiating E_L = v . p - L cost twice as much).
        # With forces -Hq carries Q too (dp/dt = -dH/dq + Q before the constraints).
        lq = [derivative(sysm.lagrangian, s) for s in sysm.coordinates]
        if sysm.has_forces:
            lq = [a + b for a, b in zip(lq, sysm.generalized_forces)]
        self._Lq = Lambdified(self.args, lq, (n,))
        self._phi = self.functions(list(sysm.phi))
        self._functions: dict = {}
        # d phi/dt at fixed (q, v); d phi^H/dt at fixed (q, p) subtracts Phip L_vt where
        # L depends on t (point())
        self._phit = None if sysm.time is None else Lambdified(
            self.args, [sp.diff(f, sysm.time) for f in sysm.phi], (m,))
        # d2L/dt dv where L depends on t (Leg^{-1} then moves with t)
        self._Lvt = None if not sysm.lagrangian_depends_on_time else Lambdified(
            self.args, [sp.diff(sysm.lagrangian, v, sysm.time) for v in sysm.velocities],
            (n,))

    def functions(self, exprs: Sequence) -> "TransportedFunctions":
        """Compiled values and gradients of functions chi(q, v) (cached by tuple)."""
        key = tuple(sp.sympify(e) for e in exprs)
        cache = self.__dict__.setdefault("_functions", {})
        if key not in cache:
            cache[key] = TransportedFunctions(self.args, key, self.side.system)
        return cache[key]

    def momenta_at(self, backend: Backend, q, v, params) -> np.ndarray:
        """p = dL/dv(q, v)."""
        return self._p(backend, list(q) + list(v) + list(params))

    def inverse_at(self, backend: Backend, q, p, params) -> np.ndarray:
        """v = Leg^{-1}(q, p) numerically (one linear solve for quadratic L)."""
        leg = self.side.legendre
        if leg.is_quadratic:
            zero = [backend.scalar(0)] * len(q)
            a = self._p(backend, list(q) + zero + list(params))
            W = self._W(backend, list(q) + zero + list(params))
            return backend.solve(W, backend.vector(p) - a)
        return leg.numeric_inverse(q, p, params=params, precision=backend.precision)

    def point(self, backend: Backend, q, p, params) -> HamiltonianPoint:
        """Everything the projected field needs at (q, p)."""
        q, p = backend.vector(q), backend.vector(p)
        params = list(backend.vector(params)) if len(params) else []
        v = self.inverse_at(backend, q, p, params)
        vals = list(q) + list(v) + list(params)
        W, M = self._W(backend, vals), self._M(backend, vals)
        round_trip = float(backend.norm(self._p(backend, vals) - p))
        Hq, Hp = -self._Lq(backend, vals), v
        phi, Phiq, Phip = self._phi.gradients(backend, vals, W, M)
        mu = self._mu(backend, vals)
        phit = None if self._phit is None else self._phit(backend, vals)
        if self._Lvt is not None:  # d phi^H/dt at fixed p: Leg^{-1} moves (W dv/dt = -L_vt)
            phit = phit - Phip @ self._Lvt(backend, vals)
        return HamiltonianPoint(q, p, v, params, W, M, Hq, Hp, phi, Phiq, Phip, mu,
                                round_trip, phit)

    def point_from_tq(self, backend: Backend, x: dict) -> HamiltonianPoint:
        """The point Leg(x) for x a dict (coordinates, velocities, parameters) on TQ.

        p is computed from x and then inverted again, so the round trip is
        part of every evaluation.
        """
        sysm = self.side.system
        q = [x[s] for s in sysm.coordinates]
        v = [x[s] for s in sysm.velocities]
        params = [x[s] for s in sysm.parameters]
        p = self.momenta_at(backend, backend.vector(q), backend.vector(v),
                            backend.vector(params) if params else [])
        return self.point(backend, q, p, params)

    def projected_field(self, backend: Backend, pt: HamiltonianPoint, rank_tol=None):
        """X = X_H + lambda^j Z_j^H at a point; returns (X, lambda).

        Raises
        ------
        numpy.linalg.LinAlgError or ZeroDivisionError
            When C^H is singular at the point.
        """
        if not len(pt.phi):
            return pt.X_H, backend.zeros(0)
        lam = -backend.solve(pt.C.T, pt.X_H_phi)
        X = pt.X_H + pt.vertical().T @ lam
        return X, lam

    def gradients(self, backend: Backend, pt: HamiltonianPoint, exprs: Sequence):
        """(values, d/dq, d/dp) of chi o Leg^{-1} for chi(q, v) in ``exprs`` at ``pt``."""
        vals = list(pt.q) + list(pt.v) + list(pt.params)
        return self.functions(exprs).gradients(backend, vals, pt.W, pt.M)

    def time_derivatives(self, backend: Backend, pt: HamiltonianPoint, exprs: Sequence):
        """d/dt of chi o Leg^{-1} at fixed (q, p) for chi(q, v, t) in ``exprs``, shape (k,).

        d chi/dt - d chi/dv W^{-1} d2L/dt dv: Leg^{-1} moves with t where L does
        (p = dL/dv fixed gives W dv/dt = -d2L/dt dv). Zeros for an autonomous system.
        """
        functions = self.functions(exprs)
        if functions.time_derivative is None:
            return backend.zeros(len(exprs))
        vals = list(pt.q) + list(pt.v) + list(pt.params)
        out = functions.time_derivative(backend, vals)
        if self._Lvt is not None:
            _, _, gv = functions.gradients(backend, vals, pt.W, pt.M)
            out = out - gv @ backend.solve(pt.W, self._Lvt(backend, vals))
        return out

    def bracket_matrix(self, backend: Backend, pt: HamiltonianPoint, exprs: Sequence):
        """{chi_a o Leg^{-1}, chi_b o Leg^{-1}} at ``pt``, shape (k, k)."""
        _, Gq, Gp = self.gradients(backend, pt, exprs)
        return numeric_bracket_matrix(Gq, Gp)


class TransportedFunctions:
    """Values and (q, p)-gradients of chi_a o Leg^{-1} for chi_a(q, v) given on TQ."""

    def __init__(self, args, exprs, system):
        n = system.n
        q, v = system.coordinates, system.velocities
        self.exprs = exprs
        k = len(exprs)
        self._val = Lambdified(args, list(exprs), (k,))
        #: d chi/dt at fixed (q, v), or None for an autonomous system
        self.time_derivative = None if system.time is None else Lambdified(
            args, [sp.diff(e, system.time) for e in exprs], (k,))
        self._dq = Lambdified(args, [derivative(e, s) for e in exprs for s in q], (k, n))
        self._dv = Lambdified(args, [derivative(e, s) for e in exprs for s in v], (k, n))

    def gradients(self, backend: Backend, vals, W, M):
        """(values (k,), d/dq (k, n), d/dp (k, n)) at (q, v) with W, M given there."""
        val = self._val(backend, vals)
        gq = self._dq(backend, vals)
        gv = self._dv(backend, vals)
        if gv.shape[0] == 0:
            return val, gq, gv
        # Y = gv W^{-1} (W symmetric): solve W Y^T = gv^T.
        Y = backend.solve(W, gv.T).T
        return val, gq - Y @ M, Y
