"""Abelian Chaplygin reduction (nhham.lagrangian.chaplygin) against reductions by hand.

Reduced equations d/dt dL_c/dr' - dL_c/dr = J_a B^a r', with L_c = L(r, r', -A r'),
J = dL/ds' on M_1, B^a_{ab} = d_a A^a_b - d_b A^a_a (Bloch-Krishnaprasad-Marsden-Murray).
"""

from pathlib import Path

import pytest
import sympy as sp

from nhham import System, models
from nhham.errors import InputError
from nhham.lagrangian.chaplygin import chaplygin_reduction
from nhham.system.scene import load_scene

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def particle():
    return System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2", ["z_dot - y*x_dot"])


def test_the_nonholonomic_particle_reduces_as_by_hand():
    """s = z (the only cyclic coordinate solved everywhere), A = (-y, 0), J = y x',
    B_xy = 1: x'' = -y x' y'/(1 + y^2), y'' = 0."""
    red = chaplygin_reduction(particle())
    assert [str(s) for s in red.symmetry] == ["z"] and [str(r) for r in red.shape] == ["x", "y"]
    names = {str(s): s for s in red.lagrangian.free_symbols}
    Y, XD, YD = names["y"], names["x_dot"], names["y_dot"]
    assert sp.simplify(red.lagrangian - ((1 + Y**2) * XD**2 + YD**2) / 2) == 0
    assert sp.simplify(red.momenta[0] - Y * XD) == 0
    assert red.curvature[0] == sp.Matrix([[0, 1], [-1, 0]])
    assert sp.simplify(red.accelerations[0] + Y * XD * YD / (1 + Y**2)) == 0
    assert red.accelerations[1] == 0
    assert red.check.value and red.check.method == "exact"
    assert sp.simplify(red.reconstruction[0] - Y * XD) == 0   # z' = y x'
    # x is cyclic in L_c and J B r': d/dt((1 + y^2) x') = y x' y' (its momentum equation)
    (c, p, rate), = red.momentum_equations
    assert str(c) == "x" and sp.simplify(p - (1 + Y**2) * XD) == 0
    assert sp.simplify(rate - Y * XD * YD) == 0


def test_the_sleigh_reduces_with_its_symmetry_y():
    """s' = y' = tan(theta) x' + a theta'/cos(theta): A = (-tan, -a/cos), B_{x theta} =
    sec^2 theta; the lifted field is P(xi_L)'s (exact check)."""
    red = chaplygin_reduction(models.chaplygin_sleigh(), symmetry=["y"])
    theta = next(s for s in red.connection.free_symbols if s.name == "theta")
    a = next(s for s in red.connection.free_symbols if s.name == "a")
    assert sp.simplify(red.connection[0, 0] + sp.tan(theta)) == 0
    assert sp.simplify(red.connection[0, 1] + a / sp.cos(theta)) == 0
    assert sp.simplify(red.curvature[0][0, 1] - 1 / sp.cos(theta)**2) == 0
    assert red.check.value


def test_the_3d_rolling_disc_reduces_to_the_closed_form():
    """The uniform thin disc (I = m R^2/4 about a diameter, m R^2/2 about the axle) in the
    scene's angles (yaw phi, lean theta from the vertical, spin psi):
    phi'' = -2 psi' theta'/cos theta, theta'' = 4 g sin theta/(5R) + sin(2 theta) phi'^2/2
    + (6/5) cos theta phi' psi', psi'' = -(10 cos theta phi' - 12 tan theta psi') theta'/6;
    the check at 4 points of M_1 in 30 digits (n = 5: P(xi_L) not formed in closed form)."""
    red = chaplygin_reduction(load_scene(EXAMPLES / "rolling_disc_3d.toml").system)
    assert [str(s) for s in red.symmetry] == ["x", "y"]
    s = {str(v): v for e in red.accelerations for v in e.free_symbols}
    phid, thd_, psid, lean = s["yaw_dot"], s["lean_dot"], s["spin_dot"], s["lean"]
    g, R = s["g"], s["r"]
    expected = [-2 * psid * thd_ / sp.cos(lean),
                4 * g * sp.sin(lean) / (5 * R) + sp.sin(2 * lean) * phid**2 / 2
                + sp.Rational(6, 5) * sp.cos(lean) * phid * psid,
                -(10 * sp.cos(lean) * phid - 12 * sp.tan(lean) * psid) * thd_ / 6]
    for got, want in zip(red.accelerations, expected):
        assert sp.simplify(got - want) == 0
    # yaw and spin are cyclic in L_c and J B r': p_spin = (3/2) m R^2 (psi' + phi' sin theta)
    # with d/dt p_spin = -m R^2 theta' phi' cos theta (from the accelerations above)
    momentum = {str(c): (p, r) for c, p, r in red.momentum_equations}
    assert set(momentum) == {"yaw", "spin"}
    p_spin, rate = momentum["spin"]
    m = next(v for e in red.momenta for v in e.free_symbols if v.name == "m")
    assert sp.simplify(p_spin - sp.Rational(3, 2) * m * R**2 * (psid + phid * sp.sin(lean))) == 0
    assert sp.simplify(rate + m * R**2 * thd_ * phid * sp.cos(lean)) == 0
    assert red.check.value and red.check.method == "sampled"


