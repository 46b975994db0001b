"""A state given in Python by the user's own names: dynamicsymbols, a mechanics model's
speeds, nhham's names; only the independent entries, the rest solved (as a scene's
[initial] is), against values worked out by hand."""

import math

import pytest
import sympy as sp
from sympy.physics import mechanics as me

import nhham
from nhham.errors import InputError
from nhham.journeys import simulate as simulate_scene
from nhham.journeys.answer import as_scene
from nhham.system.state_keys import completed_state, state_entries

t = me.dynamicsymbols._t


def rolling_disk_mechanics():
    """The vertical disk in u-form: u1 = x', u2 = y', u3 = theta', u4 = R phi' (a speed
    that is not a q'), rolling x' = R cos(theta) phi', y' = R sin(theta) phi'."""
    x, y, th, ph = me.dynamicsymbols("x y theta phi")
    u1, u2, u3, u4 = me.dynamicsymbols("u1:5")
    m, I1, I2, R = sp.symbols("m I1 I2 R")
    L = m * (x.diff(t)**2 + y.diff(t)**2) / 2 + I1 * th.diff(t)**2 / 2 \
        + I2 * ph.diff(t)**2 / 2
    return nhham.from_mechanics(
        L, [x, y, th, ph], u=[u1, u2, u3, u4],
        kd_eqs=[x.diff(t) - u1, y.diff(t) - u2, th.diff(t) - u3, R * ph.diff(t) - u4],
        velocity_constraints=[u1 - u4 * sp.cos(th), u2 - u4 * sp.sin(th)],
        parameters={m: 1.0, I1: 0.25, I2: 0.5, R: 2.0}), (x, y, th, ph), (u1, u2, u3, u4)


def test_dynamicsymbols_and_speeds_name_the_state():
    """By hand (R = 2): u4 = 3 gives phi' = 3/2, then x' = R cos(theta) phi' = 3 cos 0.5,
    y' = 3 sin 0.5; theta' = u3 = 1."""
    disk, (x, y, th, ph), (u1, u2, u3, u4) = rolling_disk_mechanics()
    assert set(disk.speeds) == {u1, u2, u3, u4}
    state, solved = completed_state(disk, {x: 0, y: 0, th: 0.5, ph: 0, u3: 1, u4: 3},
                                    speeds=disk.speeds)
    assert state["phi_dot"] == pytest.approx(1.5) and state["theta_dot"] == 1.0
    assert state["x_dot"] == pytest.approx(3 * math.cos(0.5))
    assert state["y_dot"] == pytest.approx(3 * math.sin(0.5))
    assert set(solved) == {"x_dot", "y_dot"}
    assert state_entries(disk, {"theta": "pi/4", th.diff(t): 2}) == {"theta": sp.pi / 4,
                                                                      "theta_dot": 2}


def test_names_that_are_not_the_systems_are_refused():
    disk, (x, y, th, ph), speeds = rolling_disk_mechanics()
    z = me.dynamicsymbols("z")
    with pytest.raises(InputError, match="initial: z.* is not a coordinate"):
        state_entries(disk, {z: 1})
    with pytest.raises(InputError, match="uses k, which is not a parameter"):
        state_entries(disk, {x: sp.Symbol("k")})
    # two speeds that are the same combination x' + phi' fix x' and phi' no more than one
    xd, phid = disk.velocities[0], disk.velocities[3]
    with pytest.raises(InputError, match="do not determine"):
        completed_state(disk, {x: 0, y: 0, th: 0, ph: 0, speeds[0]: 1, speeds[1]: 0},
                        speeds={speeds[0]: xd + phid, speeds[1]: xd + phid})


def test_simulate_takes_the_users_names_and_solves_the_rest():
    """The disk from theta = 0 with theta' = 1 and u4 = R phi' = 4 (phi' = 2): the centre
    runs on a circle of radius R phi'/theta' = 4 (x = 4 sin t, y = 4 (1 - cos t)),
    through nhham.simulate and the simulate journey alike."""
    disk, (x, y, th, ph), (u1, u2, u3, u4) = rolling_disk_mechanics()
    given = {x: 0, y: 0, th: 0, ph: 0, u3: 1, u4: 4}
    run = nhham.simulate(disk, (0.0, 1.0), given, rtol=1e-11, atol=1e-12, warn=False)
    assert run.success
    assert run["x"][-1] == pytest.approx(4 * math.sin(1.0), abs=1e-8)
    assert run["y"][-1] == pytest.approx(4 * (1 - math.cos(1.0)), abs=1e-8)
    answer = simulate_scene(disk, t_end=1.0, initial=given,
                            options={"rtol": 1e-11, "atol": 1e-12})
    assert answer.succeeded
    final = dict(zip(answer.data["state"], answer.data["y_final"]))
    assert final["x"] == pytest.approx(4 * math.sin(1.0), abs=1e-8)
    assert as_scene(disk, initial=given).initial_solved == ("x_dot", "y_dot")


