"""Lagrangian-side geometry: paper Examples 2.1 and 4.1, Remark 2.1, identities.

Reference values are derived by hand in the tests (docstrings show how), and
identities are checked numerically at points of M_1 built by hand
(``handmade.py``), not with the library's own reduction.
"""

import numpy as np
import pytest
import sympy as sp

import nhham
from nhham.lagrangian.geometry import lagrangian_geometry

import handmade
from handmade import evaluate, evaluate_matrix

RNG_SEED = 7


def zeros_close(values, tol=1e-10):
    return np.max(np.abs(np.asarray(values, dtype=float))) < tol


# --------------------------------------------------------------- Example 2.1
def test_example_2_1_objects_by_hand():
    """Rolling disk. W = diag(m, m, I1, I2), L has no q: xi_L = (v, 0),
    mu_1 = (1, 0, 0, -R c), mu_2 = (0, 1, 0, -R s), Z_i = -W^{-1} mu_i,
    C = -mu W^{-1} mu^T, xi(phi) = R th' ph' (s, -c), lambda = -C^{-1} xi(phi)
    = m R th' ph' (s, -c) because (s, -c) is orthogonal to (c, s)."""
    system, _ = handmade.rolling_disk(params=False)
    G = lagrangian_geometry(system)
    x, y, th, ph, xd, yd, thd, phd = system.state
    m, I1, I2, R = system.parameters
    c, s = sp.cos(th), sp.sin(th)
    assert sp.expand(G.energy - system.lagrangian) == 0
    Omega = sp.zeros(8, 8)
    for i, w in enumerate([m, m, I1, I2]):
        Omega[i, 4 + i], Omega[4 + i, i] = w, -w
    assert G.poincare_cartan_2form == Omega
    assert G.euler_lagrange_field == sp.Matrix([xd, yd, thd, phd, 0, 0, 0, 0])
    Z = sp.Matrix([[0, 0, 0, 0, -1 / m, 0, 0, R * c / I2],
                   [0, 0, 0, 0, 0, -1 / m, 0, R * s / I2]])
    assert (G.vertical_fields - Z).applyfunc(sp.simplify) == sp.zeros(2, 8)
    C = sp.Matrix([[-1 / m - R**2 * c**2 / I2, -R**2 * c * s / I2],
                   [-R**2 * c * s / I2, -1 / m - R**2 * s**2 / I2]])
    assert (G.constraint_matrix - C).applyfunc(sp.simplify) == sp.zeros(2, 2)
    lam = sp.Matrix([m * R * thd * phd * s, -m * R * thd * phd * c])
    assert (G.multipliers - lam).applyfunc(sp.simplify) == sp.zeros(2, 1)
    # P(xi_L) = xi_L + lambda^1 Z_1 + lambda^2 Z_2 (the paper's formula).
    expected = sp.Matrix([xd, yd, thd, phd, -R * thd * phd * s, R * thd * phd * c, 0, 0])
    assert (G.projected_field - expected).applyfunc(sp.simplify) == sp.zeros(8, 1)


def test_example_2_1_equations_of_motion():
    system, _ = handmade.rolling_disk(params=False)
    G = lagrangian_geometry(system)
    m, I1, I2, R = system.parameters
    xdd, ydd, thdd, phdd = G.acceleration_symbols
    l1, l2 = G.multiplier_symbols
    th = system.coordinates[2]
    expected = [m * xdd + l1, m * ydd + l2, I1 * thdd,
                I2 * phdd - R * sp.cos(th) * l1 - R * sp.sin(th) * l2]
    assert [sp.expand(a - b) for a, b in zip(G.equations_of_motion, expected)] == [0] * 4


def test_constraint_matrix_regular_on_M1_decided_exactly():
    system, _ = handmade.rolling_disk()
    G = lagrangian_geometry(system)
    assert G.regular and G.constraint_rank.method == "exact"


def test_regular_is_C_regular_on_M1_not_the_lagrangian():
    """Paper Example 3.1: L = (v1^2 + v2^2 - v3^2)/2 is a regular Lagrangian (W =
    diag(1, 1, -1), else no System), but phi = v2 + v3 gives C = -(1 - 1) = 0: "regular"
    is False on both sides (C on TQ, C^H on T*Q), rank 0 < m = 1."""
    from nhham.hamiltonian.side import hamiltonian_side
    from nhham.system.models import paper_example_3_1

    system = paper_example_3_1()
    for side in (lagrangian_geometry(system), hamiltonian_side(system)):
        assert side.constraint_matrix == sp.zeros(1, 1)
        assert side.constraint_rank.value == 0 and not side.regular


