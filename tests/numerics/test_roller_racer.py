"""The roller racer of examples/roller_racer.toml end to end (issue 34: a user's model with a
thrust motor, drag and a joint motor), against an independent route: sympy's KanesMethod
built here from the bodies (generalized speeds u = q', the side-slip speeds y' and theta'
dependent), lambdify and scipy's solve_ivp. Nothing expected comes from nhham.

Checked: the accelerations and multipliers at random states on M_1; classify's verdict
(C regular, not integrable, both constraints second class on T*Q: the Poisson bracket of
the constraints' momenta forms, computed here, is not zero); the open and closed loop's
(A, B) about the straight run; simulate from the [initial] that gives only the independent
velocities (the dependent ones solved and named), with DOP853 and with --set; RATTLE on the
free roller racer (W depends on q: the compiled loop); from_mechanics of the same bodies.
"""

from __future__ import annotations

import json
import types

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from sympy.physics import mechanics as me

from nhham.numerics.codegen import c_compiler, numeric_model
from nhham.system.scene import load_scene, loads_scene
from tests.cli.conftest import EXAMPLES, run_inprocess

SCENE = EXAMPLES / "roller_racer.toml"
Q = ("x", "y", "theta", "phi")
PARAMS = ("m1", "I1", "m2", "I2", "d1", "d2", "c")


def _bodies():
    """The roller racer in sympy.physics.mechanics with speeds u = q' (kinematic
    equations q' - u = 0): the pieces KanesMethod and from_mechanics take."""
    q = me.dynamicsymbols("x y theta phi")
    u = me.dynamicsymbols("ux uy uth uphi")
    F, tau = me.dynamicsymbols("F tau")
    m1, I1, m2, I2, d1, d2, c = sp.symbols(PARAMS)
    x, y, th, ph = q
    N, O = me.ReferenceFrame("N"), me.Point("O")
    O.set_vel(N, 0)
    A = N.orientnew("A", "Axis", [th, N.z])
    B = A.orientnew("B", "Axis", [ph, A.z])
    A.set_ang_vel(N, u[2] * N.z)
    B.set_ang_vel(N, (u[2] + u[3]) * N.z)
    C1 = O.locatenew("C1", x * N.x + y * N.y)
    C1.set_vel(N, u[0] * N.x + u[1] * N.y)
    J = C1.locatenew("J", -d1 * A.x)
    J.v2pt_theory(C1, N, A)
    C2 = J.locatenew("C2", -d2 * B.x)
    C2.v2pt_theory(J, N, B)
    return types.SimpleNamespace(
        q=q, u=u, inputs=(F, tau), frame=N, origin=O,
        bodies=[me.RigidBody("front", C1, A, m1, (me.inertia(A, 0, 0, I1), C1)),
                me.RigidBody("rear", C2, B, m2, (me.inertia(B, 0, 0, I2), C2))],
        loads=[(C1, F * A.x - c * C1.vel(N)), (C2, -c * C2.vel(N)), (B, tau * N.z),
               (A, -tau * N.z)],
        kd=[qi.diff() - ui for qi, ui in zip(q, u)],
        constraints=[C1.vel(N).dot(A.y), C2.vel(N).dot(B.y)])