def test_linearize_takes_a_steady_motion_by_the_users_names():
    """A cart on a spring (k = 8, m = 2) with a pendulum-free mate constrained to follow
    it, y' = x', in u-form with u = 2 x' (a speed that is not a q'): at rest the
    eigenvalues are +-i sqrt(k/(2 m)) = +-i sqrt(2) (both masses move, the spring pulls
    one); the steady table gives x, y and u only, y' is solved."""
    x, y = me.dynamicsymbols("x y")
    u = me.dynamicsymbols("u")
    m, k = sp.symbols("m k")
    cart = nhham.from_mechanics(m * (x.diff(t)**2 + y.diff(t)**2) / 2 - k * x**2 / 2, [x, y],
                                u=[u], kd_eqs=[2 * x.diff(t) - u],
                                velocity_constraints=[y.diff(t) - u / 2],
                                parameters={m: 2.0, k: 8.0})
    answer = nhham.linearize(cart, steady={x: 0, y: 0, u: 0})
    eig = sorted(complex(re, im).imag for re, im in answer.data["eigenvalues"]
                 if abs(complex(re, im)) > 1e-9)
    assert eig == pytest.approx([-math.sqrt(2), math.sqrt(2)], abs=1e-12)


def sleigh_system():
    """The Chaplygin sleigh written as SymBRiM writes its bicycle: a
    ``sympy.physics.mechanics.System`` with speeds u_i = q_i' (kdes u_i - q_i'), the
    rolling constraint in the speeds (the contact P's velocity along the blade's normal),
    the parameters' values keyed by their Symbols. Contact P at (x, y), heading theta,
    mass centre G at a ahead of P, mass m, inertia I about G."""
    x, y, th = me.dynamicsymbols("x y theta")
    u1, u2, u3 = me.dynamicsymbols("u1:4")
    m, I, a = sp.symbols("m I a")
    N, O = me.ReferenceFrame("N"), me.Point("O")
    B = N.orientnew("B", "Axis", (th, N.z))
    B.set_ang_vel(N, u3 * N.z)
    P = O.locatenew("P", x * N.x + y * N.y)
    P.set_vel(N, u1 * N.x + u2 * N.y)
    G = P.locatenew("G", a * B.x)
    body = me.RigidBody("sleigh", G, B, m, (me.inertia(B, 0, 0, I), G))
    system = me.System(N, O)
    system.add_coordinates(x, y, th)
    system.add_speeds(u1, u2, u3)
    system.add_kdes(u1 - x.diff(t), u2 - y.diff(t), u3 - th.diff(t))
    system.add_bodies(body)
    system.add_nonholonomic_constraints(P.vel(N).dot(B.y))
    return system, (x, y, th), (u1, u2, u3), {m: 2.0, I: 0.5, a: 0.5}


def test_linearize_takes_a_mechanics_systems_speeds_as_its_steady_motion():
    """By hand: in the blade's frame (forward speed v of P, rate w = theta')
    m v' = m a w^2 and (I + m a^2) w' = -m a v w, so straight-ahead motion at v0 has,
    besides the neutral directions, the one eigenvalue -m a v0 / (I + m a^2); with
    v0 = u1 = 3 a = 1.5 (an expression in the model's Symbol a), m = 2, I = 0.5,
    a = 0.5: -1.5. The speed u2 = y' is solved from the constraint."""
    system, (x, y, th), (u1, u2, u3), values = sleigh_system()
    a = sp.Symbol("a")
    sleigh = nhham.from_mechanics(system, parameters=values)
    assert set(sleigh.speeds) == {u1, u2, u3}
    model = nhham.numeric_model(sleigh, backend="numpy")
    answer = nhham.linearize(sleigh, steady={x: 0, y: 0, th: 0, u1: 3 * a, u3: 0},
                             model=model)
    nonzero = [complex(re, im) for re, im in answer.data["eigenvalues"]
               if abs(complex(re, im)) > 1e-9]
    assert nonzero == [pytest.approx(-1.5, abs=1e-9)]
    assert answer.data["stable"] is True        # Re < 0: asymptotically stable


def test_a_swept_parameter_moves_the_entries_solved_from_the_given_ones():
    """The sleigh heading theta = pi/4 with x' = u1 = c given: y' = x' (the blade's
    normal is (-1, 1)/sqrt 2) is solved, and the forward speed is v0 = sqrt 2 c, so by
    the formula above the eigenvalue is -m a v0 / (I + m a^2) = -sqrt(2) c. The chart
    holds y' (not the given x'): at each swept c it must be solved again from x' = c
    (before, y' kept its value at c = 1 and the three points gave -sqrt 2 alike)."""
    system, (x, y, th), (u1, u2, u3), values = sleigh_system()
    c = sp.Symbol("c")
    sleigh = nhham.from_mechanics(system, parameters={**values, c: 1.0})
    model = nhham.numeric_model(sleigh, backend="numpy")
    answer = nhham.linearize(sleigh, steady={x: 0, y: 0, th: sp.pi / 4, u1: c, u3: 0},
                             model=model, sweep=("c", [0.5, 1.0, 2.0]))
    assert "y_dot" in answer.data["chart"] and "x_dot" not in answer.data["chart"]
    swept = answer.payload["sweep"]
    assert swept.coordinates == ("theta_dot",)
    assert [complex(e[0]) for e in swept.eigenvalues] == [
        pytest.approx(-math.sqrt(2) * cv, abs=1e-9) for cv in (0.5, 1.0, 2.0)]


def test_a_steady_table_left_short_is_named_steady():
    """Errors of a steady motion given in Python name the steady table, not [initial]."""
    system, (x, y, th), (u1, u2, u3), values = sleigh_system()
    sleigh = nhham.from_mechanics(system, parameters=values)
    with pytest.raises(InputError, match=r"^steady: no value for x") as caught:
        as_scene(sleigh, steady={y: 0, th: 0, u1: 1, u3: 0})
    assert caught.value.key == "steady"
