"""Models brought in from sympy.physics.mechanics as people write them.

- The 3-D rolling disc of sympy's own test_kane5.py (body-fixed speeds u,
  kinematic differential equations, rolling constraints in u), converted by
  ``from_mechanics`` to L(q, q') and affine constraints: nhham's
  accelerations, converted back to u', equal the reference values that
  test_kane5.py carries (computed there by KanesMethod) to 1e-10; its steady
  upright rolling has the textbook stability threshold w^2 = g / (3 r).
- Each accepted form of ``from_mechanics`` and each refusal, with the
  message naming the culprit.
"""

import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from sympy.physics import mechanics as me

import nhham
from nhham import ValidationError
from nhham.numerics.codegen import numeric_model
from nhham.numerics.linearization import linearize
from nhham.numerics.steady_sweep import sweep_steady
from nhham.system.mechanics import from_mechanics
from nhham.system.scene import load_scene

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
sys.path.insert(0, str(EXAMPLES))
import make_rolling_disc_3d as disc3d  # noqa: E402

t = me.dynamicsymbols._t

# test_kane5.py: p = (g, r, m), states (q1..q5, u1..u3) and the expected
# [q1'..q5', u1'..u5'] from KanesMethod's mass_matrix_full \ forcing_full.
KANE5 = [
    ((0.3, 0.1, 1.97, -0.35, 2.27), (-0.2, 1.3, 0.15),
     [0.126603940595934, 0.215942571601660, 1.28736069604936, 0.319764288376543,
      0.0989146857254898, -0.925848952664489, -0.0181350656532944, 2.91695398184589,
      -0.00992793421754526, 0.0412861634829171]),
    ((3.97, -0.28, 8.2, -0.35, 2.27), (-0.25, -2.2, 0.62),
     [0.0259159090798597, 0.668041660387416, -2.19283799213811, 0.385441810852219,
      0.420109283790573, 1.45030568179066, -0.0110924422400793, -8.35617840186040,
      -0.154098542632173, -0.146102664410010]),
]


@pytest.fixture(scope="module")
def disc():
    system = disc3d.build(dict(g=9.81, r=0.26, m=3.43))
    return system, numeric_model(system, backend="numpy")


def test_rolling_disc_accelerations_match_kane5_reference(disc):
    system, model = disc
    k = disc3d.kane_model()
    q, u = k["q"], k["u"]
    qd = sp.symbols("qd0:5")
    plain = {f.diff(t): s for f, s in zip(q, qd)}
    par = {sp.Symbol("g"): 9.81, sp.Symbol("r"): 0.26, sp.Symbol("m"): 3.43}
    # u as functions of (q, q'): the kinematic equations read u_i = kde_i + u_i
    u_of = [sp.expand(e + ui).xreplace(plain) for e, ui in zip(k["kdes"], u)]
    for qv, u3, expected in KANE5:
        sub = dict(zip(q, qv)) | par
        # q' and the dependent speeds u4, u5 from the kinematic equations and the
        # rolling constraints (which test_kane5 writes with u and q3')
        u45 = sp.symbols("u4v u5v")
        uv = list(u3) + list(u45)
        eqs = [e.xreplace(sub) - ui for e, ui in zip(u_of, uv)]
        eqs += [c.xreplace(plain).xreplace(dict(zip(u, uv))).xreplace(sub) for c in k["fnh"]]
        sol = sp.solve(eqs, list(qd) + list(u45), dict=True)[0]
        qdot = [float(sol[s]) for s in qd]
        y = np.array(list(qv) + qdot)
        acc = model.rhs(0.0, y)[5:]
        # u' = (du/dq) q' + (du/dq') q''
        point = sub | dict(zip(qd, qdot))
        udot = []
        for e in u_of:
            de = sum(sp.diff(e, a) * b for a, b in zip(q, qdot)) + sum(
                sp.diff(e, a) * b for a, b in zip(qd, acc))
            udot.append(float(de.xreplace(point)))
        got = np.array(qdot + udot)
        assert np.abs(got - np.array(expected)).max() < 1e-10, (got, expected)