@pytest.fixture(scope="module")
def kane():
    """M(q, u) u' = f(q, u, F, tau) from KanesMethod (the dependent speeds' rows are the
    constraints' derivatives), the dependent speeds solved from the constraints, the
    kinetic metric W and the constraint rows mu, all lambdified."""
    b = _bodies()
    km = me.KanesMethod(b.frame, q_ind=b.q, u_ind=[b.u[0], b.u[3]],
                        u_dependent=[b.u[1], b.u[2]], kd_eqs=b.kd,
                        velocity_constraints=b.constraints)
    km.kanes_equations(b.bodies, b.loads)
    qs, us = sp.symbols(Q), sp.symbols("ux uy uth uphi")
    ins, ps = sp.symbols("F tau"), sp.symbols(PARAMS)
    plain = {**dict(zip(b.q, qs)), **dict(zip(b.u, us)), **dict(zip(b.inputs, ins))}
    # M's columns are in KanesMethod's order of the speeds (independent first): put them
    # in the order of q, so that M q'' = f
    M = sp.Matrix.hstack(*[km.mass_matrix[:, list(km.u).index(ui)] for ui in b.u])
    M, f = M.xreplace(plain), km.forcing.xreplace(plain)
    cons = sp.Matrix(b.constraints).xreplace(plain)
    mu = cons.jacobian(us)                     # the constraints are linear in u
    dep = sp.solve(list(cons), [us[1], us[2]], dict=True)[0]
    T = sum(body.kinetic_energy(b.frame) for body in b.bodies)
    T = sp.expand(T.xreplace(plain))
    W = sp.hessian(T, us)
    args = (qs, us, ps, ins)
    lam = sp.lambdify
    return types.SimpleNamespace(
        M=lam(args, M, "numpy"), f=lam(args, f, "numpy"), mu=lam(args, mu, "numpy"),
        W=lam(args, W, "numpy"), dep=lam((qs, us, ps), [dep[us[1]], dep[us[2]]], "numpy"),
        dT_dq=lam(args, sp.Matrix([T.diff(qk) for qk in qs]), "numpy"),
        dT_dvdq=lam(args, sp.Matrix([[T.diff(ua).diff(qk) for qk in qs] for ua in us]),
                    "numpy"),
        bodies=b)


@pytest.fixture(scope="module")
def scene():
    return load_scene(SCENE)


def named(scene):
    """The scene's parameter values by name."""
    return {str(k): v for k, v in scene.system.parameter_values.items()}


def values(scene):
    return tuple(named(scene)[p] for p in PARAMS)


def on_m1(kane, p, q, ux, uphi):
    """The state (q, q') on M_1 with x' and phi' given (y', theta' solved)."""
    uy, uth = kane.dep(q, (ux, 0.0, 0.0, uphi), p)
    return np.array([*q, ux, uy, uth, uphi], dtype=float)


def kane_accelerations(kane, p, y, inputs):
    q, u = y[:4], y[4:]
    return np.linalg.solve(np.array(kane.M(q, u, p, inputs), dtype=float),
                           np.array(kane.f(q, u, p, inputs), dtype=float).ravel())


def kane_run(kane, p, y0, t_end, law):
    """solve_ivp (DOP853, rtol 1e-13) of the field in the chart (q, x', phi'), the
    dependent speeds solved at each state: it stays on M_1 by construction."""
    def rhs(_, z):
        y = on_m1(kane, p, z[:4], z[4], z[5])
        a = kane_accelerations(kane, p, y, law(y))
        return [*y[4:], a[0], a[3]]

    z0 = [*y0[:4], y0[4], y0[7]]
    sol = solve_ivp(rhs, (0.0, t_end), z0, method="DOP853", rtol=1e-13, atol=1e-13)
    z = sol.y[:, -1]
    return on_m1(kane, p, z[:4], z[4], z[5])


def random_states(kane, p, count, seed):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        q = (*rng.uniform(-2, 2, 2), *rng.uniform(-1, 1, 2))
        yield on_m1(kane, p, q, *rng.uniform(-2, 2, 2)), tuple(rng.uniform(-1, 1, 2))


def test_accelerations_and_multipliers_at_random_states(kane, scene):
    """nhham's q'' and lambda against KanesMethod's, and lambda from Lagrange's equations
    d/dt dT/dv - dT/dq - Q = -mu^T lambda with KanesMethod's q'' (Q from the same loads:
    the residual of the first two rows' complement vanishes)."""
    p = values(scene)
    model = numeric_model(scene.system)
    for y, (F, tau) in random_states(kane, p, 20, seed=34):
        at = model.with_parameters(F=F, tau=tau)
        a = kane_accelerations(kane, p, y, (F, tau))
        got = at.rhs(0.0, y)
        np.testing.assert_allclose(got[:4], y[4:], rtol=0, atol=1e-15)
        np.testing.assert_allclose(got[4:], a, rtol=0, atol=1e-12 * max(1.0, abs(a).max()))
        q, v = y[:4], y[4:]
        W = np.array(kane.W(q, v, p, (F, tau)), dtype=float)
        lhs = (W @ a + np.array(kane.dT_dvdq(q, v, p, (F, tau)), dtype=float) @ v
               - np.array(kane.dT_dq(q, v, p, (F, tau)), dtype=float).ravel()
               - _generalized_forces(kane, p, y, (F, tau)))
        mu = np.array(kane.mu(q, v, p, (F, tau)), dtype=float)
        lam, *_ = np.linalg.lstsq(-mu.T, lhs, rcond=None)
        assert np.abs(-mu.T @ lam - lhs).max() < 1e-12 * max(1.0, abs(lhs).max())
        np.testing.assert_allclose(at.multipliers(y), lam, rtol=0,
                                   atol=1e-12 * max(1.0, abs(lam).max()))


