"""The Hamiltonian side: transported constraints, Z^H, C^H, multipliers, the projected
field, the numeric layer, the T*Q constraint algorithm and the nonholonomic bracket.

Every expected value is derived by hand in the comments (conventions of DESIGN.md §2).
"""

import pytest
import sympy as sp

import nhham

import handmade
from nhham.errors import ComputationError
from nhham.hamiltonian.almost_poisson import nonholonomic_bracket
from nhham.hamiltonian.side import hamiltonian_side
from nhham.hamiltonian.legendre import Backend

S = sp.Symbol


def disk():
    return handmade.rolling_disk()[0]


def pendulum():
    return handmade.pendulum()


def nh_particle():
    xd, yd, zd = sp.symbols("x_dot y_dot z_dot")
    y = S("y")
    return nhham.System(["x", "y", "z"], (xd**2 + yd**2 + zd**2) / 2, [zd - y * xd])


def drifting():
    """Affine, integrable: y_dot = Omega x (h = -Omega x), D = ker dy."""
    xd, yd = sp.symbols("x_dot y_dot")
    return nhham.System(["x", "y"], (xd**2 + yd**2) / 2, [yd - S("Omega") * S("x")],
                        parameters={"Omega": 0.8})


def sleigh():
    th = S("theta")
    xd, yd, thd = sp.symbols("x_dot y_dot theta_dot")
    m, I, a = sp.symbols("m I a")
    return nhham.System(["x", "y", "theta"], m * (xd**2 + yd**2) / 2 + I * thd**2 / 2,
                        [-sp.sin(th) * xd + sp.cos(th) * yd - a * thd],
                        parameters={"m": 1.5, "I": 0.4, "a": 0.6})


def zero(expr):
    return sp.simplify(sp.trigsimp(expr)) == 0


# ------------------------------------------------------------------ disk
def test_rolling_disk_hamiltonian_objects():
    s = disk()
    side = hamiltonian_side(s)
    x, y, th, ph = s.coordinates
    px, py, pth, pph = side.momenta
    m, I1, I2, R = sp.symbols("m I1 I2 R")
    c, sn = sp.cos(th), sp.sin(th)
    # phi_i^H: x_dot = p_x/m, phi_dot = p_phi/I2.
    phi1 = px / m - R * c * pph / I2
    phi2 = py / m - R * sn * pph / I2
    assert zero(side.constraints[0] - phi1) and zero(side.constraints[1] - phi2)
    # Z_i^H = -mu_i d/dp: mu_1 = (1, 0, 0, -R c), mu_2 = (0, 1, 0, -R s).
    Z = sp.Matrix([[0, 0, 0, 0, -1, 0, 0, R * c], [0, 0, 0, 0, 0, -1, 0, R * sn]])
    assert side.vertical_fields == Z
    # C^H = -mu W^{-1} mu^T, the same matrix as on TQ.
    C = -sp.Matrix([[1 / m + R**2 * c**2 / I2, R**2 * c * sn / I2],
                    [R**2 * c * sn / I2, 1 / m + R**2 * sn**2 / I2]])
    assert all(zero(e) for e in side.constraint_matrix - C)
    # X_H(phi_1) = d phi_1/d theta dH/dp_theta = (R s p_phi/I2)(p_theta/I1); X_H(phi_2) similar.
    w = R * pth * pph / (I1 * I2)
    assert zero(side.constraint_derivatives[0] - w * sn)
    assert zero(side.constraint_derivatives[1] + w * c)
    # X_H(phi) = w (s, -c) is orthogonal to n = (c, s), and C^{-1} = -m (I - k n n^T)
    # (Sherman-Morrison), so lambda = -C^{-T} X_H(phi) = m w (s, -c).
    assert zero(side.multipliers[0] - m * w * sn)
    assert zero(side.multipliers[1] + m * w * c)
    # X = X_H + lambda^j Z_j: q' = dH/dp; p_x' = -lambda_1, p_y' = -lambda_2, p_theta' = 0,
    # p_phi' = R c lambda_1 + R s lambda_2 = 0.
    X = sp.Matrix([px / m, py / m, pth / I1, pph / I2, -m * w * sn, m * w * c, 0, 0])
    assert all(zero(e) for e in side.projected_field - X)
    assert side.regular and side.constraint_rank.value == 2