# --------------------------------------------------------------- Remark 2.1
def test_remark_2_1_projector_independent_of_combination_on_M1():
    """phi_bar = D phi with D regular: P_bar = P on M_1 but not off it."""
    system, point = handmade.rolling_disk()
    x, y, th = system.coordinates[:3]
    D = sp.Matrix([[2 + sp.sin(x), y], [sp.cos(th), 3]])  # det >= 3 - |y|... keep |y| small
    phi_bar = list(D * sp.Matrix(system.phi))
    other = nhham.System(system.coordinates, system.lagrangian, phi_bar,
                         parameters=dict(system.parameter_values))
    P = lagrangian_geometry(system).projector_P
    P_bar = lagrangian_geometry(other).projector_P
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(5):
        pt = point(rng)
        pt[y] = 0.3 * pt[y]
        assert zeros_close(evaluate_matrix(P - P_bar, pt))
    off = point(rng)
    off[system.velocities[0]] += 0.5
    assert not zeros_close(evaluate_matrix(P - P_bar, off), 1e-6)


# --------------------------------------------------------------- Example 4.1
def test_example_4_1_by_hand():
    """Two particles joined by a rod. With dx = x2 - x1, dy = y2 - y1, W = I:
    mu_1 = d(h1^c)/dv = (-dx, dx, -dy, dy), mu_2 = (-dy, -dy, dx, dx) in the
    order (x1, x2, y1, y2); Z_i = -mu_i; C = -mu mu^T = diag(-2|d|^2, -2|d|^2)
    (off-diagonal terms cancel) = -2 l^2 I on M_1. xi_L(phi_1) = dx'^2 + dy'^2,
    xi_L(phi_2) = dx' (y1' + y2') - (x1' + x2') dy' - 2 g dx, and
    lambda = xi(phi) / (2 l^2) on M_1. The accelerations are
    a = (0, 0, -g, -g) + lambda_1 Z_1 + lambda_2 Z_2."""
    system, point = handmade.two_particle_rod()
    G = lagrangian_geometry(system)
    x1, x2, y1, y2, x1d, x2d, y1d, y2d = system.state
    g, l = system.parameters
    dx, dy = x2 - x1, y2 - y1
    mu1 = sp.Matrix([[-dx, dx, -dy, dy]])
    mu2 = sp.Matrix([[-dy, -dy, dx, dx]])
    assert sp.expand(system.mu - sp.Matrix.vstack(mu1, mu2)) == sp.zeros(2, 4)
    Z = sp.Matrix.hstack(sp.zeros(2, 4), -sp.Matrix.vstack(mu1, mu2))
    assert sp.expand(G.vertical_fields - Z) == sp.zeros(2, 8)
    assert sp.expand(G.constraint_matrix - sp.diag(-2 * (dx**2 + dy**2), -2 * (dx**2 + dy**2))) \
        == sp.zeros(2, 2)
    ddx, ddy = x2d - x1d, y2d - y1d
    lam1 = (ddx**2 + ddy**2) / (2 * l**2)
    lam2 = (ddx * (y1d + y2d) - (x1d + x2d) * ddy - 2 * g * dx) / (2 * l**2)
    acc = [lam1 * dx + lam2 * dy, -lam1 * dx + lam2 * dy,
           -g + lam1 * dy - lam2 * dx, -g - lam1 * dy - lam2 * dx]
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(5):
        pt = point(rng)
        assert zeros_close([evaluate(G.multipliers[0] - lam1, pt),
                            evaluate(G.multipliers[1] - lam2, pt)])
        assert zeros_close([evaluate(G.projected_field[4 + i] - acc[i], pt) for i in range(4)])
        assert zeros_close(evaluate_matrix(G.constraint_matrix, pt) + 2 * 1.2**2 * np.eye(2))


def test_example_4_1_modified_lagrangian():
    """Paper §4: 𝕃 = L - Lambda^1 h1 with Lambda^1 the multiplier of h1^c."""
    system, _ = handmade.two_particle_rod()
    G = lagrangian_geometry(system)
    h1 = system.holonomic[0]
    assert sp.simplify(G.modified_lagrangian - (system.lagrangian - G.multipliers[0] * h1)) == 0


