"""Forces through the sympy.physics.mechanics bridges (nhham.system.mechanics).

Loads, actuators and LagrangesMethod forcelists become nhham's generalized forces Q
(d/dt dL/dv - dL/dq = Q - mu^T lambda, DESIGN.md §2); ``to_lagranges_method`` carries Q
back. Every check is against a value the code under test does not compute: forces
derived by hand (springs, dampers, torques), sympy's own KanesMethod and
LagrangesMethod on the same model (equations of motion at random numeric points), and
the refusals' messages naming the load and the symbol at fault.
"""

import numpy as np
import pytest
import sympy as sp
from sympy.physics import mechanics as me

from nhham import System, ValidationError
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.numerics.codegen import numeric_model
from nhham.system.mechanics import from_lagranges_method, from_mechanics, to_lagranges_method

t = me.dynamicsymbols._t
S = sp.Symbol


def evaluate(matrix, point):
    return np.array(sp.Matrix(matrix).xreplace(point).evalf(), dtype=float).ravel()


def assert_close(a, b, tol):
    a, b = np.asarray(a, float), np.asarray(b, float)
    scale = max(1.0, np.abs(b).max(initial=0.0))
    assert np.abs(a - b).max(initial=0.0) <= tol * scale, (a, b)


def kane_rates(M, F, point):
    """[q'; u'] from KanesMethod's mass_matrix_full x = forcing_full at a numeric point."""
    Mn = np.array(M.xreplace(point).evalf(), dtype=float)
    Fn = np.array(F.xreplace(point).evalf(), dtype=float).ravel()
    return np.linalg.solve(Mn, Fn)


# ------------------------------------------------------------ a particle on a line
def test_particle_on_a_line_with_friction_gravity_and_an_input():
    """F = -c x' + F(t) along N.x: Q_x = F - c x_dot by hand; gravity -m g N.x (constant)
    goes into L as -m g x; the accelerations equal KanesMethod's at random points."""
    x, F, ux = me.dynamicsymbols("x F u_x")
    m, c, g = sp.symbols("m c g")
    N, O = me.ReferenceFrame("N"), me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x)
    particle = me.Particle("p", P, m)
    loads = [me.Force(P, (-c * x.diff(t) + F) * N.x), (P, -m * g * N.x)]
    system = from_mechanics(q=[x], bodies=[particle], loads=loads, frame=N, origin=O,
                            inputs=[F])
    X, Xd = S("x"), S("x_dot")
    assert system.inputs == (S("F"),) and system.time is None
    assert sp.expand(system.generalized_forces[0] - (S("F") - c * Xd)) == 0
    assert sp.expand(system.lagrangian - (m * Xd ** 2 / 2 - m * g * X)) == 0
    assert [p.name for p in system.declared_parameters] == ["c", "g", "m"]

    km = me.KanesMethod(N, [x], [ux], kd_eqs=[x.diff(t) - ux])
    kane_loads = [(P, (-c * ux + F) * N.x), (P, -m * g * N.x)]
    km.kanes_equations([particle], kane_loads)
    M, Fk = km.mass_matrix_full, km.forcing_full
    acc = lagrangian_geometry(system).accelerations
    rng = np.random.default_rng(1)
    for _ in range(4):
        xv, vv, Fv, mv, cv, gv = rng.uniform(-2, 2, 6)
        mv = abs(mv) + 0.5
        ours = evaluate(acc, {X: xv, Xd: vv, S("F"): Fv, m: mv, c: cv, g: gv})
        theirs = kane_rates(M, Fk, {x: xv, ux: vv, F: Fv, m: mv, c: cv, g: gv})
        assert_close(ours, theirs[1:], 1e-12)
        assert_close(ours, [(Fv - cv * vv) / mv - gv], 1e-12)  # by hand


def test_a_constant_force_with_a_plain_input_symbol_is_a_force_not_a_potential():
    """(P, F N.x) with F a plain Symbol listed in inputs: constant in N, but an input, so
    Q_x = F and L is the kinetic energy alone (F is no parameter)."""
    x = me.dynamicsymbols("x")
    F, m = sp.symbols("F m")
    N, O = me.ReferenceFrame("N"), me.Point("O")
    P = O.locatenew("P", x * N.x)
    system = from_mechanics(q=[x], bodies=[me.Particle("p", P, m)], loads=[(P, F * N.x)],
                            frame=N, origin=O, inputs=[F])
    assert system.generalized_forces[0] == F
    assert sp.expand(system.lagrangian - m * S("x_dot") ** 2 / 2) == 0
    assert system.declared_parameters == (m,) and system.inputs == (F,)


