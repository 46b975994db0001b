"""A second Chaplygin step (nhham.lagrangian.chaplygin_stages): the Chaplygin ball on the
level (M, gamma) = 0 and the rubber ball, against the literature's multipliers.

On the 4-dimensional T*S of the second stage (shape pitch, roll), Omega_nh = dr ^ dp -
g dr1 ^ dr2 with g = -G_12 linear in p: theta ^ Omega = -d Omega solves to
theta = ((W^-1 c)_2, -(W^-1 c)_1) with c = dG_12/dr' and W the Hessian of L_c2 (written out by
hand from the four triples), and the factor f with d(f Omega) = 0 has d ln f = theta.
The expected f come from the literature, in the body-frame vertical gamma (from
sympy.physics.mechanics, the scene's z-x-y angles) with D = m r^2, A = (I + D E)^-1:

- Chaplygin's ball on (M, gamma) = 0: (1 - D (gamma, A gamma))^(-1/2) (Borisov & Mamaev,
  Math. Notes 70 (2001); Fedorov & Jovanovic 2004);
- the rubber ball (no twist): (gamma, A gamma)^(-1/2) (Ehlers, Koiller, Montgomery &
  Rios 2005: the rubber ball is Hamiltonizable).

Both are decided exactly: theta - d ln f reduces to 0 modulo sin^2 + cos^2 = 1 at the
scene's parameter values, and vanishes at an exact point with the parameters symbolic.
"""

from pathlib import Path

import pytest
import sympy as sp
from sympy.physics import mechanics as me

from nhham import System
from nhham.errors import InputError
from nhham.lagrangian.algebra import normal_form
from nhham.lagrangian.chaplygin import chaplygin_reduction
from nhham.lagrangian.chaplygin_stages import reduce_again
from nhham.system.scene import load_scene

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.fixture(scope="module")
def sphere():
    system = load_scene(EXAMPLES / "chaplygin_sphere.toml").system
    return system, chaplygin_reduction(system, ["x", "y"])


def theta_of(stage):
    """theta from the four triples of theta ^ Omega = -d Omega (module docstring)."""
    v = list(stage.shape_velocities)
    W = sp.hessian(stage.lagrangian, v)
    c = sp.Matrix([sp.diff(stage.gyroscopic_form[0, 1], w) for w in v])
    u = W.LUsolve(c)
    return [u[1], -u[0]]


def literature(stage, rubber):
    names = {str(s): s for s in stage.system.parameters}
    I1, I2, I3, m, r = (names[k] for k in ("I1", "I2", "I3", "m", "r"))
    pitch, roll = stage.shape
    N = me.ReferenceFrame("N")
    B = N.orientnew("B", "Body", [sp.Symbol("yaw"), pitch, roll], "ZXY")
    gamma = sp.Matrix([N.z.dot(B.x), N.z.dot(B.y), N.z.dot(B.z)])
    D = m * r**2
    gAg = (gamma.T * (sp.diag(I1, I2, I3) + D * sp.eye(3)).inv() * gamma)[0]
    return gAg ** sp.Rational(-1, 2) if rubber else (1 - D * gAg) ** sp.Rational(-1, 2)


def assert_factor(stage, f):
    """theta = d ln f: an identity in the angles at the scene's exact parameter values
    (reduced modulo sin^2 + cos^2 = 1; with the parameters symbolic the same reduction
    takes 20 s), and with the parameters symbolic at an exact point whose sines and cosines
    are rational (3/5, 4/5; 5/13, 12/13)."""
    theta = theta_of(stage)
    values = stage.system.exact_parameter_values
    pitch, roll = stage.shape
    point = {sp.sin(pitch): sp.Rational(3, 5), sp.cos(pitch): sp.Rational(4, 5),
             sp.sin(roll): sp.Rational(5, 13), sp.cos(roll): sp.Rational(12, 13)}
    for t, q in zip(theta, stage.shape):
        difference = t - sp.diff(sp.log(f), q)
        assert normal_form(difference.xreplace(values)) == 0
        assert sp.cancel(difference.xreplace(point)) == 0