# ---------------------------------------------------------------- identities
@pytest.fixture(params=sorted(handmade.IDENTITY_SYSTEMS))
def case(request):
    system, point = handmade.IDENTITY_SYSTEMS[request.param]()
    return system, point, lagrangian_geometry(system)


def _off_M1(system, point, rng):
    pt = point(rng)
    for v in system.velocities:
        pt[v] += rng.normal(scale=0.3)
    return pt


def test_P_is_a_projector(case):
    system, point, G = case
    P = G.projector_P
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(3):
        Pn = evaluate_matrix(P, _off_M1(system, point, rng))
        assert np.allclose(Pn @ Pn, Pn, atol=1e-10)
        assert np.linalg.matrix_rank(np.eye(len(Pn)) - Pn, tol=1e-9) == system.m


def test_projected_field_is_tangent_everywhere(case):
    """P(xi_L)(phi_l) = xi(phi_l) - C^{ij} xi(phi_i) C_jl = 0 on all of TQ."""
    system, point, G = case
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(3):
        pt = _off_M1(system, point, rng)
        assert zeros_close([evaluate(G.apply(G.projected_field, f), pt) for f in system.phi])


def test_projected_field_is_second_order(case):
    system, _, G = case
    J, liouville = G.almost_tangent_structure, G.liouville_field
    assert (J * G.projected_field - liouville).applyfunc(sp.simplify) == sp.zeros(2 * system.n, 1)


def test_bracket_with_energy_is_euler_lagrange_derivative(case):
    system, point, G = case
    q, v = system.coordinates, system.velocities
    f = sp.sin(q[0]) * v[1] + q[1] ** 2 * v[0] ** 2 + v[-1] * q[-1]
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(3):
        pt = _off_M1(system, point, rng)
        assert abs(evaluate(G.bracket(f, G.energy) - G.apply(G.euler_lagrange_field, f), pt)) < 1e-10


def test_hamiltonian_field_solves_symplectic_equation(case):
    """i_{X_f} omega = df: Omega^T X_f = grad f."""
    system, point, G = case
    f = system.coordinates[0] * system.velocities[-1] ** 2
    X = G.hamiltonian_field(f)
    residual = G.poincare_cartan_2form.T * X - G.gradient(f)
    rng = np.random.default_rng(RNG_SEED)
    assert zeros_close(evaluate_matrix(residual, _off_M1(system, point, rng)))


def test_energy_conserved_for_linear_constraints(case):
    system, point, G = case
    assert system.is_linear
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(3):
        assert abs(evaluate(G.apply(G.projected_field, G.energy), point(rng))) < 1e-10


def test_energy_not_conserved_for_affine_constraint():
    """y' = Omega x: y'' = Omega x' = -lambda, x'' = 0, so dE/dt = Omega^2 x x'
    = lambda h with h = -Omega x (mu v = -h on M_1)."""
    system, point = handmade.drifting_particle()
    G = lagrangian_geometry(system)
    x, y, xd, yd = system.state
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(3):
        pt = point(rng)
        dE = evaluate(G.apply(G.projected_field, G.energy), pt)
        assert abs(dE - 0.8**2 * pt[x] * pt[xd]) < 1e-10
        assert abs(dE) > 1e-6 or abs(pt[x] * pt[xd]) < 1e-6
    assert evaluate(G.multipliers[0], {xd: 2.0, system.parameters[0]: 0.8}) == pytest.approx(-1.6)


# ------------------------------------------- quadratic fast path vs general
from nhham.lagrangian.geometry import LagrangianGeometry  # noqa: E402
from nhham.system.models import MODELS, snake_chain_lagrangian  # noqa: E402


def _magnetic_knife_edge():
    """b != 0: a charged skate in a magnetic field B with an extra gyroscopic
    term e x sin(theta) theta' and a potential; knife-edge constraint and a
    holonomic-free affine one (drift from both mu(q) and h(q))."""
    x, y, th = sp.symbols("x y theta")
    xd, yd, thd = sp.symbols("x_dot y_dot theta_dot")
    m, I, B, e, k = sp.symbols("m I B e k")
    L = (m * (xd**2 + yd**2) / 2 + I * thd**2 / 2 + B * (x * yd - y * xd) / 2
         + e * x * sp.sin(th) * thd - k * (x**2 + y**2) / 2 - sp.cos(th))
    return nhham.System(["x", "y", "theta"], L,
                        [sp.sin(th) * xd - sp.cos(th) * yd + e * y * sp.cos(x)],
                        parameters={"m": 1.3, "I": 0.4, "B": 0.7, "e": 0.9, "k": 1.1},
                        name="magnetic knife edge")