# ------------------------------------------------------------ torque on a disk
def _disk():
    th = me.dynamicsymbols("theta")
    I = sp.Symbol("I")
    N, O = me.ReferenceFrame("N"), me.Point("O")
    B = N.orientnew("B", "Axis", [th, N.z])
    disk = me.RigidBody("disk", O, B, sp.Symbol("m"), (me.inertia(B, 0, 0, I), O))
    return th, I, N, O, B, disk


@pytest.mark.parametrize("axis", ["N.z", "B.z"])
def test_torque_on_a_disk_is_its_generalized_force(axis):
    """Torque(B, tau z) on a disk turning about z: Q_theta = tau (z of N or of B: the same
    axis), and theta'' = tau / I."""
    th, I, N, O, B, disk = _disk()
    tau = sp.Symbol("tau")
    z = N.z if axis == "N.z" else B.z
    system = from_mechanics(q=[th], bodies=[disk], loads=[me.Torque(B, tau * z)], frame=N,
                            origin=O)
    assert system.generalized_forces[0] == tau
    assert sp.simplify(lagrangian_geometry(system).accelerations[0] - tau / I) == 0


def test_torque_tuple_with_an_input_and_explicit_time():
    """(B, T(t) cos(t) N.z): T becomes the input T, sympy's t nhham's time t."""
    th, I, N, O, B, disk = _disk()
    T = me.dynamicsymbols("T")
    system = from_mechanics(q=[th], bodies=[disk], loads=[(B, T * sp.cos(t) * N.z)],
                            frame=N, origin=O, inputs=[T])
    assert system.inputs == (S("T"),)
    assert system.time == S("t")
    assert system.generalized_forces[0] == S("T") * sp.cos(S("t"))
    assert system.parameters[-2:] == (S("T"), S("t"))


def test_pendulum_torque_and_moving_force_by_hand():
    """What used to be refused: a torque (B, 3 N.z) and a force -m g cos(a) N.x on the
    rod's centre P = (l/2 sin a, -l/2 cos a): Q_a = 3 - m g l cos(a)^2 / 2."""
    a = me.dynamicsymbols("a")
    m, l, g = sp.symbols("m l g")
    N, O = me.ReferenceFrame("N"), me.Point("O")
    B = N.orientnew("B", "Axis", [a, N.z])
    P = O.locatenew("P", -l / 2 * B.y)
    rod = me.RigidBody("rod", P, B, m, (me.inertia(B, 0, 0, m * l ** 2 / 12), P))
    system = from_mechanics(q=[a], bodies=[rod], frame=N, origin=O,
                            loads=[(B, 3 * N.z), (P, -m * g * sp.cos(a) * N.x)])
    A = S("a")
    expected = 3 - m * g * l * sp.cos(A) ** 2 / 2
    assert sp.simplify(system.generalized_forces[0] - expected) == 0
    assert not system.inputs and system.time is None


# ------------------------------------------------------------ actuators
def _planar_body():
    """A body at P = (x, y) turning by theta, as a me.System with speeds u = q'."""
    x, y, th = q = me.dynamicsymbols("x y theta")
    u = me.dynamicsymbols("u1:4")
    m, I = sp.symbols("m I")
    N, O = me.ReferenceFrame("N"), me.Point("O")
    O.set_vel(N, 0)
    B = N.orientnew("B", "Axis", [th, N.z])
    P = O.locatenew("P", x * N.x + y * N.y)
    msys = me.System(N, O)
    msys.add_coordinates(*q)
    msys.add_speeds(*u)
    msys.add_kdes(*[f.diff(t) - s for f, s in zip(q, u)])
    msys.add_bodies(me.RigidBody("body", P, B, m, (me.inertia(B, 0, 0, I), P)))
    return msys, q, u, N, O, B, P


