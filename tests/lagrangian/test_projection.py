"""The §4 projection (nhham.lagrangian.projection) on the vertical rolling disk, by hand.

L = m (x'² + y'²)/2 + I1 θ'²/2 + I2 φ'²/2, φ_1 = x' − R cos θ φ', φ_2 = y' − R sin θ φ'
(examples/rolling_disk.toml). Everything expected here is written out by hand:
W = diag(m, m, I1, I2), ξ_L = (v, 0) (L has no q), μ_1 = (1, 0, 0, −R c),
μ_2 = (0, 1, 0, −R s), Z_i = −W⁻¹ μ_i ∂/∂v (DESIGN.md §2: Z_1 = −(1/m) ∂/∂x' +
(R cos θ / I2) ∂/∂φ'), C_ij = Z_i(φ_j) = −(μ W⁻¹ μᵀ)_ij, ξ_L(φ) = R θ' φ' (s, −c) and
λ = −C⁻ᵀ ξ_L(φ) = m R θ' φ' (s, −c) ((s, −c) is orthogonal to (c, s), so C acts on it as
−1/m). On T*Q: p = W v, H = Σ p_A² / (2 W_AA), X_H = (W⁻¹ p, 0), Z_i^H = −μ_i ∂/∂p,
φ_i^H = μ_i W⁻¹ p.
"""

import pytest
import sympy as sp

from nhham.hamiltonian.side import hamiltonian_side
from nhham.lagrangian.analysis import analyze_constraints
from nhham.lagrangian.formulas import bordered_system
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.lagrangian.linalg import ListMatrix
from nhham.lagrangian.projection import Projection, gradient_rows, tangency_equations
from nhham.system.description import System

x, y, th, ph = sp.symbols("x y theta phi")
xd, yd, thd, phd = sp.symbols("x_dot y_dot theta_dot phi_dot")
px, py, pth, pph = sp.symbols("p_x p_y p_theta p_phi")
m, I1, I2, R = sp.symbols("m I1 I2 R", positive=True)
c, s = sp.cos(th), sp.sin(th)
Q_ = (x, y, th, ph)
V = (xd, yd, thd, phd)
P_ = (px, py, pth, pph)
WEIGHTS = (m, m, I1, I2)
MU = sp.Matrix([[1, 0, 0, -R * c], [0, 1, 0, -R * s]])
PHI = [xd - R * c * phd, yd - R * s * phd]
LAMBDA = sp.Matrix([m * R * thd * phd * s, -m * R * thd * phd * c])


def zero(M) -> bool:
    return sp.Matrix(M).applyfunc(lambda e: sp.simplify(sp.expand_trig(e))).is_zero_matrix


@pytest.fixture(scope="module")
def tq():
    """The projection on TQ from hand-written components (not from L)."""
    xi = sp.Matrix(list(V) + [0, 0, 0, 0])
    Z = sp.Matrix([[0, 0, 0, 0, -1 / m, 0, 0, R * c / I2],
                   [0, 0, 0, 0, 0, -1 / m, 0, R * s / I2]])
    dphi = sp.Matrix([[0, 0, R * s * phd, 0, 1, 0, 0, -R * c],
                      [0, 0, -R * c * phd, 0, 0, 1, 0, -R * s]])
    return Projection(xi, Z, dphi, normal=sp.cancel)


@pytest.fixture(scope="module")
def tstar():
    """The projection on T*Q from hand-written components."""
    XH = sp.Matrix([p / w for p, w in zip(P_, WEIGHTS)] + [0, 0, 0, 0])
    ZH = sp.Matrix.hstack(sp.zeros(2, 4), -MU)
    phiH = [px / m - R * c * pph / I2, py / m - R * s * pph / I2]
    return Projection(XH, ZH, gradient_rows(phiH, Q_ + P_), normal=sp.cancel)


def test_constraint_matrix_and_multipliers_by_hand(tq):
    C = sp.Matrix([[-1 / m - R**2 * c**2 / I2, -R**2 * c * s / I2],
                   [-R**2 * c * s / I2, -1 / m - R**2 * s**2 / I2]])
    assert zero(tq.constraint_matrix - C)
    assert zero(tq.constraint_derivatives - R * thd * phd * sp.Matrix([s, -c]))
    assert zero(tq.multipliers - LAMBDA)


def test_projector_is_a_projection_that_kills_Z(tq):
    P, Q = tq.projector_P, tq.projector_Q
    assert zero(P * P - P)
    assert zero(P * tq.vertical.T)           # P(Z_i) = 0
    assert zero(Q * tq.vertical.T - tq.vertical.T)  # Q(Z_i) = Z_i
    # a field tangent to the constraints (dφ(X) = 0) is left alone: X = ∂/∂θ'
    tangent = sp.Matrix([0, 0, 0, 0, 0, 0, 1, 0])
    assert zero(tq.project(tangent) - tangent)