def _rotating_frame_particle():
    """b != 0 and W, b, V all depending on q: L = |r' + Omega x r|^2 m(z)/2 - g z."""
    x, y, z = sp.symbols("x y z")
    xd, yd, zd = sp.symbols("x_dot y_dot z_dot")
    Om, g = sp.symbols("Omega g")
    mass = 1 + z**2 / 4
    L = mass * ((xd - Om * y) ** 2 + (yd + Om * x) ** 2 + zd**2) / 2 - g * z
    return nhham.System(["x", "y", "z"], L, [zd - x * yd],
                        parameters={"Omega": 0.8, "g": 9.81}, name="rotating frame")


def _quartic_particle():
    """Not quadratic in v: L = |v|^2/2 + eps (x'^4)/12 + cos(y) x' y'^2 - V."""
    x, y, th = sp.symbols("x y theta")
    xd, yd, thd = sp.symbols("x_dot y_dot theta_dot")
    eps = sp.Symbol("eps")
    L = ((xd**2 + yd**2 + thd**2) / 2 + eps * xd**4 / 12 + sp.cos(y) * xd * yd**2 / 5
         - sp.sin(x) * y)
    return nhham.System(["x", "y", "theta"], L, [xd - sp.cos(th) * thd],
                        parameters={"eps": 0.3}, name="quartic")


def _snake_chain(N):
    """The snake with L written as the sum of link kinetic energies (unexpanded)."""
    base = MODELS["snake"](N)
    return nhham.System(base.coordinates, snake_chain_lagrangian(N), base.constraints,
                        parameters={p.name: x for p, x in base.parameter_values.items()})


FAST_PATH_SYSTEMS = {
    "magnetic_knife_edge": _magnetic_knife_edge,
    "rotating_frame": _rotating_frame_particle,
    "quartic": _quartic_particle,
    "snake3": lambda: MODELS["snake"](3),
    "snake3_chain": lambda: _snake_chain(3),
    "rolling_ball": MODELS["rolling_ball"],
    "snakeboard": MODELS["snakeboard"],
    "two_particle_rod": MODELS["two_particle_rod"],
}


def _max_abs_at_random_points(matrix, system, rng, count=6):
    """max |entry| of a symbolic matrix at random (q, v, parameters)."""
    syms = list(system.state) + list(system.parameters)
    f = sp.lambdify(syms, sp.Matrix(matrix), "numpy")
    worst = 0.0
    for _ in range(count):
        value = np.asarray(f(*rng.uniform(-1.3, 1.3, len(syms))), dtype=float)
        worst = max(worst, float(np.abs(value).max()) if value.size else 0.0)
    return worst


@pytest.mark.parametrize("name", sorted(FAST_PATH_SYSTEMS))
def test_quadratic_fast_path_agrees_with_general_path(name):
    """W, momenta, mixed Hessian, forcing, drift, E_L and a bracket: both paths equal."""
    system = FAST_PATH_SYSTEMS[name]()
    fast, general = LagrangianGeometry(system), LagrangianGeometry(system, fast=False)
    assert general._parts is None
    assert (fast._parts is None) == (name == "quartic")
    rng = np.random.default_rng(RNG_SEED)
    q, v = system.coordinates, system.velocities
    f = sp.sin(q[0]) * v[1] + q[-1] * v[0] ** 2
    pairs = [(fast.hessian, general.hessian), (fast.momenta, general.momenta),
             (fast.mixed_hessian, general.mixed_hessian), (fast.forcing, general.forcing),
             (fast.ingredients.drift, general.ingredients.drift),
             (fast.poincare_cartan_2form, general.poincare_cartan_2form),
             (sp.Matrix([fast.energy]), sp.Matrix([general.energy]))]
    if system.n <= 3:  # the bracket solves with W symbolically: keep it small
        pairs.append((sp.Matrix([fast.bracket(f, fast.energy)]),
                      sp.Matrix([general.bracket(f, general.energy)])))
    for a, b in pairs:
        assert a.shape == b.shape
        assert _max_abs_at_random_points(a - b, system, rng) < 1e-12
    assert fast.ingredients.mu == system.mu