def test_pendulum_multiplier_and_field():
    s = pendulum()
    side = hamiltonian_side(s)
    x, y = s.coordinates
    px, py = side.momenta
    m, g = S("m"), S("g")
    # phi^H = 2 (x p_x + y p_y)/m, mu = (2x, 2y), C = -4 (x^2 + y^2)/m,
    # X_H(phi^H) = 2 (p_x^2 + p_y^2)/m^2 - 2 g y, lambda = -X_H(phi)/C = (p^2 - g m^2 y)/(2 m r^2).
    r2 = x**2 + y**2
    assert zero(side.constraints[0] - 2 * (x * px + y * py) / m)
    assert zero(side.constraint_matrix[0, 0] + 4 * r2 / m)
    lam = (px**2 + py**2 - g * m**2 * y) / (2 * m * r2)
    assert zero(side.multipliers[0] - lam)
    # p' = -dH/dq - lambda mu = (-2 x lambda, -m g - 2 y lambda).
    X = side.projected_field
    assert zero(X[2] + 2 * x * lam) and zero(X[3] + m * g + 2 * y * lam)
    # X is tangent to M_1 = {g = 0, phi^H = 0}.
    for f in side.holonomic + side.constraints:
        assert side.M1.vanishes(side.algebra.apply(X, f)).value


def test_two_particle_rod_multipliers_on_M1():
    x1, x2, y1, y2 = sp.symbols("x1 x2 y1 y2")
    v = x1d, x2d, y1d, y2d = sp.symbols("x1_dot x2_dot y1_dot y2_dot")
    g, l = sp.symbols("g l")
    L = sum(w**2 for w in v) / 2 - g * (y1 + y2)
    X, Y = x2 - x1, y2 - y1
    s = nhham.System(["x1", "x2", "y1", "y2"], L, [X * (y2d + y1d) - (x2d + x1d) * Y],
                     holonomic=[(X**2 + Y**2 - l**2) / 2], parameters={"g": 9.81, "l": 1.2})
    side = hamiltonian_side(s)
    px1, px2, py1, py2 = side.momenta
    # Unit masses: v = p. With C = -2 l^2 Id on M_1 (paper Ex. 4.1),
    # lambda_1 = |p2 - p1|^2/(2 l^2), lambda_2 = (p_x2 p_y1 - p_x1 p_y2 - g (x2 - x1))/l^2.
    lam1 = ((px2 - px1) ** 2 + (py2 - py1) ** 2) / (2 * l**2)
    lam2 = (px2 * py1 - px1 * py2 - g * X) / l**2
    assert side.M1.vanishes(side.multipliers[0] - lam1).value
    assert side.M1.vanishes(side.multipliers[1] - lam2).value


# ---------------------------------------------------------------- numeric layer
@pytest.mark.parametrize("make", [disk, pendulum, sleigh, drifting, nh_particle])
@pytest.mark.parametrize("precision", [None, 30])
def test_numeric_layer_matches_symbolic(make, precision):
    s = make()
    side = hamiltonian_side(s)
    be = Backend(precision)
    pts = side.M1.points()[0][:3]
    Xs = side.projected_field
    args = list(side.variables) + list(s.parameters)
    f = sp.lambdify(args, list(Xs) + list(side.multipliers), "mpmath" if precision else "numpy")
    with be.context():
        for pt in pts:
            q = [pt[a] for a in side.coordinates]
            p = [pt[a] for a in side.momenta]
            par = [pt[a] for a in s.parameters]
            hp = side.numeric.point(be, q, p, par)
            X, lam = side.numeric.projected_field(be, hp)
            ref = f(*[pt[a] for a in args])
            got = list(X) + list(lam)
            assert max(abs(float(a - b)) for a, b in zip(got, ref)) < 1e-12
            assert hp.round_trip < 1e-12


