"""The Legendre map Leg : TQ -> T*Q, its inverse, and transport of objects.

Conventions (``DESIGN.md`` §2): Leg(q, v) = (q, p) with p_A = dL/dv^A;
H = E_L o Leg^{-1}; omega_Q = dq^A ^ dp_A. Vectors on TQ are columns in the
order (q, v), on T*Q in the order (q, p); a 2-form is the antisymmetric
matrix Omega with omega(X, Y) = X^T Omega Y.

The inverse v(q, p) is

* ``"linear"`` when L is at most quadratic in v: p = W(q) v + a(q) is solved
  by one linear solve, v = W^{-1} (p - a), written without a symbolic
  inverse of W (an LU solve, or division when W is diagonal);
* ``"closed-form"`` when every p_A depends on v^A alone and sympy solves the
  n one-dimensional equations, keeping the branch that inverts Leg at seeded
  points (a round trip v -> p -> v);
* ``"numeric"`` otherwise: there is no symbolic inverse, and asking for one
  raises :class:`NoClosedFormInverseError` saying so; :meth:`LegendreMap.numeric_inverse`
  solves p = dL/dv(q, v) by Newton's method at given (q, p).

The numeric helpers at the end of the module (lambdify with a float64 or
mpmath backend, dense solves on numpy float or object arrays) are shared by
the Hamiltonian side, the classification and the cross-check.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import sympy as sp

from nhham.errors import ComputationError
from nhham.lagrangian.algebra import cancel
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.progress import part
from nhham.settings import PARAMETER_BOX, SEED
from nhham.system.description import System
from nhham.system.evaluation import Backend, numeric_function
from nhham.system.naming import momentum_symbol

__all__ = ["LegendreMap", "legendre_map", "NoClosedFormInverseError", "canonical_form_matrix"]

# Seed of the round-trip points that pick a branch of a closed-form inverse.
_BRANCH_SEED = SEED


class NoClosedFormInverseError(ComputationError):
    """p = dL/dv cannot be solved for v in closed form: only a numeric inverse exists."""


def legendre_map(system) -> "LegendreMap":
    """The Legendre map of ``system``'s Lagrangian (frozen, lazy).

    Parameters
    ----------
    system : nhham.System

    Returns
    -------
    LegendreMap

    Examples
    --------
    >>> from nhham import legendre_map, models
    >>> legendre_map(models.rolling_disk(symbolic=True)).momenta.T
    Matrix([[m*x_dot, m*y_dot, I1*theta_dot, I2*phi_dot]])
    """
    return LegendreMap(system)


def canonical_form_matrix(n: int) -> sp.Matrix:
    """Omega_Q of omega_Q = dq^A ^ dp_A in the basis (q, p): [[0, I], [-I, 0]], shape (2n, 2n)."""
    return sp.Matrix(sp.BlockMatrix([[sp.zeros(n, n), sp.eye(n)], [-sp.eye(n), sp.zeros(n, n)]]))


@dataclass(frozen=True, eq=False, repr=False)
class LegendreMap:
    """Leg(q, v) = (q, dL/dv) for a regular Lagrangian (frozen; everything lazy).

    Parameters
    ----------
    system : nhham.System

    Attributes
    ----------
    coordinates, velocities : tuple of sympy.Symbol
        q^A and v^A of the system.
    momentum_symbols : tuple of sympy.Symbol
        p_A, named ``p_<q>``.

    Examples
    --------
    >>> from nhham import legendre_map, models
    >>> leg = legendre_map(models.rolling_disk(symbolic=True))
    >>> leg.is_quadratic, leg.inverse
    (True, {x_dot: p_x/m, y_dot: p_y/m, theta_dot: p_theta/I1, phi_dot: p_phi/I2})
    """

    system: System

    def __post_init__(self):
        self.system.require_regular_lagrangian("the inverse Legendre map and H")

    @property
    def coordinates(self) -> tuple:
        return tuple(self.system.coordinates)

    @property
    def velocities(self) -> tuple:
        return tuple(self.system.velocities)

    @cached_property
    def momentum_symbols(self) -> tuple:
        return tuple(momentum_symbol(q) for q in self.system.coordinates)

    def __repr__(self):
        return f"LegendreMap({self.system!r}, inverse={self.inverse_kind!r})"

    @property
    def n(self) -> int:
        return len(self.coordinates)

    # ------------------------------------------------------------ the map
    @cached_property
    def _geometry(self):
        # The fibre derivatives have one home, with its fast path for L quadratic in v;
        # the system's shared geometry, so that a command forms them once.
        return lagrangian_geometry(self.system)

    @cached_property
    def momenta(self) -> sp.Matrix:
        """p_A = dL/dv^A as functions of (q, v), shape (n, 1)."""
        return self._geometry.momenta

    @cached_property
    def hessian(self) -> sp.Matrix:
        """W_AB = d p_A / d v^B, shape (n, n)."""
        return self.system.hessian

    @cached_property
    def mixed_hessian(self) -> sp.Matrix:
        """M_AB = d p_A / d q^B, shape (n, n)."""
        return self._geometry.mixed_hessian

    @cached_property
    def jacobian(self) -> sp.Matrix:
        """d Leg in the bases (q, v) -> (q, p): [[I, 0], [M, W]], shape (2n, 2n)."""
        n = self.n
        return sp.Matrix(sp.BlockMatrix([[sp.eye(n), sp.zeros(n, n)],
                                         [self.mixed_hessian, self.hessian]]))

    @cached_property
    def time_derivative(self) -> sp.Matrix:
        """d Leg/dt at fixed (q, v): (0, d2L/dt dv), shape (2n, 1); zero unless L depends
        on the time t (then Leg moves with t, DESIGN.md §2)."""
        n, system = self.n, self.system
        if not system.lagrangian_depends_on_time:
            return sp.zeros(2 * n, 1)
        return sp.zeros(n, 1).col_join(self.momenta.diff(system.time))

    def flow_map(self, field: sp.Matrix) -> sp.Matrix:
        """d/dt Leg(x(t)) along a motion whose velocity on TQ is ``field``: Leg_* X + d Leg/dt,
        shape (2n, 1). It is :meth:`tangent_map` for an autonomous L; with L in t the
        Hamiltonian field X_H(t) o Leg_t is Leg_* xi_L plus the map's own rate
        (p = dL/dv(q, v, t) changes at fixed (q, v) by d2L/dt dv).
        """
        return self.tangent_map(field) + self.time_derivative

    @cached_property
    def _to_momenta(self) -> dict:
        return dict(zip(self.momentum_symbols, self.momenta))

    # ------------------------------------------------------------ inverse
    @cached_property
    def is_quadratic(self) -> bool:
        """True when L is a polynomial of degree <= 2 in the velocities."""
        if self.system.quadratic_parts is not None:  # read from L's terms: no expansion
            return True
        try:
            poly = sp.Poly(sp.expand(self.system.lagrangian), *self.velocities)
        except sp.PolynomialError:
            return False
        return poly.total_degree() <= 2

    @cached_property
    def _closed_form(self):
        return None if self.is_quadratic else self._closed_form_inverse()

    @property
    def inverse_kind(self) -> str:
        """``"linear"``, ``"closed-form"`` or ``"numeric"`` (see the module docstring).

        Deciding the kind never forms the linear inverse (that is done on
        first use of :attr:`inverse`).
        """
        if self.is_quadratic:
            return "linear"
        return "closed-form" if self._closed_form is not None else "numeric"

    @property
    def has_exact_inverse(self) -> bool:
        """True when v(q, p) is available as expressions."""
        return self.inverse_kind != "numeric"

    @property
    def inverse_statement(self) -> str:
        """One sentence on how Leg is inverted."""
        kind = self.inverse_kind
        if kind == "linear":
            return "L is quadratic in v: v = W^{-1}(p - a(q)) by one linear solve (exact)"
        if kind == "closed-form":
            return ("p_A depends on v^A alone and each equation was solved in closed form; the "
                    "branch was chosen by a round trip at seeded points (exact)")
        return ("p = dL/dv could not be solved for v in closed form: the inverse of the Legendre "
                "map is only available numerically (Newton's method, LegendreMap.numeric_inverse)")

    @cached_property
    def inverse(self) -> dict:
        """v^A(q, p) as ``{v^A: expr}``.

        Raises
        ------
        NoClosedFormInverseError
            When the inverse is only available numerically.
        """
        kind = self.inverse_kind
        if kind == "linear":
            return self._linear_inverse()
        if kind == "closed-form":
            return self._closed_form
        raise NoClosedFormInverseError(
            f"{self.inverse_statement}; H and the fields on T*Q need v(q, p) in closed form: "
            f"the Lagrangian side (derive --side lagrangian, simulate) does not, or write L "
            f"with momenta solvable for the velocities (quadratic in them)", key="lagrangian")

    def _linear_inverse(self) -> dict:
        # v = W^-1 (p - a) = S (p - a) / delta with S = delta W^-1 the fraction-free
        # adjugate of the geometry (one home): no LU solve of nested fractions, whose
        # cancellation grows without bound on a dense trigonometric W (Euler angles).
        zero = {v: 0 for v in self.velocities}
        rhs = sp.Matrix(self.momentum_symbols) - self.momenta.xreplace(zero)
        with part("Legendre inverse v(q, p) by the adjugate of W"):
            S = self._geometry.scaled_inverse
            numerators = S.apply(rhs)
            return {v: cancel(numerators[i] / S.scale) for i, v in enumerate(self.velocities)}

    def _closed_form_inverse(self):
        """Per-component closed-form solve when p_A depends on v^A only."""
        vels = self.velocities
        for A, pA in enumerate(self.momenta):
            if (pA.free_symbols & set(vels)) - {vels[A]}:
                return None
        rng = np.random.default_rng(_BRANCH_SEED)
        checks = self._round_trip_points(rng, 3)
        out = {}
        for A, (v, p, pA) in enumerate(zip(vels, self.momentum_symbols, self.momenta)):
            try:
                candidates = sp.solve(sp.Eq(pA, p), v, dict=False)
            except (NotImplementedError, ValueError, TypeError):
                return None
            chosen = None
            for cand in candidates:
                if all(_close(cand, v, p, pA, pt) for pt in checks):
                    chosen = cand
                    break
            if chosen is None:
                return None
            out[v] = chosen
        return out

    def _round_trip_points(self, rng, count):
        # sympy Floats, not Python floats: xreplace puts a value in as it is, and a
        # momentum that is a bare velocity (p_A = v^A) would come back a float. Each point
        # with its velocities reversed too: a branch that inverts Leg for one sign of v
        # only (the cube root of p = v^3/3 chosen for v < 0) is no inverse.
        pts = []
        for _ in range(count):
            pt = {s: sp.Float(rng.uniform(-0.6, 0.6)) for s in self.coordinates + self.velocities}
            for par in self.system.parameters:
                pt[par] = sp.Float(self.system.parameter_values.get(
                    par, rng.uniform(*PARAMETER_BOX)))
            pts += [pt, {**pt, **{v: -pt[v] for v in self.velocities}}]
        return pts

    # ----------------------------------------------------- numeric inverse
    @cached_property
    def _numeric_fibre(self):
        args = list(self.coordinates) + list(self.velocities) + list(self.system.parameters)
        return {
            "numpy": (numeric_function(args, list(self.momenta)),
                      numeric_function(args, self.hessian.tolist())),
            "mpmath": (numeric_function(args, list(self.momenta), precision=30),
                       numeric_function(args, self.hessian.tolist(), precision=30)),
        }

    def numeric_inverse(self, q, p, params=None, precision: int | None = None,
                        tol: float | None = None, maxiter: int = 50) -> np.ndarray:
        """Solve p = dL/dv(q, v) for v by Newton's method.

        Parameters
        ----------
        q, p : sequence of float, shape (n,)
        params : sequence of float, optional
            Values of ``system.parameters`` in order; default the system's values.
        precision : int or None
            None for float64, an integer for mpmath with that many digits.
        tol : float, optional
            Convergence tolerance on |p - dL/dv| (relative to 1 + |p|);
            default 1e-13 (float64) or 10**(2 - digits).
        maxiter : int

        Returns
        -------
        numpy.ndarray, shape (n,)
            float64, or object array of mpmath.mpf.

        Raises
        ------
        ComputationError
            If Newton's method does not converge (W singular or no solution).
        """
        if params is None:
            params = [self.system.numeric_parameters()[s] for s in self.system.parameters]
        be = Backend(precision)
        F, J = self._numeric_fibre[be.module]
        with be.context():
            q = be.vector(q)
            p = be.vector(p)
            params = list(be.vector(params)) if len(params) else []
            v = be.zeros(self.n)
            if tol is None:
                tol = 1e-13 if precision is None else 10.0 ** (2 - precision)
            tol = be.scalar(tol)
            scale = 1 + be.norm(p)
            for _ in range(maxiter):
                r = be.vector(F(*q, *v, *params)) - p
                if be.norm(r) <= tol * scale:
                    return v
                Wn = be.matrix(J(*q, *v, *params))
                try:
                    v = v - be.solve(Wn, r)
                except (np.linalg.LinAlgError, ZeroDivisionError) as exc:
                    raise ComputationError(
                        f"numeric Legendre inverse: W is singular at q = {_numbers(q)}, v = "
                        f"{_numbers(v)}: L is not regular there (the Hamiltonian side needs "
                        f"W invertible)") from exc
            raise ComputationError(
                f"numeric Legendre inverse did not converge in {maxiter} Newton steps at "
                f"q = {_numbers(q)}, p = {_numbers(p)} (residual {float(be.norm(r)):.3g}): no "
                f"velocity has these momenta near v = 0")

    # --------------------------------------------------------- transport
    @cached_property
    def hamiltonian(self) -> sp.Expr:
        """H = E_L o Leg^{-1} as an expression in (q, p) (needs an exact inverse)."""
        L = self.system.lagrangian
        v = sp.Matrix(self.velocities)
        energy = (v.T * self.momenta)[0] - L
        return self.transport(energy)

    def pullback(self, f) -> sp.Expr:
        """Leg* f = f o Leg: a function of (q, p) made a function of (q, v)."""
        return sp.sympify(f).xreplace(self._to_momenta)

    def transport(self, f) -> sp.Expr:
        """f o Leg^{-1}: a function of (q, v) made a function of (q, p).

        Rational expressions are cancelled; needs an exact inverse.
        """
        out = sp.sympify(f).xreplace(self.inverse)
        if self.inverse_kind == "closed-form":
            # Radicals from a closed-form branch only collapse under simplify.
            return sp.simplify(out)
        return cancel(out)

    def tangent_map(self, field: sp.Matrix) -> sp.Matrix:
        """Leg_* X at Leg(x), as functions of x = (q, v), shape (2n, 1).

        Parameters
        ----------
        field : sympy.Matrix, shape (2n, 1)
            Components of X on TQ in the basis (d/dq, d/dv).
        """
        return (self.jacobian * sp.Matrix(field)).applyfunc(sp.expand)

    def pushforward(self, field: sp.Matrix) -> sp.Matrix:
        """Leg_* X as a vector field on T*Q in (q, p) (needs an exact inverse)."""
        return self.tangent_map(field).applyfunc(self.transport)

    def pullback_field(self, field: sp.Matrix) -> sp.Matrix:
        """Leg^* Y = (Leg_*)^{-1}(Y o Leg) on TQ, shape (2n, 1).

        The q-components are those of Y o Leg; the v-components solve
        W dv = Y^p - M Y^q (a linear solve, no symbolic inverse).
        """
        n = self.n
        Y = sp.Matrix(field).applyfunc(self.pullback)
        yq, yp = Y[:n, 0], Y[n:, 0]
        rhs = yp - self.mixed_hessian * yq
        W = self.hessian
        yv = sp.Matrix([rhs[i] / W[i, i] for i in range(n)]) if W.is_diagonal() else W.LUsolve(rhs)
        return sp.Matrix.vstack(yq, yv.applyfunc(sp.cancel))

    def pullback_form(self, omega: sp.Matrix) -> sp.Matrix:
        """Leg^* omega for a 2-form on T*Q given by its matrix: J^T (Omega o Leg) J."""
        O = sp.Matrix(omega).applyfunc(self.pullback)
        return (self.jacobian.T * O * self.jacobian).applyfunc(sp.expand)


def _numbers(values) -> str:
    """A vector for a message: [0.608, 1.24] (not numpy's reprs)."""
    return "[" + ", ".join(f"{float(x):.6g}" for x in values) + "]"


def _close(cand, v, p, pA, pt):
    """Round trip: v0 -> p0 = pA(v0) -> cand(p0) == v0 at a point."""
    try:
        p0 = complex(pA.xreplace(pt).evalf())
        back = complex(cand.xreplace({**pt, p: sp.Float(p0.real)}).evalf())
    except (TypeError, ValueError, ZeroDivisionError):
        return False
    return abs(back.imag) < 1e-9 and abs(back.real - pt[v]) < 1e-9 * (1 + abs(pt[v]))