def _generalized_forces(kane, p, y, inputs):
    """Q_A = sum of F . dv/dq'_A over the loads, by hand (forces on C1 and C2, torques)."""
    x, yy, th, ph, xd, yd, thd, phd = y
    m1, I1, m2, I2, d1, d2, c = p
    F, tau = inputs
    e1, e2 = np.array([np.cos(th), np.sin(th)]), np.array([-np.sin(th), np.cos(th)])
    f2 = np.array([-np.sin(th + ph), np.cos(th + ph)])
    v1 = np.array([xd, yd])
    v2 = v1 - d1 * thd * e2 - d2 * (thd + phd) * f2
    # partial velocities of C1 and C2 with respect to (x', y', theta', phi')
    P1 = np.array([[1, 0], [0, 1], [0, 0], [0, 0]], dtype=float)
    P2 = np.array([[1, 0], [0, 1], -d1 * e2 - d2 * f2, -d2 * f2])
    force1, force2 = F * e1 - c * v1, -c * v2
    return P1 @ force1 + P2 @ force2 + np.array([0, 0, 0, tau])


def poisson_bracket(kane, p, y):
    """{Psi_1, Psi_2}(q, p) with Psi_i = mu_i(q) W(q)^-1 p, at the momenta p = W v of the
    state y (the q-derivatives by five-point differences at fixed p)."""
    q, v = y[:4], y[4:]
    mu = np.array(kane.mu(q, v, p, (0.0, 0.0)), dtype=float)
    W = np.array(kane.W(q, v, p, (0.0, 0.0)), dtype=float)
    pm = W @ v

    def psi(qq):
        return (np.array(kane.mu(qq, v, p, (0.0, 0.0)), dtype=float)
                @ np.linalg.solve(np.array(kane.W(qq, v, p, (0.0, 0.0)), dtype=float), pm))

    dpsi_dq = np.column_stack([derivative(psi, q, k) for k in range(4)])
    dpsi_dp = mu @ np.linalg.inv(W)
    return dpsi_dq[0] @ dpsi_dp[1] - dpsi_dp[0] @ dpsi_dq[1]


def test_classify_verdict(kane, scene):
    """C = -mu W^-1 mu^T has rank 2 (W > 0, mu of rank 2); ker mu is not involutive (the
    bracket of two fields in it leaves it); on T*Q, Psi_i(q, p) = mu_i W^-1 p, and
    {Psi_1, Psi_2} != 0 at a point of M_1: both second class. With point masses
    (I1 = I2 = 0, by --set) the bracket vanishes: both first class, still not integrable."""
    rc, out, err = run_inprocess("classify", str(SCENE), "--json")
    assert rc == 0, err
    r = json.loads(out)["result"]
    assert (r["regular"], r["rank_c"], r["status"]) == (True, 2, "determined")
    p = values(scene)
    y, inputs = next(random_states(kane, p, 1, seed=7))
    q, v = y[:4], y[4:]
    mu = np.array(kane.mu(q, v, p, inputs), dtype=float)
    W = np.array(kane.W(q, v, p, inputs), dtype=float)
    Wi = np.linalg.inv(W)
    assert np.linalg.matrix_rank(mu @ Wi @ mu.T) == 2
    assert abs(poisson_bracket(kane, p, y)) > 1e-3
    assert abs(poisson_bracket(kane, p[:1] + (0.0,) + p[2:3] + (0.0,) + p[4:], y)) < 1e-9
    rc, out, err = run_inprocess("classify", str(SCENE), "--set", "I1=0", "--set", "I2=0",
                                 "--json")
    assert rc == 0, err
    r0 = json.loads(out)["result"]
    assert (r0["integrable"], r0["first_class"], r0["second_class"]) == (False, 2, 0), r0
    assert _involutive(kane) is False
    assert r["integrable"] is False, r
    assert (r["first_class"], r["second_class"]) == (0, 2), r


