"""A rigid body in Euler angles with a full inertia tensor: every command answers, on the
routes bounded by the size of W (not by n), against the Suslov problem's closed form.

The body (ZXZ angles phi, theta, psi; I11 = 2, I22 = 1, I33 = 3, I13 = 0.5) with its body
angular velocity's third component held at zero (``examples/suslov.toml``). By hand, from
I omega' = (I omega) x omega + lambda e3 with omega3 = 0:

    omega1' = -(I13/I11) omega1 omega2,   omega2' = (I13/I22) omega1^2,

so E = (I11 omega1^2 + I22 omega2^2)/2 is conserved and omega2 = W tanh(I13 W t/I11 + c)
with W^2 = 2E/I22. One constraint: its bracket matrix is 0, one first-class constraint.
At the rotation phi' = w about a vertical second axis (theta = pi/2, psi = 0) the
linearisation on (theta, psi, theta') has the eigenvalues +-i w and -I13 w/I11.
The Lagrangian itself is checked against sympy.physics.mechanics' angular velocity.
"""

import json
import math
import time
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import nhham
from nhham.budget import time_budget
from nhham.cli.main import main
from nhham.errors import BudgetExceeded
from nhham.journeys import simulate as simulate_scene
from nhham.lagrangian.adjugate import CLOSED_FORM_WORK, closed_form_size, determinant_terms
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.progress import part, reporting
from nhham.render.text import Steps

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "examples" / "suslov.toml"
I11, I22, I33, I13 = 2.0, 1.0, 3.0, 0.5

#: The same body with its centre free: 6 coordinates, W block-diagonal (m I and the
#: 3 x 3 block of the angles).
FREE_CENTRE = SCENE.read_text().replace(
    'coordinates = ["phi", "theta", "psi"]',
    'coordinates = ["x", "y", "z", "phi", "theta", "psi"]').replace(
    "I13 = 0.5 }", "I13 = 0.5, m = 1.5 }").replace(
    'lagrangian = "(', 'lagrangian = "m*(x_dot**2 + y_dot**2 + z_dot**2)/2 + (').replace(
    "[initial]\n", "[initial]\nx = 0.0\ny = 0.0\nz = 0.0\nx_dot = 1.0\ny_dot = -0.5\n"
    "z_dot = 2.0\n").replace(
    "[steady]\n", "[steady]\nx = 0.0\ny = 0.0\nz = 0.0\nx_dot = 0.0\ny_dot = 0.0\n"
    "z_dot = 0.0\n")


def body_rates(phi, theta, psi, dphi, dtheta, dpsi):
    """omega in the body frame for ZXZ angles (the scene's definitions)."""
    return (dphi * np.sin(theta) * np.sin(psi) + dtheta * np.cos(psi),
            dphi * np.sin(theta) * np.cos(psi) - dtheta * np.sin(psi),
            dphi * np.cos(theta) + dpsi)


def command(capsys, *argv):
    capsys.readouterr()
    status = main([*argv, "--json"])
    return status, json.loads(capsys.readouterr().out)["result"]


@pytest.fixture(scope="module")
def scene():
    return nhham.load_scene(SCENE)


def test_the_lagrangian_is_sympy_mechanics_body(scene):
    """L = omega^T I omega / 2 with omega from sympy.physics.mechanics (ZXZ body-fixed)."""
    from sympy.physics import mechanics as me

    q = me.dynamicsymbols("phi theta psi")
    N = me.ReferenceFrame("N")
    B = me.ReferenceFrame("B")
    B.orient_body_fixed(N, q, "ZXZ")
    w = B.ang_vel_in(N)
    omega = sp.Matrix([w.dot(B.x), w.dot(B.y), w.dot(B.z)])
    a11, a22, a33, a13 = sp.symbols("I11 I22 I33 I13")
    inertia = sp.Matrix([[a11, 0, a13], [0, a22, 0], [a13, 0, a33]])
    t = me.dynamicsymbols._t
    names = {qi.diff(t): sp.Symbol(f"{qi.name}_dot") for qi in q}
    names.update({qi: sp.Symbol(qi.name) for qi in q})
    L_mech = ((omega.T * inertia * omega)[0] / 2).subs(names)
    system = scene.system
    L = system.lagrangian.xreplace({p: sp.Symbol(p.name) for p in system.parameters})
    L = L.xreplace({s: sp.Symbol(s.name) for s in L.free_symbols})
    assert sp.simplify(sp.expand(L - L_mech)) == 0
    # the constraint is omega3
    phi_c = system.phi[0].xreplace({s: sp.Symbol(s.name) for s in system.phi[0].free_symbols})
    assert sp.simplify(phi_c - omega[2].subs(names)) == 0


def test_w_inverse_is_bounded_by_its_size_not_by_n(scene):
    """n = 3, yet delta W^-1 has hundreds of operations: no closed forms (before: n <= 3
    took the symbolic inverse and ran for minutes); a 2 x 2 pendulum-on-cart stays small."""
    G = lagrangian_geometry(scene.system)
    size = closed_form_size(G.hessian, G.state)
    assert 3 * size > CLOSED_FORM_WORK and not G.closed_form_affordable
    th, m, l = sp.symbols("theta m l")
    cart = sp.Matrix([[2 * m, m * l * sp.cos(th)], [m * l * sp.cos(th), m * l ** 2]])
    assert 2 * closed_form_size(cart, [th]) <= CLOSED_FORM_WORK
    assert closed_form_size(sp.diag(m, m * th ** 2), [th]) == 0   # diagonal: divides


