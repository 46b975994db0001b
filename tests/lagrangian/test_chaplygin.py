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