X, Y, TH, XD, YD, THD = sp.symbols("x y theta x_dot y_dot theta_dot")
R = sp.sqrt(X ** 2 + Y ** 2)
k, l0, c, F0, T0 = sp.symbols("k l0 c F0 T0")
# Hand-derived closed forms: a force f along the unit vector (x, y)/r from O to P
# (positive pushes P away) has Q = f (x, y)/r; r' = (x x' + y y')/r.
# The ForceActuator's force is written in the speed u1 = x' (replaced through the kdes).
ACTUATORS = {
    "LinearSpring": (lambda N, O, B, P, u: me.LinearSpring(k, me.LinearPathway(O, P), l0),
                     [-k * (R - l0) * X / R, -k * (R - l0) * Y / R, 0]),
    "LinearDamper": (lambda N, O, B, P, u: me.LinearDamper(c, me.LinearPathway(O, P)),
                     [-c * (X * XD + Y * YD) * X / R ** 2, -c * (X * XD + Y * YD) * Y / R ** 2,
                      0]),
    "ForceActuator": (lambda N, O, B, P, u: me.ForceActuator(F0 * u[0], me.LinearPathway(O, P)),
                      [F0 * XD * X / R, F0 * XD * Y / R, 0]),
    "TorqueActuator": (lambda N, O, B, P, u: me.TorqueActuator(T0, N.z, B, N), [0, 0, T0]),
}


@pytest.mark.parametrize("kind", sorted(ACTUATORS))
def test_each_actuator_gives_the_hand_derived_generalized_force(kind):
    make, expected = ACTUATORS[kind]
    msys, q, u, N, O, B, P = _planar_body()
    msys.add_actuators(make(N, O, B, P, u))
    system = from_mechanics(msys)
    assert not system.inputs
    for got, want in zip(system.generalized_forces, expected):
        assert sp.simplify(got - want) == 0, (got, want)


def test_actuators_keyword_and_loads_in_speeds():
    """actuators= in from_mechanics and a load written in speeds (u = q'/2 for theta)."""
    x, y, th = q = me.dynamicsymbols("x y theta")
    w = me.dynamicsymbols("w")
    Tin = me.dynamicsymbols("T_in")
    m, I = sp.symbols("m I")
    N, O = me.ReferenceFrame("N"), me.Point("O")
    B = N.orientnew("B", "Axis", [th, N.z])
    P = O.locatenew("P", x * N.x + y * N.y)
    body = me.RigidBody("body", P, B, m, (me.inertia(B, 0, 0, I), P))
    system = from_mechanics(
        q=list(q), u=[w], kd_eqs=[th.diff(t) - 2 * w], bodies=[body], frame=N, origin=O,
        loads=[(B, -c * w * N.z)],
        actuators=[me.TorqueActuator(Tin, N.z, B, N),
                   me.LinearSpring(k, me.LinearPathway(O, P), l0)],
        inputs=[Tin])
    expected = [-k * (R - l0) * X / R, -k * (R - l0) * Y / R, S("T_in") - c * THD / 2]
    for got, want in zip(system.generalized_forces, expected):
        assert sp.simplify(got - want) == 0, (got, want)
    assert system.inputs == (S("T_in"),)