def _involutive(kane):
    """ker mu spanned by X = d/dx + tan(theta) d/dy + theta'(1, 0) d/dtheta (x' = 1,
    phi' = 0) and Y = the same with x' = 0, phi' = 1; [X, Y] in ker mu?"""
    qs, us = sp.symbols(Q), sp.symbols("ux uy uth uphi")
    b = kane.bodies
    plain = {**dict(zip(b.q, qs)), **dict(zip(b.u, us))}
    cons = sp.Matrix(b.constraints).xreplace(plain)
    dep = sp.solve(list(cons), [us[1], us[2]], dict=True)[0]

    def field(ux, uphi):
        vals = {us[0]: ux, us[3]: uphi}
        return sp.Matrix([ux, dep[us[1]].subs(vals), dep[us[2]].subs(vals), uphi])

    X, Y = field(1, 0), field(0, 1)
    q = sp.Matrix(qs)
    lie = Y.jacobian(q) * X - X.jacobian(q) * Y
    mu = cons.jacobian(us)
    miss = sp.simplify(mu * lie)
    return all(e == 0 for e in miss)


def closed_loop_law(scene, p_kp=None, p_kd=None):
    """The scene's [control] laws as written in examples/roller_racer.toml, by hand."""
    pv = named(scene)
    kp, kd = p_kp if p_kp is not None else pv["kp"], p_kd if p_kd is not None else pv["kd"]
    thrust = 2 * pv["c"] * pv["U"]
    return lambda y: (thrust, -kp * y[3] - kd * y[7])


def derivative(g, z, k, h=1e-3):
    """dg/dz_k by the five-point central difference: error h^4 g^(5) / 30 ~ 1e-13 here,
    rounding ~ eps |g| / h ~ 1e-13."""
    def at(t):
        w = np.array(z, dtype=float)
        w[k] += t
        return np.asarray(g(w), dtype=float)

    return (8 * (at(h) - at(-h)) - (at(2 * h) - at(-2 * h))) / (12 * h)


def my_jacobian(kane, scene):
    """(A, B) of the field in the chart z = (x, y, theta, phi, x', phi') at the straight
    run, inputs (F, tau) at (2 c U, 0): the field (q', x'', phi'') of KanesMethod with the
    dependent speeds solved at each z, differentiated by five-point differences."""
    pv, p = named(scene), values(scene)
    z0 = np.array([0.0, 0.0, 0.0, 0.0, pv["U"], 0.0])
    u0 = np.array([2 * pv["c"] * pv["U"], 0.0])

    def field(z, inputs):
        y = on_m1(kane, p, z[:4], z[4], z[5])
        a = kane_accelerations(kane, p, y, inputs)
        return np.array([*y[4:], a[0], a[3]])

    A = np.column_stack([derivative(lambda z: field(z, u0), z0, k) for k in range(6)])
    B = np.column_stack([derivative(lambda u: field(z0, u), u0, k) for k in range(2)])
    return A, B


CHART = ("x", "y", "theta", "phi", "x_dot", "phi_dot")


@pytest.fixture(scope="module")
def linearized():
    from nhham.journeys import linearize

    return linearize(load_scene(SCENE)).payload


