"""The ready-made models against hand derivations written out here.

Every expected value below is derived by hand in the test (or in its
docstring) from the physics, not copied from nhham/models.py. Numeric checks
run at random points of M_1 found by projection (see :func:`point_on_M1`).
"""

from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from nhham import RedundantConstraintError, System
from nhham.errors import InputError
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.system.models import (
    MODELS,
    ball_on_turntable,
    chaplygin_sleigh,
    knife_edge_inclined,
    nonholonomic_particle,
    paper_example_3_1,
    paper_example_3_2,
    particle_on_sphere,
    pendulum_cartesian,
    rolling_ball,
    rolling_disk,
    snake,
    snake_centres,
    snakeboard,
    two_particle_rod,
)

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
S = sp.Symbol


def dot(name):
    return S(f"{name}_dot")


# ------------------------------------------------------------- helpers
def point_on_M1(system, rng, low=0.3, high=1.3):
    """A random numeric point of M_1 as ``{symbol: float}`` (parameters included).

    Coordinates are drawn from [low, high] (away from the Euler-angle
    singularity theta = 0 of the ball models), projected onto the holonomic
    constraints by Gauss-Newton; velocities are the orthogonal projection of
    a random vector onto mu v + h = 0.
    """
    point = dict(system.parameter_values)
    q = rng.uniform(low, high, size=system.n)
    if system.holonomic:
        G = sp.Matrix(system.holonomic).xreplace(point)
        g = sp.lambdify(system.coordinates, G, "numpy")
        jac = sp.lambdify(system.coordinates, G.jacobian(system.coordinates), "numpy")
        for _ in range(60):
            residual = np.asarray(g(*q), float).ravel()
            q = q - np.linalg.lstsq(np.asarray(jac(*q), float), residual, rcond=None)[0]
        assert np.abs(np.asarray(g(*q), float)).max() < 1e-13
    point.update(zip(system.coordinates, q))
    mu = _num(system.mu, point)
    h = _num(system.h, point).ravel()
    v0 = rng.normal(size=system.n)
    v = v0 - mu.T @ np.linalg.solve(mu @ mu.T, mu @ v0 + h) if system.m else v0
    point.update(zip(system.velocities, v))
    return point


def _num(expr, point):
    return np.array(sp.Matrix(expr).xreplace(point).evalf(), dtype=float)


def constrained_accelerations(system, point):
    """(accelerations, multipliers) from nhham's saddle-point ingredients at a point."""
    ing = lagrangian_geometry(system).ingredients
    n, m = system.n, system.m
    W, F, mu, drift = (_num(x, point) for x in (ing.W, ing.forcing, ing.mu, ing.drift))
    K = np.block([[W, mu.T], [mu, np.zeros((m, m))]])
    sol = np.linalg.solve(K, np.concatenate([F.ravel(), -drift.ravel()]))
    return sol[:n], sol[n:]