def test_rolling_disc_upright_stability_threshold(disc):
    system, model = disc
    g, r, m = 9.81, 0.26, 3.43
    I1, I3 = m * r * r / 4, m * r * r / 2
    scene = load_scene(EXAMPLES / "rolling_disc_3d.toml")
    scene_model = numeric_model(scene.system, backend="numpy")
    for w in (1.0, 3.0, 6.0, 10.0):
        mw = scene_model.with_parameters(w=w)
        lin = linearize(mw, scene.steady.values(mw.parameters))
        lam2 = -(I3 * (I3 + m * r * r) * w * w - m * g * r * I1) / (I1 * (I1 + m * r * r))
        pair = [np.sqrt(complex(lam2)), -np.sqrt(complex(lam2))]
        nonzero = [z for z in lin.eigenvalues if abs(z) > 1e-9]
        assert len(nonzero) == 2
        assert max(min(abs(z - p) for p in pair) for z in nonzero) < 1e-10
        assert lin.spectrally_stable == (w * w > g / (3 * r))
    swept = sweep_steady(scene_model, scene.steady.values, "w", np.linspace(0.5, 6, 12))
    assert len(swept.crossings) == 1
    assert abs(swept.crossings[0].value - np.sqrt(g / (3 * r))) < 1e-8


# ------------------------------------------------------------- adapter forms
def _pendulum_parts():
    """A rigid pendulum rod hinged at O, angle a from the downward vertical."""
    a = me.dynamicsymbols("a")
    m, l, g = sp.symbols("m l g")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    B = N.orientnew("B", "Axis", [a, N.z])
    P = O.locatenew("P", -l / 2 * B.y)
    rod = me.RigidBody("rod", P, B, m, (me.inertia(B, 0, 0, m * l ** 2 / 12), P))
    return a, (m, l, g), N, O, B, P, rod


def test_bodies_and_gravity_give_T_minus_V():
    a, (m, l, g), N, O, B, P, rod = _pendulum_parts()
    system = from_mechanics(q=[a], bodies=[rod], loads=[(P, -m * g * N.y)], frame=N, origin=O)
    A, Ad = sp.symbols("a a_dot")
    expected = m * l ** 2 * Ad ** 2 / 6 + m * g * l / 2 * sp.cos(A)
    assert sp.simplify(system.lagrangian - expected.subs({})) == 0


def test_mechanics_system_with_speeds_and_kdes():
    a, (m, l, g), N, O, B, P, rod = _pendulum_parts()
    w = me.dynamicsymbols("w")
    B.set_ang_vel(N, 2 * w * N.z)       # angular velocity given by a speed
    msys = me.System(N, O)
    msys.add_coordinates(a)
    msys.add_speeds(w)
    msys.add_kdes(a.diff(t) - 2 * w)    # w = a'/2: not the identity
    msys.add_bodies(rod)
    msys.add_loads(me.Force(P, -m * g * N.y))
    system = from_mechanics(msys)
    A, Ad = sp.symbols("a a_dot")
    # omega = 2 w = a' once the kinematic equation is solved for w
    expected = m * l ** 2 * Ad ** 2 / 6 + m * g * l / 2 * sp.cos(A)
    assert sp.simplify(system.lagrangian - expected) == 0


def test_refusals_name_the_culprit():
    a, (m, l, g), N, O, B, P, rod = _pendulum_parts()
    u1, u2 = me.dynamicsymbols("u1 u2")
    # (a velocity constraint nonlinear in u is taken with Chetaev's rule since issue 36:
    # tests/system/test_mechanics.py::test_from_mechanics_brings_nonlinear_velocity_constraints)
    with pytest.raises(ValidationError, match=r"kd_eqs\[0\]: the term .*not affine"):
        from_mechanics(q=[a], bodies=[rod], frame=N, origin=O, u=[u1],
                       kd_eqs=[a.diff(t) - u1 ** 3])
    Q = me.Point("Q")
    Q.set_vel(N, 0)
    loose = me.Particle("loose", Q, m)
    with pytest.raises(ValidationError, match=r"bodies\[1\] \(loose\): its mass centre Q has "
                                              r"no position from the origin"):
        from_mechanics(q=[a], bodies=[rod, loose], frame=N, origin=O)
    with pytest.raises(ValidationError, match=r"u2\(t\), a function of time that is not one"):
        # a speed that no kinematic equation defines (test_kane3's ignorable wheel rates)
        B2 = N.orientnew("B2", "Axis", [0, N.z])
        B2.set_ang_vel(N, u2 * N.z)
        wheel = me.RigidBody("wheel", P, B2, m, (me.inertia(B2, 1, 1, 1), P))
        from_mechanics(q=[a], bodies=[rod, wheel], frame=N, origin=O, u=[u1],
                       kd_eqs=[a.diff(t) - u1])
    msys = me.System(N, O)
    msys.add_coordinates(a)
    msys.add_bodies(rod)
    msys.add_actuators(me.TorqueActuator(sp.Symbol("T"), N.z, B, N))
    # forces and actuators are accepted now (test_mechanics_forces.py): T on the angle a
    assert from_mechanics(msys).generalized_forces[0] == sp.Symbol("T")