# ------------------------------------------------------------ differential drive
def _driven_robot():
    """examples/make_differential_drive.py's robot as a me.System with speeds (the wheel
    rates independent), wheel motors (TorqueActuator, the chassis reacting) and a drag
    on the axle midpoint written in speeds."""
    q = me.dynamicsymbols("x y theta phiL phiR")
    x, y, theta, phiL, phiR = q
    u = me.dynamicsymbols("u1:6")
    TL, TR = me.dynamicsymbols("T_L T_R")
    mc, Ic, mw, Iw, Id, r, b, d, cd = sp.symbols("mc Ic mw Iw Id r b d c_d")
    N, O = me.ReferenceFrame("N"), me.Point("O")
    O.set_vel(N, 0)
    C = N.orientnew("C", "Axis", [theta, N.z])
    WL = C.orientnew("WL", "Axis", [phiL, C.y])
    WR = C.orientnew("WR", "Axis", [phiR, C.y])
    A = O.locatenew("A", x * N.x + y * N.y)
    G = A.locatenew("G", d * C.x)
    PL = A.locatenew("PL", b * C.y)
    PR = A.locatenew("PR", -b * C.y)
    bodies = [me.RigidBody("chassis", G, C, mc, (me.inertia(C, 0, 0, Ic), G)),
              me.RigidBody("left_wheel", PL, WL, mw, (me.inertia(C, Id, Iw, Id), PL)),
              me.RigidBody("right_wheel", PR, WR, mw, (me.inertia(C, Id, Iw, Id), PR))]

    def contact(P, W):
        return P.pos_from(O).dt(N) + me.cross(W.ang_vel_in(N), -r * N.z)

    in_u = {f.diff(t): s for f, s in zip(q, u)}
    cons = [A.pos_from(O).dt(N).dot(C.y), contact(PL, WL).dot(C.x), contact(PR, WR).dot(C.x)]
    msys = me.System(N, O)
    msys.add_coordinates(*q)
    msys.add_speeds(u[3], u[4])
    msys.add_speeds(u[0], u[1], u[2], independent=False)
    msys.add_kdes(*[f.diff(t) - s for f, s in zip(q, u)])
    msys.add_bodies(*bodies)
    msys.add_nonholonomic_constraints(*[sp.expand(c.xreplace(in_u)) for c in cons])
    msys.add_actuators(me.TorqueActuator(TL, C.y, WL, C), me.TorqueActuator(TR, C.y, WR, C))
    msys.add_loads(me.Force(A, -cd * (u[0] * N.x + u[1] * N.y)))
    values = {mc: 4.0, Ic: 0.08, mw: 0.3, Iw: 0.0015, Id: 0.001, r: 0.1, b: 0.15, d: 0.05,
              cd: 0.7}
    return msys, q, u, (TL, TR), values


def test_differential_drive_with_wheel_torques_agrees_with_kanes_method():
    msys, q, u, (TL, TR), values = _driven_robot()
    system = from_mechanics(msys, parameters={s.name: v for s, v in values.items()},
                            inputs=[TL, TR])
    assert system.n == 5 and system.m == 3 and system.inputs == (S("T_L"), S("T_R"))
    Q = list(system.generalized_forces)
    assert Q == [-S("c_d") * S("x_dot"), -S("c_d") * S("y_dot"), 0, S("T_L"), S("T_R")]

    msys.form_eoms()
    M, F = msys.mass_matrix_full, msys.forcing_full
    speeds = list(msys.u)           # u4, u5 (independent), then u1, u2, u3
    model = numeric_model(system, backend="numpy")
    mu = sp.lambdify(system.coordinates, system.mu.xreplace(system.parameter_values), "numpy")
    rng = np.random.default_rng(5)
    for _ in range(3):
        qv = rng.uniform(-1, 1, 5)
        tl, tr = rng.uniform(-0.5, 0.5, 2)
        # velocities on the constraints: wheel rates free, (x', y', theta') solved
        Mu = np.asarray(mu(*qv), float)
        wheels = rng.uniform(-3, 3, 2)
        dependent = np.linalg.solve(Mu[:, :3], -Mu[:, 3:] @ wheels)
        v = np.concatenate([dependent, wheels])
        y = np.concatenate([qv, v])
        ours = model.with_parameters(T_L=tl, T_R=tr).rhs(0.0, y)
        point = dict(values)
        point.update(zip(q, qv))
        point.update({s: v[int(s.func.__name__[1:]) - 1] for s in speeds})
        point.update({TL: tl, TR: tr})
        rates = kane_rates(M, F, point)
        u_dot = dict(zip(speeds, rates[5:]))
        theirs = np.concatenate([rates[:5], [u_dot[s] for s in u]])
        assert_close(ours, theirs, 1e-10)


# ------------------------------------------------------------ LagrangesMethod
def _knife_edge_lagranges_method():
    """A knife edge (x, y, theta) driven along its blade by F(t) cos(t), with a viscous
    drag, a turning torque tau(t) and a lateral spring, as a LagrangesMethod forcelist."""
    x, y, th = q = me.dynamicsymbols("x y theta")
    F, tau = me.dynamicsymbols("F tau")
    m, I, c, ky = sp.symbols("m I c k_y")
    N = me.ReferenceFrame("N")
    B = N.orientnew("B", "Axis", [th, N.z])
    P = me.Point("P")
    P.set_vel(N, x.diff(t) * N.x + y.diff(t) * N.y)
    L = m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2 + I * th.diff(t) ** 2 / 2
    forcelist = [(P, F * sp.cos(t) * B.x - c * (x.diff(t) * N.x + y.diff(t) * N.y)),
                 (P, -ky * y * N.y), (B, tau * N.z)]
    lm = me.LagrangesMethod(L, list(q), forcelist=forcelist, frame=N,
                            nonhol_coneqs=[sp.sin(th) * x.diff(t) - sp.cos(th) * y.diff(t)])
    return lm, q, (F, tau), {m: 1.3, I: 0.4, c: 0.3, ky: 2.0}