def trig_zero(expr):
    """True when expr is identically 0 as a polynomial in sin/cos of single angles.

    expand_trig splits cos(a - b); sin(t)^2 -> 1 - cos(t)^2 then decides exactly.
    """
    e = sp.expand(sp.expand_trig(expr))
    e = e.replace(lambda a: a.is_Pow and isinstance(a.base, sp.sin) and a.exp.is_even,
                  lambda a: (1 - sp.cos(a.base.args[0])**2)**(a.exp // 2))
    return sp.expand(e) == 0


# ------------------------------------------------------- construction
@pytest.mark.parametrize("name", sorted(MODELS))
def test_every_model_constructs_with_values(name):
    system = MODELS[name]()
    assert isinstance(system, System)
    assert set(system.parameter_values) == set(system.parameters)
    assert system.m < system.n


@pytest.mark.parametrize("name", sorted(set(MODELS) - {"paper_example_3_1", "paper_example_3_2"}))
def test_every_model_constructs_symbolically(name):
    system = MODELS[name](symbolic=True)
    assert system.parameters and not system.parameter_values


def test_keyword_overrides_values():
    system = rolling_disk(m=2.5, R=0.3)
    assert system.parameter_values[S("m")] == 2.5
    assert system.parameter_values[S("R")] == 0.3
    assert ball_on_turntable(0.7).parameter_values[S("Omega")] == 0.7


def test_snake_rejects_bad_link_count():
    for bad in (0, -1, 2.0, True):
        with pytest.raises(InputError):
            snake(bad)


def test_nonholonomic_particle_potential():
    system = nonholonomic_particle(potential="k*(x**2 + y**2)/2", potential_parameters={"k": 3.0})
    x = S("x")
    assert sp.expand(system.lagrangian.diff(x)) == -S("k") * x
    assert system.parameter_values[S("k")] == 3.0
    with pytest.raises(InputError):
        nonholonomic_particle(potential="q*x")


# ------------------------------------------------------- rolling disk
def test_rolling_disk_mu_Z_and_C():
    """mu_1 = dx - R cos(theta) dphi, mu_2 = dy - R sin(theta) dphi; DESIGN's Z_1 check."""
    system = rolling_disk(symbolic=True)
    m, I2, R, th = S("m"), S("I2"), S("R"), S("theta")
    assert system.mu == sp.Matrix([[1, 0, 0, -R * sp.cos(th)], [0, 1, 0, -R * sp.sin(th)]])
    assert system.h == sp.zeros(2, 1)
    geo = lagrangian_geometry(system)
    Z1 = geo.vertical_fields.row(0)
    assert list(Z1) == [0, 0, 0, 0, -1 / m, 0, 0, R * sp.cos(th) / I2]
    C = sp.Matrix([
        [-1 / m - R**2 * sp.cos(th)**2 / I2, -R**2 * sp.cos(th) * sp.sin(th) / I2],
        [-R**2 * sp.cos(th) * sp.sin(th) / I2, -1 / m - R**2 * sp.sin(th)**2 / I2],
    ])
    assert sp.simplify(geo.constraint_matrix - C) == sp.zeros(2, 2)


def test_rolling_disk_projected_field_is_paper_formula():
    """P(xi_L) = xi_L + m R th1' th2' sin(th1) Z_1 - m R th1' th2' cos(th1) Z_2 (paper Ex. 2.1)."""
    system = rolling_disk(symbolic=True)
    geo = lagrangian_geometry(system)
    m, R, th = S("m"), S("R"), S("theta")
    k = m * R * dot("theta") * dot("phi")
    expected = geo.euler_lagrange_field + (
        k * sp.sin(th) * geo.vertical_fields.row(0) - k * sp.cos(th) * geo.vertical_fields.row(1)
    ).T
    rng = np.random.default_rng(1)
    for _ in range(3):
        p = point_on_M1(rolling_disk(), rng)
        p.update({S("I1"): 0.25, S("I2"): 0.5})
        assert np.allclose(_num(geo.projected_field, p), _num(expected, p), rtol=1e-13, atol=1e-13)


# ---------------------------------------------------------- knife edge
def test_knife_edge_reduced_equations():
    """phi'' = 0 and u' = g sin(alpha) cos(phi) for the speed u along the blade."""
    system = knife_edge_inclined()
    g, alpha = 9.81, 0.3
    rng = np.random.default_rng(2)
    for _ in range(4):
        p = point_on_M1(system, rng)
        (xdd, ydd, phdd), _ = constrained_accelerations(system, p)
        ph, xd, yd, phd = p[S("phi")], p[dot("x")], p[dot("y")], p[dot("phi")]
        # u' = d/dt(cos(phi) x' + sin(phi) y')
        du = np.cos(ph) * xdd + np.sin(ph) * ydd + phd * (-np.sin(ph) * xd + np.cos(ph) * yd)
        assert abs(phdd) < 1e-12
        assert du == pytest.approx(g * np.sin(alpha) * np.cos(ph), rel=1e-12)


# ----------------------------------------------------- Chaplygin sleigh
def test_chaplygin_sleigh_reduced_equations():
    """u' = a w^2, w' = -m a u w/(I + m a^2) (Newton-Euler, derived in the docstring below).

    Body frame: centre of mass velocity (u, s), w = theta'. Contact point at
    -a e1 has lateral velocity s - a w = 0. Newton: m(u' - w s) = 0,
    m(s' + w u) = F; Euler: I w' = -a F. Hence (I + m a^2) w' = -m a u w.
    """
    m, I, a = 1.3, 0.4, 0.7
    system = chaplygin_sleigh(m=m, I=I, a=a)
    rng = np.random.default_rng(3)
    for _ in range(4):
        p = point_on_M1(system, rng)
        (xdd, ydd, wd), _ = constrained_accelerations(system, p)
        th, xd, yd, w = p[S("theta")], p[dot("x")], p[dot("y")], p[dot("theta")]
        u = np.cos(th) * xd + np.sin(th) * yd
        du = np.cos(th) * xdd + np.sin(th) * ydd + w * (-np.sin(th) * xd + np.cos(th) * yd)
        assert du == pytest.approx(a * w**2, rel=1e-12)
        assert wd == pytest.approx(-m * a * u * w / (I + m * a**2), rel=1e-12)


# ----------------------------------------------- nonholonomic particle
def test_nonholonomic_particle_multiplier_and_integrals():
    """m x'' = lambda y, m y'' = 0, m z'' = -lambda, z'' = y' x' + y x''
    => lambda = -m x' y'/(1 + y^2); x' sqrt(1 + y^2) is constant."""
    m = 2.0
    system = nonholonomic_particle(m=m)
    rng = np.random.default_rng(4)
    for _ in range(4):
        p = point_on_M1(system, rng)
        (xdd, ydd, zdd), (lam,) = constrained_accelerations(system, p)
        y, xd, yd = p[S("y")], p[dot("x")], p[dot("y")]
        assert lam == pytest.approx(-m * xd * yd / (1 + y**2), rel=1e-12)
        assert abs(ydd) < 1e-12
        assert xdd * np.sqrt(1 + y**2) + xd * y * yd / np.sqrt(1 + y**2) == pytest.approx(0, abs=1e-12)


# ----------------------------------------------------------- the balls
def test_ball_angular_velocity_and_energy_against_physics_vector():
    """The ZXZ angular velocity of sympy.physics.vector gives the Lagrangian and constraints."""
    from sympy.physics.vector import ReferenceFrame, dynamicsymbols

    t = dynamicsymbols._t
    phi, theta, psi = dynamicsymbols("phi theta psi")
    N = ReferenceFrame("N")
    B = N.orientnew("B", "Body", (phi, theta, psi), "ZXZ")
    w = B.ang_vel_in(N)
    back = {f.diff(t): dot(f.func.__name__) for f in (phi, theta, psi)}
    back.update({f: S(f.func.__name__) for f in (phi, theta, psi)})
    wx, wy, wz = (sp.trigsimp(w.dot(N.x).xreplace(back)), sp.trigsimp(w.dot(N.y).xreplace(back)),
                  sp.trigsimp(w.dot(N.z).xreplace(back)))
    m, r, I = S("m"), S("r"), S("I")
    L = m * (dot("x")**2 + dot("y")**2) / 2 + I * (wx**2 + wy**2 + wz**2) / 2
    system = rolling_ball(symbolic=True)
    assert sp.simplify(system.lagrangian - L) == 0
    # contact point: v + omega x (-r e_z) = (x' - r wy, y' + r wx)
    expected = [dot("x") - r * wy, dot("y") + r * wx]
    for got, want in zip(system.constraints, expected):
        assert sp.simplify(got - want) == 0
    turntable = ball_on_turntable(symbolic=True)
    Om, x, y = S("Omega"), S("x"), S("y")
    for got, want in zip(turntable.constraints, [expected[0] + Om * y, expected[1] - Om * x]):
        assert sp.simplify(got - want) == 0


def test_rolling_ball_centre_moves_uniformly():
    system = rolling_ball()
    rng = np.random.default_rng(5)
    for _ in range(4):
        p = point_on_M1(system, rng)
        a, _ = constrained_accelerations(system, p)
        assert np.abs(a[:2]).max() < 1e-12


def test_ball_on_turntable_circles_at_two_sevenths_omega():
    """v' = (I/(I + m r^2)) Omega e_z x v = (2/7) Omega e_z x v for a homogeneous ball."""
    Omega = 1.7
    system = ball_on_turntable(Omega, m=1.2, r=0.8)
    assert system.parameter_values[S("I")] == pytest.approx(0.4 * 1.2 * 0.8**2)
    assert any(e != 0 for e in system.h)
    rng = np.random.default_rng(6)
    for _ in range(4):
        p = point_on_M1(system, rng)
        a, _ = constrained_accelerations(system, p)
        k = 2 * Omega / 7
        assert a[0] == pytest.approx(-k * p[dot("y")], rel=1e-11, abs=1e-12)
        assert a[1] == pytest.approx(k * p[dot("x")], rel=1e-11, abs=1e-12)


# ------------------------------------------------------------ snakeboard
def test_snakeboard_constraints_from_wheel_positions():
    """Axles at (x, y) +/- r (cos theta, sin theta), headings theta +/- phi: no sideways slip."""
    system = snakeboard(symbolic=True)
    x, y, th, ph, r = S("x"), S("y"), S("theta"), S("phi"), S("r")
    for sign, got in zip((1, -1), system.constraints):
        px, py = x + sign * r * sp.cos(th), y + sign * r * sp.sin(th)
        vx = sum(sp.diff(px, q) * dot(q.name) for q in (x, y, th))
        vy = sum(sp.diff(py, q) * dot(q.name) for q in (x, y, th))
        heading = th + sign * ph
        want = -sp.sin(heading) * vx + sp.cos(heading) * vy
        assert trig_zero(got - want)


def test_snakeboard_C_degenerates_at_right_angle_steering():
    system = snakeboard()
    C = lagrangian_geometry(system).constraint_matrix
    base = {**system.parameter_values, S("x"): 0.1, S("y"): 0.2, S("theta"): 0.3, S("psi"): 0.4}
    dets = []
    for eps in (1e-2, 1e-3):
        base[S("phi")] = np.pi / 2 - eps
        dets.append(np.linalg.det(_num(C, base)))
    # det C ~ cos(phi)^2 ~ eps^2: shrinks 100-fold when eps shrinks 10-fold
    assert dets[1] / dets[0] == pytest.approx(1e-2, rel=1e-2)
    base[S("phi")] = sp.pi / 2
    assert sp.Matrix(system.mu.xreplace(base)).rank() == 1


# ------------------------------------------------------------ holonomic
def test_pendulum_acceleration():
    """a = -g e_y + k (x, y), k = (g y - |v|^2)/l^2 (from d^2/dt^2 |q|^2 = 0)."""
    g, l = 9.81, 1.3
    system = pendulum_cartesian(l=l, m=0.7)
    assert len(system.holonomic) == 1 and system.m == 1
    rng = np.random.default_rng(7)
    for _ in range(4):
        p = point_on_M1(system, rng)
        a, _ = constrained_accelerations(system, p)
        q = np.array([p[S("x")], p[S("y")]])
        v = np.array([p[dot("x")], p[dot("y")]])
        k = (g * q[1] - v @ v) / l**2
        assert np.allclose(a, np.array([0, -g]) + k * q, rtol=1e-12, atol=1e-12)


def test_particle_on_sphere_acceleration():
    g, R = 9.81, 2.0
    system = particle_on_sphere(R=R)
    rng = np.random.default_rng(8)
    for _ in range(4):
        p = point_on_M1(system, rng)
        a, _ = constrained_accelerations(system, p)
        q = np.array([p[S(n)] for n in "xyz"])
        v = np.array([p[dot(n)] for n in "xyz"])
        k = (g * q[2] - v @ v) / R**2
        assert np.allclose(a, np.array([0, 0, -g]) + k * q, rtol=1e-12, atol=1e-12)


def test_two_particle_rod_multipliers():
    """Paper Ex. 4.1 with P1 = (x1, y1), P2 = (x2, y2); by hand, on M_1:
    C = -2 l^2 Id, lambda1 = |v2 - v1|^2/(2 l^2), lambda2 = (x2' y1' - x1' y2' - g X)/l^2."""
    g, l = 9.81, 1.5
    system = two_particle_rod(l=l)
    assert [q.name for q in system.coordinates] == ["x1", "x2", "y1", "y2"]
    x1, x2, y1, y2 = (S(n) for n in ("x1", "x2", "y1", "y2"))
    assert sp.expand(system.holonomic[0] - ((x2 - x1)**2 + (y2 - y1)**2 - S("l")**2) / 2) == 0
    geo = lagrangian_geometry(system)
    rng = np.random.default_rng(9)
    for _ in range(4):
        p = point_on_M1(system, rng)
        assert np.allclose(_num(geo.constraint_matrix, p), -2 * l**2 * np.eye(2), atol=1e-12)
        _, lam = constrained_accelerations(system, p)
        x1d, x2d, y1d, y2d = (p[dot(n)] for n in ("x1", "x2", "y1", "y2"))
        X = p[x2] - p[x1]
        assert lam[0] == pytest.approx(((x2d - x1d)**2 + (y2d - y1d)**2) / (2 * l**2), rel=1e-12)
        assert lam[1] == pytest.approx((x2d * y1d - x1d * y2d - g * X) / l**2, rel=1e-12)


# ---------------------------------------------------------- paper Sec. 3
def test_paper_example_3_1_is_fully_degenerate():
    geo = lagrangian_geometry(paper_example_3_1())
    assert geo.constraint_matrix == sp.zeros(1, 1)
    assert sp.simplify(geo.constraint_derivatives[0]) == 0


def test_paper_example_3_2_secondary_constraint():
    geo = lagrangian_geometry(paper_example_3_2())
    assert geo.constraint_matrix == sp.zeros(1, 1)
    assert sp.simplify(geo.constraint_derivatives[0] - S("q1")) == 0


# ------------------------------------------------------------------ snake
def _hand_centre_velocities(N, th, v, l):
    """Centre velocities written from the chain geometry: c_{i+1} = c_i + l/2 (e_i + e_{i+1})."""
    perp = [sp.Matrix([-sp.sin(t), sp.cos(t)]) for t in th]
    vel = [sp.Matrix([v[0], v[1]])]
    for i in range(1, N):
        vel.append(vel[-1] + l / 2 * (perp[i - 1] * v[2 + i - 1] + perp[i] * v[2 + i]))
    return vel


def test_snake1_is_the_knife_edge():
    m, l = S("m"), S("l")
    system = snake(1, symbolic=True)
    th, x, y = S("theta1"), S("x"), S("y")
    knife = m * (dot("x")**2 + dot("y")**2) / 2 + m * l**2 / 12 * dot("theta1")**2 / 2
    assert sp.expand(system.lagrangian - knife) == 0
    assert list(system.coordinates) == [x, y, th]
    assert sp.expand(system.constraints[0] - (-sp.sin(th) * dot("x") + sp.cos(th) * dot("y"))) == 0


def test_snake2_against_hand_written_energy():
    """T = m|c1'|^2/2 + m|c2'|^2/2 + (m l^2/12)(t1'^2 + t2'^2)/2 with
    c2 = c1 + (l/2)(cos t1 + cos t2, sin t1 + sin t2)."""
    m, l = S("m"), S("l")
    t1, t2 = S("theta1"), S("theta2")
    xd, yd, t1d, t2d = dot("x"), dot("y"), dot("theta1"), dot("theta2")
    c2x = xd - l / 2 * (sp.sin(t1) * t1d + sp.sin(t2) * t2d)
    c2y = yd + l / 2 * (sp.cos(t1) * t1d + sp.cos(t2) * t2d)
    T = (m * (xd**2 + yd**2) / 2 + m * (c2x**2 + c2y**2) / 2
         + m * l**2 / 24 * (t1d**2 + t2d**2))
    system = snake(2, symbolic=True)
    assert trig_zero(system.lagrangian - T)
    # knife edge at the centre of link 2: no velocity across the link
    across = -sp.sin(t2) * c2x + sp.cos(t2) * c2y
    assert trig_zero(system.constraints[1] - across)


@pytest.mark.parametrize("N", [3, 4])
def test_snake_energy_and_constraints_from_chain_geometry(N):
    m, l = S("m"), S("l")
    system = snake(N, symbolic=True)
    th = [S(f"theta{i}") for i in range(1, N + 1)]
    v = list(system.velocities)
    vel = _hand_centre_velocities(N, th, v, l)
    T = sum(m * (c.T * c)[0] / 2 for c in vel) + sum(m * l**2 / 24 * w**2 for w in v[2:])
    assert trig_zero(system.lagrangian - T)
    for i, c in enumerate(vel):
        across = -sp.sin(th[i]) * c[0] + sp.cos(th[i]) * c[1]
        assert trig_zero(system.constraints[i] - across)
    # the plotting helper agrees with the chain: d/dt of its centres
    for (X, Y), c in zip(snake_centres(N), vel):
        dX = sum(sp.diff(X, q) * w for q, w in zip(system.coordinates, v))
        dY = sum(sp.diff(Y, q) * w for q, w in zip(system.coordinates, v))
        assert sp.expand(dX - c[0]) == 0 and sp.expand(dY - c[1]) == 0


def test_snake_sizes():
    for N in (1, 2, 5):
        system = snake(N)
        assert (system.n, system.m) == (N + 2, N)
        assert system.is_linear


# --------------------------------------------------------------- examples
_MODEL_OF_EXAMPLE = {
    "rolling_disk.toml": rolling_disk,
    "knife_edge_inclined.toml": knife_edge_inclined,
    "chaplygin_sleigh.toml": chaplygin_sleigh,
    "nonholonomic_particle.toml": nonholonomic_particle,
    "rolling_ball.toml": rolling_ball,
    "ball_on_turntable.toml": ball_on_turntable,
    "snakeboard.toml": snakeboard,
    "pendulum_cartesian.toml": pendulum_cartesian,
    "particle_on_sphere.toml": particle_on_sphere,
    "paper_4_1_two_particle_rod.toml": two_particle_rod,
    "paper_3_1.toml": paper_example_3_1,
    "paper_3_2.toml": paper_example_3_2,
}


def _example_files():
    return sorted(p.name for p in EXAMPLES.glob("*.toml"))


def test_expected_examples_exist():
    names = set(_example_files())
    assert set(_MODEL_OF_EXAMPLE) <= names
    assert {"paper_2_1_rolling_disk.toml", "redundant_disk.toml"} <= names


@pytest.mark.parametrize("filename", [f for f in _example_files() if f != "redundant_disk.toml"])
def test_example_loads_with_consistent_initial_data(filename):
    scene_mod = pytest.importorskip("nhham.system.scene")
    scene = scene_mod.load_scene(EXAMPLES / filename)
    residuals = pytest.importorskip("nhham.system.initial").check_initial(scene)
    if scene.initial is not None:
        assert residuals and max(abs(r) for r in residuals.values()) < 1e-14
    model = _MODEL_OF_EXAMPLE.get(filename)
    if model is not None:
        _assert_same_system(scene.system, model())


def _assert_same_system(got, want):
    assert got.coordinates == want.coordinates
    assert dict(got.parameter_values) == pytest.approx(dict(want.parameter_values))
    pairs = [(got.lagrangian, want.lagrangian)] + list(zip(got.phi, want.phi)) \
        + list(zip(got.holonomic, want.holonomic))
    assert len(got.phi) == len(want.phi) and len(got.holonomic) == len(want.holonomic)
    rng = np.random.default_rng(10)
    # The scene writes decimals where a model may have exact fractions, so
    # compare values at random points rather than expressions.
    for _ in range(3):
        point = dict(want.parameter_values)
        point.update({s: rng.uniform(0.3, 1.3) for s in want.state})
        for a, b in pairs:
            assert float(a.xreplace(point)) == pytest.approx(float(b.xreplace(point)),
                                                              rel=1e-13, abs=1e-13)


def test_redundant_disk_example_is_reported():
    scene_mod = pytest.importorskip("nhham.system.scene")
    with pytest.raises(RedundantConstraintError, match=r"constraints\[2\]"):
        scene_mod.load_scene(EXAMPLES / "redundant_disk.toml")


def test_redundant_disk_example_drops_to_the_rolling_disk():
    scene_mod = pytest.importorskip("nhham.system.scene")
    scene = scene_mod.load_scene(EXAMPLES / "redundant_disk.toml", drop_redundant=True)
    assert [d.label for d in scene.system.dropped] == ["constraints[2]"]
    _assert_same_system(scene.system, rolling_disk())


def test_redundant_disk_example_names_the_combination():
    scene_mod = pytest.importorskip("nhham.system.scene")
    with pytest.raises(RedundantConstraintError,
                       match=r"constraints\[2\].*redundant.*cos\(theta\).*sin\(theta\)"):
        scene_mod.load_scene(EXAMPLES / "redundant_disk.toml")


def test_make_snake_writes_a_loadable_scene(tmp_path):
    scene_mod = pytest.importorskip("nhham.system.scene")
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_snake", EXAMPLES / "make_snake.py")
    make_snake = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(make_snake)
    for N in (1, 4):
        path = tmp_path / f"snake_{N}.toml"
        assert make_snake.main([str(N), str(path)]) == 0
        scene = scene_mod.load_scene(path)
        assert max(abs(r) for r in pytest.importorskip("nhham.system.initial").check_initial(scene).values()) == 0.0
        _assert_same_system(scene.system, snake(N))
        assert "rank C = %d" % N in path.read_text()
        # the fallback writer (used when nhham.scene is missing) gives the same scene
        fallback = tmp_path / f"fallback_{N}.toml"
        fallback.write_text(make_snake._dump(snake(N), make_snake.initial_state(N)))
        again = scene_mod.load_scene(fallback)
        assert again.initial == scene.initial
        _assert_same_system(again.system, snake(N))
    assert make_snake.main(["0"]) == 2
