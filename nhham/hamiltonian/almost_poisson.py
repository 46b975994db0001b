"""The nonholonomic (almost-Poisson) bracket on T*Q and its Jacobiator.

{f, g}_nh = omega_Q(P X_f, P X_g), P the §4 projection of the T*Q side
(:class:`~nhham.hamiltonian.side.HamiltonianSide`); the Jacobiator as an integrability
diagnostic on M_1.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import sympy as sp

from nhham.errors import ComputationError
from nhham.hamiltonian.brackets import BivectorBracket
from nhham.hamiltonian.legendre import canonical_form_matrix
from nhham.hamiltonian.side import HamiltonianSide, hamiltonian_side
from nhham.lagrangian.algebra import cancel, solve_linear
from nhham.lagrangian.engine import Policy, policy_of
from nhham.lagrangian.submanifold import Submanifold
from nhham.settings import SEED

__all__ = ["NonholonomicBracket", "nonholonomic_bracket", "JacobiatorReport"]


@dataclass(frozen=True)
class JacobiatorReport:
    """The Jacobiator of the nonholonomic bracket as an integrability diagnostic.

    Attributes
    ----------
    vanishes : bool
        True when every Jacobiator component on coordinate functions vanishes
        on M_1 (then the bracket is Poisson on M_1).
    components : dict
        ``{(z_i, z_j, z_k): expr}`` for the components that are not
        identically zero (as functions on T*Q, before restriction).
    on_M1 : dict
        ``{(z_i, z_j, z_k): Decision}``: does the component vanish on M_1.
    witness : tuple or None
        A triple whose component does not vanish on M_1, with its value.
    """

    vanishes: bool
    components: dict
    on_M1: dict
    witness: tuple | None

    def describe(self) -> str:
        if self.vanishes:
            return "the nonholonomic bracket satisfies the Jacobi identity on M_1"
        assert self.witness is not None  # a bracket that fails has a witness
        (i, j, k), value = self.witness
        return (f"the nonholonomic bracket fails the Jacobi identity on M_1: "
                f"Jac({i}, {j}, {k}) = {value}")


class NonholonomicBracket(BivectorBracket):
    """{f, g}_nh = omega_Q(P X_f, P X_g) on T*Q, with P = id - (C^H)^{ij} Z_j^H (x) d phi_i^H.

    The bivector is Lambda = Omega^T P^T Omega P Omega (X_f = Omega grad f,
    omega_Q(X, Y) = X^T Omega Y, Omega = [[0, I], [-I, 0]]).

    Equations of motion: for every f, exactly on T*Q,

        X(f) = {f, H}_nh + (C^H)^{ij} (h_j - phi_j^H) {f, phi_i^H},

    so on M_1 dot f = {f, H}_nh + (C^H)^{ij} h_j {f, phi_i^H}: the second
    term is the extra term of affine constraints (it vanishes when h = 0).
    (Derivation: df(P X_H) = omega(X_f, P X_H) = {f, H}_nh + omega(Q X_f, P X_H)
    and omega(Z_j, Y) = mu_j(pi_* Y), with pi_* P X_H = dH/dp = v, mu_j v = phi_j - h_j.)
    """

    def __init__(self, side: HamiltonianSide):
        if side.m and not side.regular:
            raise ComputationError(
                f"the nonholonomic bracket needs C^H invertible on M_1; here rank C^H = "
                f"{side.constraint_rank.value} < m = {side.m} "
                f"({side.constraint_rank.describe()})")
        Omega = canonical_form_matrix(side.n)
        P = side.projector_P
        tensor = (Omega.T * P.T * Omega * P * Omega).applyfunc(cancel)
        super().__init__(tensor, side.variables)
        self.side = side

    @cached_property
    def extra_coefficients(self) -> sp.Matrix:
        """k_i = (C^H)^{ij} (h_j - phi_j^H), shape (m, 1): dot f = {f, H}_nh + k_i {f, phi_i^H}."""
        side = self.side
        if not side.m:
            return sp.zeros(0, 1)
        sysm = side.system
        if sysm.is_affine:
            rhs = sp.Matrix([sysm.h[j] - side.constraints[j] for j in range(side.m)])
        else:  # h_j - phi_j = -mu_j v for affine phi; -mu_j(q, v) v o Leg^-1 in general
            rhs = sp.Matrix([-side.legendre.transport(
                sum((a * v for a, v in zip(sysm.mu.row(j), sysm.velocities)), sp.S.Zero))
                for j in range(side.m)])
        return solve_linear(side.constraint_matrix, rhs).applyfunc(cancel)

    def extra_term(self, f) -> sp.Expr:
        """(C^H)^{ij} (h_j - phi_j^H) {f, phi_i^H} (zero on M_1 for linear constraints)."""
        side = self.side
        return cancel(sum((self.extra_coefficients[i] * side.algebra.bracket(f, phi)
                          for i, phi in enumerate(side.constraints)), sp.S.Zero))

    def time_derivative(self, f) -> sp.Expr:
        """d f/dt along the projected field: {f, H}_nh + extra term (+ df(P F^V), the
        projected force, when the system has forces)."""
        out = self(f, self.side.H) + self.extra_term(f)
        side = self.side
        if side.system.has_forces:
            FV = side.X_H - side.algebra.hamiltonian_field(side.H)
            grad = sp.Matrix([[sp.diff(f, z) for z in side.variables]])
            out += (grad * side.projector_P * FV)[0]
        return cancel(out)

    def equations_of_motion(self) -> tuple:
        """(dq/dt, dp/dt) from the bracket: z -> {z, H}_nh + extra term, as a 2n-tuple."""
        return tuple(self.time_derivative(z) for z in self.side.variables)

    def jacobiator_report(self, manifold: Submanifold | None = None) -> JacobiatorReport:
        """Jacobiator components on coordinate triples and whether they vanish on M_1."""
        M = self.side.M1 if manifold is None else manifold
        names = self.variables
        comps, decisions, witness = {}, {}, None
        for (i, j, k), value in self.jacobiator_tensor().items():
            key = (names[i], names[j], names[k])
            comps[key] = value
            d = M.vanishes(value)
            decisions[key] = d
            if not d.value and witness is None:
                witness = (key, value)
        return JacobiatorReport(witness is None, comps, decisions, witness)


def nonholonomic_bracket(system, precision=None, samples=6, seed=SEED, *,
                         policy: Policy | None = None) -> NonholonomicBracket:
    """The nonholonomic bracket of ``system`` on T*Q (see :class:`NonholonomicBracket`).

    ``policy`` (:class:`nhham.Policy`) holds the settings of its sampled decisions;
    ``precision``, ``samples`` and ``seed`` are deprecated (a ``DeprecationWarning``;
    removed in the next release).

    Examples
    --------
    A particle on y' = x x': {q^i, p_j}_nh is the orthogonal projector onto the allowed
    velocities (1, x), i.e. (1, x)(1, x)^T / (1 + x^2); the constraint is integrable
    (y - x^2/2 is constant), and the bracket satisfies the Jacobi identity.

    >>> import sympy as sp
    >>> from nhham import System, nonholonomic_bracket
    >>> s = System(["x", "y"], "(x_dot**2 + y_dot**2)/2", constraints=["y_dot - x*x_dot"])
    >>> bracket = nonholonomic_bracket(s)
    >>> x, y, p_x, p_y = sp.symbols("x y p_x p_y")
    >>> [sp.factor(bracket(q, p)) for q, p in [(x, p_x), (x, p_y), (y, p_y)]]
    [1/(x**2 + 1), x/(x**2 + 1), x**2/(x**2 + 1)]
    >>> bracket.jacobiator_tensor()
    {}
    """
    policy = policy_of(policy, "nonholonomic_bracket", precision=precision, samples=samples,
                       seed=seed)
    return NonholonomicBracket(hamiltonian_side(system, policy=policy))