def test_projected_field_is_tangent_and_the_papers_formula(tq):
    X = tq.projected_field
    # ξ(φ) + λ^j Z_j(φ) = 0: the projected field is tangent to every φ_i
    assert zero(tq.gradients * X)
    assert zero(X - sp.Matrix([xd, yd, thd, phd, -R * thd * phd * s, R * thd * phd * c, 0, 0]))
    assert zero(tq.project(tq.xi) - X)
    # P(ξ + a Z_1 + b Z_2) = P(ξ) for any a, b
    a, b = sp.symbols("a b")
    assert zero(tq.project(tq.xi + a * tq.vertical.row(0).T + b * tq.vertical.row(1).T) - X)


def test_cotangent_instance_agrees_through_the_legendre_map(tq, tstar):
    """Leg(q, v) = (q, W v): λ^H ∘ Leg = λ, Leg_* P(ξ_L) = X ∘ Leg and Leg_* P_L = P_H Leg_*
    with Leg_* = diag(1, W) (W constant)."""
    leg = {p: w * v for p, w, v in zip(P_, WEIGHTS, V)}
    assert zero(tstar.multipliers.xreplace(leg) - LAMBDA)
    T = sp.diag(1, 1, 1, 1, *WEIGHTS)
    assert zero(T * tq.projected_field - tstar.projected_field.xreplace(leg))
    assert zero(T * tq.projector_P - tstar.projector_P.xreplace(leg) * T)
    assert zero(tstar.projector_P * tstar.vertical.T)


@pytest.fixture(scope="module")
def disk():
    return System(["x", "y", "theta", "phi"],
                  "m*(x_dot**2 + y_dot**2)/2 + I1*theta_dot**2/2 + I2*phi_dot**2/2",
                  constraints=["x_dot - R*cos(theta)*phi_dot", "y_dot - R*sin(theta)*phi_dot"],
                  parameters=["m", "I1", "I2", "R"])


def _rename(expr, system):
    """The system's symbols as this module's (same names, the assumptions set here)."""
    ours = {str(v): v for v in Q_ + V + P_ + (m, I1, I2, R)}
    return expr.xreplace({sym: ours[sym.name] for sym in expr.free_symbols if sym.name in ours})


def test_the_four_results_use_the_one_projection(disk, tq, tstar):
    """LagrangianGeometry, HamiltonianSide, the algorithm's run and the analysis give the
    hand-built projection's objects."""
    G = lagrangian_geometry(disk)
    assert isinstance(G.projection, Projection)
    assert zero(_rename(G.multipliers, disk) - LAMBDA)
    assert zero(_rename(G.projector_P, disk) - tq.projector_P)
    H = hamiltonian_side(disk)
    assert isinstance(H.projection, Projection)
    assert zero(_rename(H.projected_field, disk) - tstar.projected_field)
    a = analyze_constraints(disk)
    (run,) = [b.run for b in a.blocks]
    assert zero(_rename(a.projector_P, disk) - tq.projector_P)
    assert zero(_rename(run.projector_Q, disk) - tq.projector_Q)
    assert a.free_multipliers == run.free_multipliers == 0


def test_bordered_system_eliminates_to_the_tangency_equations(tq):
    """(K, c) of the inverse-free form at any point: eliminating a from
    W a + μᵀ λ = F, J_v a = −J_q v gives A λ + b = 0 with the rows from the fields
    (A_ji = Z_i(φ_j) = C_ij, b_j = ξ(φ_j) by hand above)."""
    W = sp.diag(*WEIGHTS)
    Jq = gradient_rows(PHI, Q_)
    Jv = gradient_rows(PHI, V)
    K, cvec = bordered_system(ListMatrix(W.tolist()), ListMatrix(MU.tolist()),
                              ListMatrix([[0]] * 4, 1),
                              ListMatrix((Jq * sp.Matrix(V)).tolist(), 1),
                              ListMatrix(Jv.tolist()))
    K, cvec = sp.Matrix(K.rows), sp.Matrix(cvec.rows)
    assert K[:4, :4] == W and K[:4, 4:] == MU.T and K[4:, :4] == Jv and K[4:, 4:].is_zero_matrix
    Winv = W.inv()
    A = -Jv * Winv * MU.T
    b = -cvec[4:, 0] + Jv * Winv * cvec[:4, 0]
    rows_A, rows_b = tangency_equations(tq.gradients, tq.xi, tq.vertical)
    assert zero(A - rows_A) and zero(b - rows_b)
    assert zero(rows_A - tq.constraint_matrix.T)


def test_a_geometry_shares_its_siblings_closed_forms_but_keeps_its_guard():
    """lagrangian_geometry(closed_form=False) built after a closed_form=True sibling has
    formed λ starts from that λ, and still refuses large closed forms itself."""
    system = System(["x", "y"], "x_dot**2/2 + y_dot**2/2", constraints=["y_dot - x*x_dot"])
    free = lagrangian_geometry(system, closed_form=True)
    lam = free.multipliers
    guarded = lagrangian_geometry(system)
    assert guarded is not free and guarded.projection.owner == "lagrangian_geometry"
    assert free.projection.owner is None
    assert vars(guarded.projection)["multipliers"] is lam
    # λ = −C⁻¹ ξ(φ) with C = −(1 + x²), ξ(φ) = −x_dot²: λ = −x_dot² / (1 + x²)
    x, xd = sp.symbols("x x_dot")
    assert sp.simplify(_rename(lam[0], system) + xd**2 / (1 + x**2)) == 0