# ------------------------------------------------------- the algorithm on T*Q
def test_paper_example_3_2_on_cotangent_side():
    q1, q2, q3 = sp.symbols("q1 q2 q3")
    v1, v2, v3 = sp.symbols("q1_dot q2_dot q3_dot")
    s = nhham.System(["q1", "q2", "q3"], (v1**2 + v2**2 - v3**2) / 2 + q1**2 / 2, [v1 + v3])
    side = hamiltonian_side(s)
    p1, p2, p3 = side.momenta
    run = side.analysis()
    # p1 = v1, p3 = -v3: phi^H = p1 - p3; H = (p1^2 + p2^2 - p3^2)/2 - q1^2/2.
    # Z^H = -(d/dp1 + d/dp3): Z(phi^H) = -1 + 1 = 0; X_H(phi^H) = {p1 - p3, H} = q1 -> M_2;
    # Z(q1) = 0, X_H(q1) = dH/dp1 = p1 -> M_3; Z(p1) = -1: lambda = -X_H(p1)/Z(p1) = q1.
    assert run.status == "determined"
    assert [(st.rank, st.augmented_rank, len(st.constraints)) for st in run.stages] == \
        [(0, 1, 1), (0, 1, 2), (1, 1, 3)]
    finals = [sp.factor(c) for c in run.final_constraints]
    assert sp.expand(finals[0] - (p1 - p3)) == 0
    assert finals[1] in (q1, -q1) and finals[2] in (p1, -p1)
    assert dict(run.multipliers) == {S("lambda_1"): q1}


def test_paper_example_3_1_free_multiplier_on_cotangent_side():
    v1, v2, v3 = sp.symbols("q1_dot q2_dot q3_dot")
    s = nhham.System(["q1", "q2", "q3"], (v1**2 + v2**2 - v3**2) / 2, [v2 + v3])
    run = hamiltonian_side(s).analysis()
    # phi^H = p2 - p3, Z(phi^H) = -1 + 1 = 0 and X_H(phi^H) = 0: fully undetermined.
    assert run.status == "underdetermined"
    assert run.free_multiplier_symbols == (S("lambda_1"),)
    assert len(run.stages) == 1


# ----------------------------------------------------- nonholonomic bracket
def test_nonholonomic_particle_bracket_and_jacobiator_by_hand():
    s = nh_particle()
    nh = nonholonomic_bracket(s)
    x, y, z = s.coordinates
    px, py, pz = nh.side.momenta
    # phi = p_z - y p_x, mu = (-y, 0, 1), Z = y d/dp_x - d/dp_z, C = Z(phi) = -(1 + y^2).
    # With K = C^{-1}: {f, g}_nh = {f, g} - K {phi, g} Z(f) + K {phi, f} Z(g)
    # (from omega(Q X_f, P X_g) = K {phi, f} mu(pi_* X_g) and mu(pi_* X_g) = -Z(g)).
    # {x, p_x}_nh = 1 + K y^2 = 1/(1 + y^2); {z, p_x}_nh = {x, p_z}_nh = y/(1 + y^2);
    # {z, p_z}_nh = y^2/(1 + y^2); {y, p_y}_nh = 1; {p_x, p_y}_nh = -y p_x/(1 + y^2);
    # {p_y, p_z}_nh = -p_x/(1 + y^2); positions commute.
    d = 1 + y**2
    expected = {(x, px): 1 / d, (z, px): y / d, (x, pz): y / d, (z, pz): y**2 / d,
                (y, py): 1, (px, py): -y * px / d, (py, pz): -px / d, (x, y): 0, (px, pz): 0}
    for (f, g), val in expected.items():
        assert zero(nh(f, g) - val), (f, g)
    # Jac(x, p_y, p_z) = {x, {p_y, p_z}} + {p_y, {p_z, x}} + {p_z, {x, p_y}}
    #   = {x, -p_x/d} + {p_y, -y/d} + 0 = -1/d^2 + (1 - y^2)/d^2 = -y^2/(1 + y^2)^2.
    assert zero(nh.jacobiator(x, py, pz) + y**2 / d**2)
    report = nh.jacobiator_report()
    assert not report.vanishes and report.witness is not None


def test_rolling_disk_jacobiator_by_hand():
    s = disk()
    nh = nonholonomic_bracket(s)
    x, y, th, ph = s.coordinates
    px, py, pth, pph = nh.side.momenta
    m, I2, R = sp.symbols("m I2 R")
    c, sn = sp.cos(th), sp.sin(th)
    # K = C^{-1} = -m (I - k n n^T), n = (c, s), k = m R^2/(I2 + m R^2). From
    # {f, g}_nh = {f, g} - K_ij {phi_i, g} Z_j(f) + K_ij {phi_i, f} Z_j(g):
    # {x, p_x}_nh = 1 + K_11/m = k c^2; {p_x, p_theta}_nh = -m R s p_phi/I2;
    # {x, p_theta}_nh = 0; {x, theta}_nh = 0; {x, p_phi}_nh = R c (1 - k); {theta, p_theta}_nh = 1.
    k = m * R**2 / (I2 + m * R**2)
    assert zero(nh(x, px) - k * c**2)
    assert zero(nh(px, pth) + m * R * sn * pph / I2)
    assert zero(nh(x, pph) - R * c * (1 - k))
    # Jac(x, p_x, p_theta) = {x, -m R s p_phi/I2} + 0 + {p_theta, k c^2}
    #   = (-m R s/I2) R c (1 - k) + (-2 k c s)(-1) = m R^2 s c/(I2 + m R^2).
    assert zero(nh.jacobiator(x, px, pth) - m * R**2 * sn * c / (I2 + m * R**2))
    assert not nh.jacobiator_report().vanishes