def test_the_chaplygin_ball_on_the_zero_level_has_borisov_mamaev_s_multiplier(sphere):
    """x, y, then yaw on p_yaw = 0: p_yaw's rate is 0 (the vertical angular momentum about
    the contact point), J2 = p_yaw = 0 on the level, the lifted field is P(xi_L)'s at
    points of M_1 on the level, and theta = d ln (1 - D (gamma, A gamma))^(-1/2)."""
    system, first = sphere
    assert [str(c) for c, _, rate in first.momentum_equations] == ["yaw"]
    stage = reduce_again(first, ["yaw"], level={"yaw": 0})
    assert [str(r) for r in stage.shape] == ["pitch", "roll"]
    assert [str(s) for s in stage.symmetry] == ["x", "y", "yaw"]
    assert stage.momenta == sp.Matrix([0]) and stage.level == ((stage.eliminated[0], 0),)
    assert stage.check.value and stage.check.method == "sampled"
    data = stage.to_dict()
    assert data["level"] == {"yaw": "0"} and data["shape_constraints"] == []
    assert [s["by"] for s in data["stages"]] == ["symmetry", "momentum level"]
    assert_factor(stage, literature(stage, rubber=False))


def test_the_rubber_ball_reduces_by_its_no_twist_constraint_and_is_hamiltonizable(sphere):
    """Rolling without slipping or twisting: omega . N.z = yaw' + sin(pitch) roll' = 0 is
    left on the shape space by the first step (x, y), solves yaw' = -sin(pitch) roll'
    (A2 = (0, sin pitch), B2_(pitch, roll) = cos pitch), and theta = d ln (gamma,
    A gamma)^(-1/2)."""
    system, _ = sphere
    v = dict(zip(map(str, system.coordinates), system.velocities))
    pitch = next(c for c in system.coordinates if str(c) == "pitch")
    rubber = System(system.coordinates, system.lagrangian,
                    list(system.phi) + [v["yaw"] + sp.sin(pitch) * v["roll"]],
                    parameters=list(system.parameters))
    first = chaplygin_reduction(rubber, ["x", "y"])
    assert first.constraints == sp.Matrix([[1, 0, sp.sin(pitch)]]) and first.check.value
    stage = reduce_again(first, ["yaw"])
    assert stage.connection == sp.Matrix([[0, sp.sin(pitch)]])
    assert stage.curvature[0][0, 1] == sp.cos(pitch) and stage.level == ()
    assert stage.check.value
    f = literature(stage, rubber=True)
    assert_factor(stage, f)
    # Ehlers & Koiller (Rubber rolling over a sphere, 2007): the invariant density is the
    # determinant of the reduced Legendre transform to the power (b/a - 1)/2 = -1/2 on a
    # plane; here against the round sphere's area cos(pitch) dpitch droll
    W = sp.hessian(stage.lagrangian, list(stage.shape_velocities))
    ratio = normal_form((W.det() * f**2 / sp.cos(stage.shape[0])**2).xreplace(
        system.exact_parameter_values))
    assert ratio.is_number and ratio > 0


def test_a_level_whose_momentum_is_not_conserved_or_not_zero_is_refused():
    """The nonholonomic particle reduced by z: p_x = (1 + y^2) x' has rate y x' y'."""
    first = chaplygin_reduction(System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2",
                                       ["z_dot - y*x_dot"]))
    with pytest.raises(InputError, match="p_x is not conserved") as info:
        reduce_again(first, ["x"], level={"x": 0})
    assert info.value.key == "level"
    with pytest.raises(InputError, match="only the level 0"):
        reduce_again(first, ["x"], level={"x": 1})
    with pytest.raises(InputError, match="y is not cyclic") as info:
        reduce_again(first, ["y"], level={"y": 0})
    assert info.value.key == "then"
    with pytest.raises(InputError, match="w not a shape coordinate"):
        reduce_again(first, ["w"])
    with pytest.raises(InputError, match="no constraint is left"):
        reduce_again(first, ["x"])