def test_from_lagranges_method_reads_the_forcelist():
    lm, q, (F, tau), values = _knife_edge_lagranges_method()
    system = from_lagranges_method(lm, parameters={s.name: v for s, v in values.items()},
                                   inputs=[F, tau])
    assert system.inputs == (S("F"), S("tau")) and system.time == S("t")
    Fs, Ts, tt, c, ky = S("F"), S("tau"), S("t"), S("c"), S("k_y")
    by_hand = [Fs * sp.cos(tt) * sp.cos(TH) - c * XD,
               Fs * sp.cos(tt) * sp.sin(TH) - c * YD - ky * Y, Ts]
    for got, want in zip(system.generalized_forces, by_hand):
        assert sp.simplify(got - want) == 0, (got, want)

    lm.form_lagranges_equations()
    rhs = lm.rhs()
    model = numeric_model(system, backend="numpy")
    rng = np.random.default_rng(8)
    for _ in range(4):
        xv, yv, thv, speed, omega, Fv, tv, time = rng.uniform(-1.5, 1.5, 8)
        v = [speed * np.cos(thv), speed * np.sin(thv), omega]
        point = dict(values)
        point.update(zip(q, [xv, yv, thv]))
        point.update(zip([f.diff(t) for f in q], v))
        point.update({F: Fv, tau: tv, t: time})
        theirs = evaluate(rhs, point)
        ours = model.with_parameters(F=Fv, tau=tv).rhs(time, np.array([xv, yv, thv] + v))
        assert_close(ours, theirs[:6], 1e-12)


def test_lagranges_method_through_from_mechanics_takes_inputs():
    lm, q, (F, tau), values = _knife_edge_lagranges_method()
    system = from_mechanics(lm, inputs=[F, tau])
    assert system.inputs == (S("F"), S("tau"))
    assert [p.name for p in system.declared_parameters] == ["I", "c", "k_y", "m"]


# ------------------------------------------------------------ round trip
def _forced_disk():
    """The vertical rolling disk with a driving torque u(t) on the wheel, a steering
    torque k_s sin(t) and a Rayleigh dissipation on the heading (nhham's own forces)."""
    return System(
        ["x", "y", "theta", "phi"],
        "m*(x_dot**2 + y_dot**2)/2 + I1*theta_dot**2/2 + I2*phi_dot**2/2",
        constraints=["x_dot - R*cos(theta)*phi_dot", "y_dot - R*sin(theta)*phi_dot"],
        parameters={"m": 1.2, "I1": 0.4, "I2": 0.3, "R": 0.5, "k_s": 0.8, "c": 0.25},
        forces={"phi": "u - c*phi_dot", "theta": "k_s*sin(t)"},
        dissipation="c*theta_dot**2/2", inputs=["u"])


def test_to_lagranges_method_carries_the_forces():
    system = _forced_disk()
    form = to_lagranges_method(system)
    lm, qs, maps = form
    assert lm.inertial is not None and len(lm.forcelist) == 2
    assert maps.to_mechanics[S("u")] == me.dynamicsymbols("u")
    assert maps.from_mechanics[me.dynamicsymbols("u")] == S("u")
    lm.form_lagranges_equations()
    # lm.eom = d/dt dL/dq' - dL/dq - Q + mu^T lam; the same as nhham's equations of motion
    eom = lm.eom.xreplace(maps.from_mechanics)
    ours = lagrangian_geometry(system).equations_of_motion
    for a, b in zip(eom, ours):
        assert sp.simplify(a - b) == 0, (a, b)
    # and numerically: LagrangesMethod's accelerations equal nhham's
    M = lm.mass_matrix_full.xreplace(maps.from_mechanics)
    F = lm.forcing_full.xreplace(maps.from_mechanics)
    model = numeric_model(system, backend="numpy")
    rng = np.random.default_rng(13)
    for _ in range(3):
        qv = rng.uniform(-1, 1, 4)
        th_dot, phi_dot, uv, time = rng.uniform(-2, 2, 4)
        v = [0.5 * np.cos(qv[2]) * phi_dot, 0.5 * np.sin(qv[2]) * phi_dot, th_dot, phi_dot]
        point = dict(system.parameter_values)
        point.update(zip(system.state, list(qv) + v))
        point.update({S("u"): uv, S("t"): time})
        x = np.linalg.solve(np.array(M.xreplace(point).evalf(), float),
                            np.array(F.xreplace(point).evalf(), float).ravel())
        y = np.concatenate([qv, v])
        assert_close(model.with_parameters(u=uv).rhs(time, y)[4:], x[4:8], 1e-12)