def test_linearisation_of_the_open_and_closed_loop(kane, scene, linearized):
    """The open loop's (A, B) and the closed loop's A + B K (K of the joint servo,
    tau = -kp phi - kd phi') in nhham's chart against the KanesMethod Jacobian; the
    speed's eigenvalue -2 c / (m1 + m2) by hand."""
    A, B = my_jacobian(kane, scene)
    pv = named(scene)
    opened, closed = linearized["open_loop"], linearized["linearization"]
    assert opened.chart == closed.chart == CHART
    np.testing.assert_allclose(opened.full_matrix, A, rtol=0, atol=1e-8)
    keep = [CHART.index(name) for name in opened.coordinates]
    assert opened.coordinates == ("phi", "x_dot", "phi_dot")
    np.testing.assert_allclose(opened.input_matrix, B[keep], rtol=0, atol=1e-8)
    K = np.zeros((2, 6))
    K[1, 3], K[1, 5] = -pv["kp"], -pv["kd"]
    np.testing.assert_allclose(closed.full_matrix, A + B @ K, rtol=0, atol=1e-8)
    mine = np.linalg.eigvals((A + B @ K)[np.ix_(keep, keep)])
    speed = -2 * pv["c"] / (pv["m1"] + pv["m2"])
    assert np.min(np.abs(mine - speed)) < 1e-12
    np.testing.assert_allclose(sorted(closed.eigenvalues, key=lambda e: (e.real, e.imag)),
                               sorted(mine, key=lambda e: (e.real, e.imag)), atol=1e-8)
    assert closed.stable is True and opened.stable is False
    assert max(np.linalg.eigvals(A[np.ix_(keep, keep)]).real) > 0    # free joint: unstable


def test_sweep_finds_where_the_servo_damps_the_joint(kane, scene):
    """linearize --sweep kd: the joint's pair crosses the imaginary axis where the servo's
    damping cancels the free joint's, kd = A[phi', phi'] / B[phi', tau] of the open loop
    (KanesMethod's Jacobian; the closed loop's phi'' row is A's minus kd B's in phi')."""
    from nhham.journeys import linearize

    A, B = my_jacobian(kane, scene)
    edge = A[5, 5] / B[5, 1]
    swept = linearize(load_scene(SCENE), sweep=("kd", np.linspace(-0.01, 0.02, 7))
                      ).payload["sweep"]
    assert [c.kind for c in swept.crossings] == ["complex"]
    assert swept.crossings[0].value == pytest.approx(edge, abs=1e-8)
    assert swept.crossings[0].direction == -1        # stable above the edge
    # the crossing pair: the closed loop's phi row there, lambda^2 = A[phi', phi] - kp B
    pv = named(scene)
    omega = np.sqrt(-(A[5, 3] - pv["kp"] * B[5, 1]))
    assert abs(swept.crossings[0].eigenvalue.imag) == pytest.approx(omega, rel=1e-8)


def test_state_space_widths(linearized):
    """Issue 34 item 8: the closed loop has no external input (B of width 0); the open
    loop has one column per input (F, tau)."""
    opened, closed = linearized["open_loop"], linearized["linearization"]
    assert closed.state_space().B.shape == (3, 0)
    assert closed.state_space().D.shape == (3, 0)
    assert opened.inputs == ("F", "tau")
    assert opened.state_space().B.shape == (3, 2)
    assert opened.state_space().D.shape == (3, 2)


def simulate_json(*argv):
    rc, out, err = run_inprocess("simulate", *map(str, argv), "--json")
    assert rc == 0, err
    return json.loads(out)


def final_state(env):
    r = env["result"]
    return dict(zip(r["state"], r["y_final"]))


def initial_state(kane, scene):
    """[initial] gives q, x' and phi'; y' and theta' from the constraints (by KanesMethod's
    dependent speeds)."""
    p = values(scene)
    return on_m1(kane, p, (0.0, 0.0, 0.0, 0.3), 0.5, 0.0)


def test_initial_solves_the_dependent_velocities_and_names_them(kane, scene):
    """Issue 34 item 4: [initial] gives x_dot and phi_dot only."""
    env = simulate_json(SCENE, "--t-end", "0.5")
    y0 = initial_state(kane, scene)
    solved = [w for w in env["warnings"] if w.startswith("initial: solved")]
    # at theta = 0 constraints[0] fixes y_dot = 0 exactly (not a rounding residue)
    assert len(solved) == 1 and "y_dot = 0, theta_dot = " in solved[0]
    theta_dot = float(solved[0].split("theta_dot = ")[1].split(",")[0])
    assert theta_dot == pytest.approx(y0[6], rel=1e-9)