@pytest.mark.parametrize("scene_file", ["rolling_disc_3d.toml", "differential_drive.toml"])
def test_points_route_agrees_with_the_numeric_saddle_solve(scene_file):
    """Stage 1 at exact points (rank of Z_i(phi_j), consistency) against numbers: C is
    well conditioned at random states of M_1 (rank m) and the saddle solve's accelerations
    keep every constraint: d(phi)/dt = 0 (so no secondary constraint appears)."""
    from nhham.lagrangian.geometry import LagrangianGeometry
    from nhham.lagrangian.tangency import tangency_at_points

    system = load_scene(EXAMPLES / scene_file).system
    geo = LagrangianGeometry(system)
    v = tangency_at_points(system, geo.hessian, geo.forcing,
                           list(system.holonomic) + list(system.phi), seed=7)
    assert int(v.rank.value) == system.m and bool(v.consistent.value)
    model = numeric_model(system, backend="numpy")
    rng = np.random.default_rng(3)
    for _ in range(5):
        y = model.project(rng.uniform(-1, 1, 2 * system.n)).y
        assert model.cond_C(y) < 1e8
        dy = model.rhs(0.0, y)
        h = 1e-7   # phi(y + h dy) - phi(y) = O(h^2) when the field keeps phi = 0
        assert np.abs(model.residuals(y + h * dy)[:system.m]).max() < 1e-10


def _blade_system(*constraints):
    """A knife edge (point mass and blade inertia) as a sympy.physics.mechanics System
    with speeds u = q' and the given nonholonomic constraints in u."""
    x, y, th = me.dynamicsymbols("x y theta")
    u = me.dynamicsymbols("u1:4")
    m, I = sp.symbols("m I")
    N, O = me.ReferenceFrame("N"), me.Point("O")
    B = N.orientnew("B", "Axis", [th, N.z])
    P = O.locatenew("P", x * N.x + y * N.y)
    msys = me.System(N, O)
    msys.add_coordinates(x, y, th)
    msys.add_speeds(*u)
    msys.add_kdes(*[q.diff(t) - s for q, s in zip((x, y, th), u)])
    msys.add_bodies(me.RigidBody("blade", P, B, m, (me.inertia(B, 0, 0, I), P)))
    msys.add_nonholonomic_constraints(*[c(th, u) for c in constraints])
    return msys


def _sideways(th, u):
    return sp.sin(th) * u[0] - sp.cos(th) * u[1]


def test_redundant_constraint_advice_can_be_followed():
    """The second constraint is twice the first: the message names it as the user knows
    it (nonholonomic_constraints[1]) and its advice, drop_redundant=True, is a keyword
    from_mechanics takes; the kept constraint is sin(theta) x' - cos(theta) y'."""
    msys = _blade_system(_sideways, lambda th, u: 2 * _sideways(th, u))
    with pytest.raises(ValidationError) as info:
        from_mechanics(msys)
    message = str(info.value)
    assert message.startswith("nonholonomic_constraints[1]: ")
    assert "= (2)*nonholonomic_constraints[0]" in message and "drop_redundant=True" in message
    assert info.value.key == "nonholonomic_constraints[1]"
    system = from_mechanics(msys, drop_redundant=True)
    x, y, th, xd, yd = sp.symbols("x y theta x_dot y_dot")
    assert system.m == 1 and len(system.dropped) == 1
    assert sp.expand(system.constraints[0] - (sp.sin(th) * xd - sp.cos(th) * yd)) == 0


def test_mechanics_objects_are_read_or_pointed_to_what_reads_them():
    """A LagrangesMethod is read as from_lagranges_method reads it; a KanesMethod (which
    holds equations of motion, not energies) is pointed to the System it comes from."""
    x, y = me.dynamicsymbols("x y")
    L = (x.diff(t) ** 2 + y.diff(t) ** 2) / 2
    lm = me.LagrangesMethod(L, [x, y], nonhol_coneqs=[x.diff(t) - y * y.diff(t)])
    system = from_mechanics(lm)
    X, Y, Xd, Yd = sp.symbols("x y x_dot y_dot")
    assert system.constraints == (Xd - Y * Yd,)
    msys = _blade_system(_sideways)
    km = me.KanesMethod(msys.frame, list(msys.q), list(msys.u), kd_eqs=list(msys.kdes))
    with pytest.raises(nhham.InputError, match="KanesMethod.*pass the sympy.physics.mechanics"
                                               ".System it is formed from"):
        from_mechanics(km)