def test_round_trip_keeps_the_generalized_forces():
    system = _forced_disk()
    lm = to_lagranges_method(system).lm
    back = from_lagranges_method(lm, parameters=dict(system.parameter_values), inputs=["u"])
    assert back.inputs == system.inputs and back.time == system.time
    for a, b in zip(back.generalized_forces, system.generalized_forces):
        assert sp.expand(a - b) == 0


# ------------------------------------------------------------ refusals
def _line():
    x = me.dynamicsymbols("x")
    N, O = me.ReferenceFrame("N"), me.Point("O")
    P = O.locatenew("P", x * N.x)
    return x, N, O, P, dict(q=[x], bodies=[me.Particle("p", P, S("m"))], frame=N, origin=O)


def test_unlisted_function_of_time_is_refused_naming_load_and_symbol():
    x, N, O, P, common = _line()
    G = me.dynamicsymbols("G")
    with pytest.raises(ValidationError) as info:
        from_mechanics(**common, loads=[(P, -x * N.x), (P, G * N.x)])
    message = str(info.value)
    assert message.startswith("loads[1]: ") and "G(t)" in message and "inputs=[G(t)]" in message
    # listed, it is an input
    system = from_mechanics(**common, loads=[(P, -x * N.x), (P, G * N.x)], inputs=[G])
    assert system.generalized_forces[0] == S("G") - S("x")


def test_what_cannot_be_a_force_is_refused_naming_the_culprit():
    x, N, O, P, common = _line()
    with pytest.raises(ValidationError, match=r"loads\[1\]: .* is not a load"):
        from_mechanics(**common, loads=[(P, N.x), "gravity"])
    with pytest.raises(ValidationError, match=r"loads\[0\]: the force .* depends on the "
                                              r"acceleration Derivative\(x\(t\), \(t, 2\)\)"):
        from_mechanics(**common, loads=[(P, -x.diff(t, 2) * N.x)])
    loose = me.Point("Q")
    with pytest.raises(ValidationError, match=r"loads\[0\]: the point Q has no position from "
                                              r"the origin O"):
        from_mechanics(**common, loads=[(loose, -x.diff(t) * N.x)])
    with pytest.raises(ValidationError, match=r"actuators\[0\]: .* is not an actuator"):
        from_mechanics(**common, actuators=[42])
    T = me.dynamicsymbols("T")
    with pytest.raises(ValidationError, match=r"lagrangian: the term .*T\(t\)"):
        from_mechanics(x.diff(t) ** 2 / 2 + T * x, [x], inputs=[T])
    with pytest.raises(ValidationError, match=r"inputs\[0\]: x\(t\) is a coordinate"):
        from_mechanics(**common, inputs=[x])


def test_lagranges_method_force_on_an_unlisted_function_is_refused():
    lm, q, (F, tau), values = _knife_edge_lagranges_method()
    with pytest.raises(ValidationError) as info:
        from_lagranges_method(lm, inputs=[F])
    assert "forcelist[2]" in str(info.value) and "tau(t)" in str(info.value)


def test_more_refusals_name_the_culprit():
    x, N, O, P, common = _line()
    with pytest.raises(ValidationError, match=r"loads\[0\]: .* is not a Vector"):
        from_mechanics(**common, loads=[(P, x)])
    B = me.ReferenceFrame("B")   # not oriented relative to N
    with pytest.raises(ValidationError, match=r"loads\[0\]: the vector x\(t\)\*B.z cannot be "
                                              r"expressed in N"):
        from_mechanics(**common, loads=[(P, x * B.z)])
    with pytest.raises(ValidationError, match=r"inputs\[0\]: t is the time"):
        from_mechanics(**common, inputs=[t])