@pytest.mark.parametrize("t_end", [3.0])
def test_simulate_dop853_against_solve_ivp(kane, scene, t_end):
    """The closed loop from [initial] (the joint servo straightens the racer): the end
    state of nhham simulate (DOP853, rtol 1e-10) against KanesMethod + solve_ivp."""
    env = simulate_json(SCENE, "--t-end", t_end, "--rtol", "1e-12", "--atol", "1e-12")
    got = final_state(env)
    want = kane_run(kane, values(scene), initial_state(kane, scene), t_end,
                    closed_loop_law(scene))
    np.testing.assert_allclose([got[n] for n in (*Q, *(f"{c}_dot" for c in Q))], want,
                               rtol=0, atol=1e-8)


def test_set_changes_a_gain(kane, scene):
    """Issue 34 item 5: --set kp=5 --set c=0.2 is the run with those values (the steady
    thrust law 2 c U moves with c)."""
    env = simulate_json(SCENE, "--t-end", 2.0, "--rtol", "1e-12", "--atol", "1e-12",
                        "--set", "kp=5", "--set", "c=0.2")
    assert env["scene"]["set"] == {"kp": 5.0, "c": 0.2}
    p = list(values(scene))
    p[PARAMS.index("c")] = 0.2
    pv = dict(named(scene), c=0.2, kp=5.0)
    law = (lambda y: (2 * pv["c"] * pv["U"], -pv["kp"] * y[3] - pv["kd"] * y[7]))
    y0 = on_m1(kane, tuple(p), (0.0, 0.0, 0.0, 0.3), 0.5, 0.0)
    want = kane_run(kane, tuple(p), y0, 2.0, law)
    got = final_state(env)
    np.testing.assert_allclose([got[n] for n in (*Q, *(f"{c}_dot" for c in Q))], want,
                               rtol=0, atol=1e-8)


def free_scene_text():
    """The roller racer without forces, inputs, [steady] inputs and [control] (coasting)."""
    keep, skip = [], False
    for line in SCENE.read_text().splitlines():
        if line.startswith("["):
            skip = line == "[control]"
        if skip or line.startswith(("inputs", "forces", "F =", "tau =")):
            continue
        keep.append(line)
    return "\n".join(keep) + "\n"


def test_rattle_on_the_free_roller_racer(kane, scene, tmp_path):
    """Issue 34 item 6: W depends on q; RATTLE runs in the compiled loop (the result says
    so when a compiler is there) and ends where KanesMethod + solve_ivp does: rattle to
    1e-8 at h = 5e-4 with its order 2 seen (halving h divides the error by 4), rattle4 at
    h = 5e-3."""
    path = tmp_path / "free.toml"
    path.write_text(free_scene_text())
    assert not loads_scene(path.read_text()).system.inputs
    p = values(scene)[:-1] + (0.0,)          # no drag (c = 0), no thrust, no joint torque
    want = kane_run(kane, p, initial_state(kane, scene), 1.0, lambda y: (0.0, 0.0))
    errors = {}
    for method, step in (("rattle", 1e-3), ("rattle", 5e-4), ("rattle4", 5e-3)):
        env = simulate_json(path, "--method", method, "--step", step, "--t-end", 1.0)
        if c_compiler():
            assert env["result"]["settings"]["backend"] == "c"
        got = final_state(env)
        errors[method, step] = np.abs(np.array([got[n] for n in (*Q, *(f"{c}_dot" for c in Q))])
                                      - want).max()
    assert errors["rattle", 5e-4] < 1e-8 and errors["rattle4", 5e-3] < 1e-8, errors
    assert 3.5 < errors["rattle", 1e-3] / errors["rattle", 5e-4] < 4.5, errors