def test_determinant_terms_bounds_the_expanded_determinant():
    """The permanent of the term counts is an upper bound (random sparse polynomial
    matrices; the bound is reached when nothing cancels)."""
    rng = np.random.default_rng(3)
    xs = sp.symbols("x0:5")
    for _ in range(20):
        k = int(rng.integers(2, 5))
        M = sp.Matrix(k, k, lambda i, j: sum(int(rng.integers(-3, 4)) * xs[int(rng.integers(5))]
                                             ** int(rng.integers(0, 3))
                                             for _ in range(int(rng.integers(0, 3)))))
        det = sp.expand(M.det())
        assert len(sp.Add.make_args(det)) * (det != 0) <= determinant_terms(M)
    a, b, c, d = sp.symbols("a b c d")
    assert determinant_terms(sp.Matrix([[a + b, c], [d, a]])) == 3   # a^2 + a b - c d


def test_classify_derive_compare_answer(capsys):
    status, data = command(capsys, "classify", str(SCENE))
    assert status == 0
    assert (data["status"], data["regular"], data["integrable"]) == ("determined", True, False)
    assert (data["first_class"], data["second_class"]) == (1, 0)
    status, data = command(capsys, "derive", str(SCENE))
    assert status == 0 and data["form"] == "implicit"   # W^-1 is not formed in closed form
    status, data = command(capsys, "compare", str(SCENE))
    assert status == 0 and data["agree"] and data["method"] == "points"


def test_simulate_follows_the_closed_form(scene):
    """omega2 = W tanh(I13 W t/I11 + c), omega1^2 = (2E - I22 omega2^2)/I11, omega3 = 0."""
    answer = simulate_scene(scene, t_end=6.0, options={"rtol": 1e-11, "atol": 1e-12,
                                                       "max_step": 0.05})
    res = answer.payload["result"]
    w1, w2, w3 = body_rates(*res.y)
    E = (I11 * w1[0] ** 2 + I22 * w2[0] ** 2) / 2
    W = math.sqrt(2 * E / I22)
    c = math.atanh(w2[0] / W)
    assert np.max(np.abs(w3)) < 1e-9
    assert np.max(np.abs(w2 - W * np.tanh(I13 * W * res.t / I11 + c))) < 1e-7
    assert np.max(np.abs(I11 * w1 ** 2 + I22 * w2 ** 2 - 2 * E)) < 1e-8
    # omega1' = -(I13/I11) omega1 omega2 keeps omega1's sign: W (I22/I11)^(1/2) sech(...)
    sech = 1 / np.cosh(I13 * W * res.t / I11 + c)
    assert np.max(np.abs(w1 - np.sign(w1[0]) * W * math.sqrt(I22 / I11) * sech)) < 1e-7


def test_linearize_gives_the_hand_eigenvalues(capsys):
    status, data = command(capsys, "linearize", str(SCENE))
    assert status == 0
    w = 1.0
    expected = sorted([-I13 * w / I11, 1j * w, -1j * w], key=lambda z: (z.real, z.imag))
    eig = sorted((complex(re, im) for re, im in data["eigenvalues"]),
                 key=lambda z: (round(z.real, 9), round(z.imag, 9)))
    assert np.allclose(eig, expected, atol=1e-12)


def test_reduce_by_the_cyclic_angle(capsys):
    """phi' = -psi'/cos(theta): B_(theta, psi) = d_theta A_psi = sin(theta)/cos(theta)^2."""
    status, data = command(capsys, "reduce", str(SCENE), "--symmetry", "phi")
    assert status == 0 and data["check"]["agrees"]
    th = sp.Symbol("theta")
    B = sp.sympify(data["curvature"][0][0][1], locals={"theta": th})
    assert sp.simplify(B - sp.sin(th) / sp.cos(th) ** 2) == 0


def test_the_free_centre_body_answers_every_command(tmp_path, capsys):
    """6 coordinates: the same verdict, the centre moving uniformly (no force on it)."""
    path = tmp_path / "free_centre.toml"
    path.write_text(FREE_CENTRE)
    status, data = command(capsys, "classify", str(path))
    assert status == 0 and (data["first_class"], data["second_class"]) == (1, 0)
    status, data = command(capsys, "compare", str(path))
    assert status == 0 and data["agree"]
    status, data = command(capsys, "derive", str(path))
    assert status == 0 and data["form"] == "implicit"
    status, data = command(capsys, "linearize", str(path))
    assert status == 0
    eig = [complex(re, im) for re, im in data["eigenvalues"]]
    assert any(abs(z + I13 / I11) < 1e-9 for z in eig)
    answer = simulate_scene(nhham.load_scene(path), t_end=2.0,
                            options={"rtol": 1e-11, "atol": 1e-12})
    res = answer.payload["result"]
    assert np.allclose(res.y[:3, -1], [2.0, -1.0, 4.0], atol=1e-9)   # x0 + v t


def test_a_part_names_the_work_running():
    """progress.part: the budget's message and --verbose name the part inside the step,
    and the step's record comes before its parts'."""
    steps = Steps()
    with reporting(steps), pytest.raises(BudgetExceeded, match="inverse"):
        with time_budget(0.2, steps.where), steps.step("constraint algorithm"):
            with part("symbolic inverse"):
                time.sleep(5)
    steps = Steps()
    with reporting(steps), steps.step("outer"):
        with part("inner"):
            assert steps.where() == "outer: inner"
        assert steps.where() == "outer"
    assert [what for what, _ in steps.records] == ["outer", "  inner"]
    with part("no command running"):   # a library call: nothing recorded, nothing fails
        pass