@pytest.mark.parametrize("system, why", [
    (System(["x", "y"], "(x_dot**2 + y_dot**2)/2 - x - y", ["x_dot - y*y_dot"]),
     "cyclic coordinates"),
    (System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2", ["z_dot - y*x_dot"],
            holonomic=["x - y"]), "holonomic"),
    (System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2",
            ["x_dot**2 + y_dot**2 - 1"]), "not linear"),
])
def test_a_system_that_is_not_chaplygin_is_refused_saying_why(system, why):
    with pytest.raises(InputError, match="not of Chaplygin type") as info:
        chaplygin_reduction(system)
    assert why in str(info.value) and info.value.key == "constraints"


def test_a_symmetry_that_is_not_cyclic_is_refused():
    with pytest.raises(InputError, match="symmetry: y not cyclic"):
        chaplygin_reduction(particle(), symmetry=["y"])


def test_forces_reduce_with_the_virtual_displacements_of_the_symmetry():
    """A sleigh pushed along its axis (thrust F) with a drag -k v on its centre: shape
    (x, theta), symmetry y (dy = -A dr), so the force on r is Q_r - A^T Q_y at
    y' = -A r'. By hand in the forward speed u = (x' + a w sin theta)/cos theta and
    w = theta': m u' = m a w^2 + F - k u, (I + m a^2) w' = -a w (m u + k a) (the lateral
    drag k a w at the centre has the arm a about the blade), and x' = u cos theta -
    a w sin theta gives x'' = (F - k u) cos theta/m - u w sin theta + a^2 w sin theta
    (m u + k a)/(I + m a^2). Adding Q_x alone (without -A^T Q_y, the old reduction) is
    caught by the check against P(xi_L)."""
    sleigh = System(["x", "y", "theta"], "m*(x_dot**2 + y_dot**2)/2 + I*theta_dot**2/2",
                    ["-sin(theta)*x_dot + cos(theta)*y_dot - a*theta_dot"],
                    forces={"x": "F*cos(theta) - k*x_dot", "y": "F*sin(theta) - k*y_dot"},
                    parameters=["m", "I", "a", "F", "k"])
    red = chaplygin_reduction(sleigh, symmetry=["y"])
    s = {str(v): v for v in set(sleigh.parameters) | set(sleigh.coordinates)
         | set(sleigh.velocities)}
    m, I, a, F, k, th = s["m"], s["I"], s["a"], s["F"], s["k"], s["theta"]
    w, xd = s["theta_dot"], s["x_dot"]
    u = (xd + a * w * sp.sin(th)) / sp.cos(th)
    xdd = ((F - k * u) * sp.cos(th) / m - u * w * sp.sin(th)
           + a**2 * w * sp.sin(th) * (m * u + k * a) / (I + m * a**2))
    wd = -a * w * (m * u + k * a) / (I + m * a**2)
    assert sp.simplify(red.accelerations[0] - xdd) == 0
    assert sp.simplify(red.accelerations[1] - wd) == 0
    assert red.check.value and red.check.method == "exact"
    # the old reduced force Q_x (y' left in it, no -A^T Q_y): the check says no
    from nhham.lagrangian import chaplygin as module

    old = red.shape_forces.copy()
    old[0], old[1] = sleigh.forces[0], 0
    acc = module.reduced_accelerations(red.lagrangian, red.shape,
                                        red.shape_velocities, red.gyroscopic + old)
    on_m1 = dict(zip([s["y_dot"]], red.reconstruction))
    assert not module._check_at_points(sleigh, red.shape, on_m1, acc).value