def test_fast_forcing_expands_to_the_general_one_for_b_nonzero():
    """Exact agreement (expand of the difference is 0) on polynomial/trig input."""
    system = _magnetic_knife_edge()
    fast, general = LagrangianGeometry(system), LagrangianGeometry(system, fast=False)
    assert any(b != 0 for b in fast._parts.b)
    assert sp.expand(fast.forcing - general.forcing) == sp.zeros(system.n, 1)
    assert sp.expand(fast.mixed_hessian - general.mixed_hessian) == sp.zeros(system.n, system.n)
    assert sp.expand(sp.Matrix(system.hessian) - sp.hessian(system.lagrangian, system.velocities)) \
        == sp.zeros(system.n, system.n)


def test_magnetic_forcing_by_hand():
    """F_B = (d_B b_A - d_A b_B) v^A - d_B V here (W constant): the Lorentz
    force B (y', -x'), the gyroscopic pair +-e sin(theta) from
    d_x b_theta - d_theta b_x = e sin(theta), and -k r, + sin(theta) from V."""
    system = _magnetic_knife_edge()
    x, y, th, xd, yd, thd = system.state
    m, I, B, e, k = system.parameters
    expected = sp.Matrix([B * yd + e * sp.sin(th) * thd - k * x,
                          -B * xd - k * y,
                          -e * sp.sin(th) * xd + sp.sin(th)])
    assert sp.expand(LagrangianGeometry(system).forcing - expected) == sp.zeros(3, 1)


# ------------------------------------------------ System validation numerics
def test_fast_sample_values_match_evalf():
    """Validation's one-pass numeric evaluation equals xreplace + evalf; an entry that is
    not a real number at the point (the real cube root's principal branch at x < 2, i pi x)
    is NaN in both."""
    from nhham.system.sampled_checks import (
        VALIDATION_SAMPLES, numeric, numeric_samples, sample_q)

    system = _snake_chain(3)
    x, y = system.coordinates[:2]
    extra = sp.Matrix([[sp.sqrt(2 + sp.sin(x)) * sp.exp(y), sp.log(1 + x**2) / (3 + sp.cos(y)),
                        sp.atan(x) * sp.tanh(y), (x - 2) ** sp.Rational(1, 3), sp.pi * sp.I * x]])
    for matrix in (system.hessian, system.mu, extra):
        points = sample_q(system, np.random.default_rng(3), VALIDATION_SAMPLES)
        fast = numeric_samples(matrix, points)
        slow = [numeric(matrix, p) for p in points]
        assert all(np.allclose(a, b, rtol=1e-12, atol=1e-12, equal_nan=True)
                   for a, b in zip(fast, slow))
    # x < 2 at every sample (|x| < 2): (x - 2)^(1/3) is complex, as is i pi x (x != 0)
    assert all(np.isnan(a[0, 3:]).all() and np.isfinite(a[0, :3]).all() for a in fast)


def test_fast_sample_values_fall_back_for_unknown_nodes():
    """Derivative objects (non-smooth L) take sympy's path and its error message."""
    from nhham.errors import ValidationError
    from nhham.system.sampled_checks import numeric_samples

    x, xd = sp.symbols("x x_dot")
    W = sp.hessian(sp.Abs(xd) ** 2 + x, (xd,))
    with pytest.raises(ValidationError, match="smooth in the velocities"):
        numeric_samples(W, [{x: 0.3, xd: 0.4}])


@pytest.mark.parametrize("name", sorted(FAST_PATH_SYSTEMS))
def test_system_W_and_mu_read_from_terms_equal_derivatives(name):
    system = FAST_PATH_SYSTEMS[name]()
    W = sp.hessian(system.lagrangian, system.velocities)
    mu = sp.Matrix([[sp.diff(f, v) for v in system.velocities] for f in system.phi])
    rng = np.random.default_rng(RNG_SEED)
    assert _max_abs_at_random_points(system.hessian - W, system, rng) < 1e-12
    assert sp.expand(system.mu - mu) == sp.zeros(*mu.shape)