def test_from_mechanics_of_the_same_bodies(kane, scene):
    """from_mechanics of the pieces KanesMethod took (speeds u, kinematic equations,
    constraints in u, loads) gives the scene's accelerations."""
    from nhham import from_mechanics

    b = _bodies()
    system = from_mechanics(q=b.q, u=b.u, kd_eqs=b.kd, bodies=b.bodies, loads=b.loads,
                            frame=b.frame, origin=b.origin,
                            velocity_constraints=b.constraints, inputs=b.inputs,
                            parameters={k: named(scene)[k] for k in PARAMS})
    assert system.inputs == tuple(sp.symbols("F tau"))
    ours = numeric_model(system, backend="numpy")    # its equations, without a compile
    theirs = numeric_model(scene.system)
    p = values(scene)
    for y, (F, tau) in random_states(kane, p, 5, seed=3):
        a = kane_accelerations(kane, p, y, (F, tau))
        for model in (ours, theirs):
            got = model.with_parameters(F=F, tau=tau).rhs(0.0, y)[4:]
            np.testing.assert_allclose(got, a, rtol=0, atol=1e-12 * max(1.0, abs(a).max()))


def test_initial_with_velocities_that_are_not_independent_is_refused(tmp_path):
    """Issue 34 item 4: x_dot and y_dot given at theta = 0 (constraints[0] fixes y_dot from
    x_dot) leave theta_dot and phi_dot open: exit 2, one line naming both."""
    head, tail = SCENE.read_text().split("[initial]\n")
    path = tmp_path / "dependent.toml"
    path.write_text(head + "[initial]\n" + tail.replace("phi_dot = 0.0\n", "y_dot = 0.1\n", 1))
    rc, out, err = run_inprocess("simulate", str(path), "--t-end", "0.1")
    assert rc == 2 and out == "" and err.count("\n") == 1
    assert "theta_dot, phi_dot are not fixed" in err
    assert "(constraints[0] relates x_dot, y_dot)" in err


def newton_contact_forces(kane, p, y, inputs):
    """The wheels' side forces f1 A.y at C1 and f2 B.y at C2 from the momentum balance of
    the whole racer, m1 a_C1 + m2 a_C2 = f1 A.y + f2 B.y + F A.x - c (v_C1 + v_C2) (the
    joint's forces cancel), with KanesMethod's accelerations and a_C2 from the kinematics
    of C2 = C1 - d1 A.x - d2 B.x: two equations for f1, f2 (A.y, B.y independent when
    phi != 0)."""
    m1, I1, m2, I2, d1, d2, c = p
    F, _ = inputs
    th, ph, thd, phd = y[2], y[3], y[6], y[7]
    a = kane_accelerations(kane, p, y, inputs)

    def frame(angle):
        return np.array([np.cos(angle), np.sin(angle)]), np.array([-np.sin(angle),
                                                                   np.cos(angle)])

    ax, ay = frame(th)
    bx, by = frame(th + ph)
    v1 = y[4:6]
    v2 = v1 - d1 * thd * ay - d2 * (thd + phd) * by
    a1 = a[:2]
    a2 = (a1 - d1 * (a[2] * ay - thd**2 * ax)
          - d2 * ((a[2] + a[3]) * by - (thd + phd)**2 * bx))
    rhs = m1 * a1 + m2 * a2 - F * ax + c * (v1 + v2)
    f1, f2 = np.linalg.solve(np.column_stack([ay, by]), rhs)
    return np.array([*(f1 * ay), 0.0]), np.array([*(f2 * by), 0.0])


def test_contact_forces_at_the_wheels(kane, scene):
    """The [contacts] forces (from the multipliers) against the momentum balance, at
    random states and at the start of the scene's run (inputs from the [control] laws)."""
    from nhham.numerics.contact_forces import contact_forces

    p = values(scene)
    model = numeric_model(scene.system)
    for y, inputs in random_states(kane, p, 5, seed=11):
        at = model.with_parameters(F=inputs[0], tau=inputs[1])
        got = contact_forces(scene.system, scene.contacts, y, at.multipliers(y),
                             parameters={"F": inputs[0], "tau": inputs[1]})
        for name, want in zip(("front", "rear"), newton_contact_forces(kane, p, y, inputs)):
            np.testing.assert_allclose(got.forces[name][0], want, rtol=0, atol=1e-12)
    env = simulate_json(SCENE, "--t-end", "0.5")
    y0 = initial_state(kane, scene)
    start = newton_contact_forces(kane, p, y0, closed_loop_law(scene)(y0))
    for name, want in zip(("front", "rear"), start):
        np.testing.assert_allclose(env["result"]["contact_forces"][name]["force"][0], want,
                                   rtol=0, atol=1e-12)