@pytest.mark.parametrize("make", [pendulum, drifting])
def test_jacobiator_vanishes_for_integrable_constraints(make):
    nh = nonholonomic_bracket(make())
    report = nh.jacobiator_report()
    assert report.vanishes and report.witness is None
    assert "satisfies the Jacobi identity" in report.describe()


def test_equations_of_motion_need_the_affine_term():
    # Drifting particle: phi^H = p_y - Omega x, h = -Omega x, C = -1, K = -1.
    # dot f = {f, H}_nh + K (h - phi^H) {f, phi^H}; on M_1: dot f = {f, H}_nh + Omega x {f, phi^H}.
    s = drifting()
    nh = nonholonomic_bracket(s)
    side = nh.side
    x, y = s.coordinates
    px, py = side.momenta
    Om = S("Omega")
    X = side.projected_field
    for z, Xz in zip(side.variables, X):
        assert zero(nh.time_derivative(z) - Xz)
    # Without the extra term y' comes out wrong: {y, H}_nh = 0 (P kills d/dp_y) but y' = Omega x.
    assert zero(nh(y, side.H))
    assert zero(X[1] - py) and side.M1.vanishes(X[1] - Om * x).value
    # extra term K (h - phi^H) {y, phi^H} = -(-Omega x - p_y + Omega x) * 1 = p_y (= Omega x on M_1).
    assert zero(nh.extra_term(y) - py)


def test_linear_constraints_need_no_extra_term():
    s = sleigh()
    nh = nonholonomic_bracket(s)
    side = nh.side
    for z, Xz in zip(side.variables, side.projected_field):
        assert side.M1.vanishes(nh(z, side.H) - Xz).value


def test_nonholonomic_bracket_needs_regular_C():
    v1, v2, v3 = sp.symbols("q1_dot q2_dot q3_dot")
    s = nhham.System(["q1", "q2", "q3"], (v1**2 + v2**2 - v3**2) / 2, [v2 + v3])
    with pytest.raises(ComputationError, match="C\\^H invertible"):
        nonholonomic_bracket(s)


SHARED = ("state", "energy", "vertical_fields", "constraint_gradients", "constraint_matrix",
          "constraint_derivatives", "multipliers", "multiplier_symbols", "projected_field",
          "projector_Q", "projector_P", "M1", "constraint_rank", "regular")


def test_both_sides_answer_under_the_same_names():
    """The Lagrangian and Hamiltonian sides share their names; on the rolling disk
    (W constant, Leg linear) C^H o Leg = C and the multipliers agree through Leg."""
    system = disk()
    geo, side = nhham.lagrangian_geometry(system), hamiltonian_side(system)
    for name in SHARED:
        getattr(geo, name), getattr(side, name)
    assert len(side.state) == len(geo.state) == 2 * system.n
    pull = dict(zip(side.legendre.momentum_symbols, geo.momenta))
    # H o Leg = E_L: the two energies are one function seen from both sides
    assert side.energy == side.H and sp.simplify(side.energy.subs(pull) - geo.energy) == 0
    assert (side.constraint_matrix.subs(pull) - geo.constraint_matrix).applyfunc(
        sp.simplify) == sp.zeros(system.m, system.m)
    assert (side.multipliers.subs(pull) - geo.multipliers).applyfunc(
        sp.simplify) == sp.zeros(system.m, 1)
    assert side.multiplier_symbols == geo.multiplier_symbols


def test_the_hamiltonian_side_answers_only_under_the_lagrangian_names():
    side = hamiltonian_side(disk())
    for old in ("constraint_matrix_H", "multipliers_H", "projected_field_H"):
        with pytest.raises(AttributeError):
            getattr(side, old)
