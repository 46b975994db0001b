"""Stability modulo a declared symmetry (issue 43, item 2): a ``[symmetry]`` none of whose
coordinates is cyclic counts as neutral as soon as it is declared, for a motion with
w = 0 as for w != 0; where its momentum is conserved, its level is divided out too.

The values are the scenes' hand derivations (their headers):

- tests/study/scenes/trailer_robot.toml: a differential-drive robot towing a trailer,
  running straight at V = r w. The hitch acts at the axle midpoint O, so the robot's yaw
  obeys the Chaplygin sleigh's J omega' = -m0 d V omega (J = Ic + m0 d^2 + 2 Iw b^2/r^2),
  and the trailer angle psi = theta - theta2 obeys psi' = omega - (V/l) sin(psi): modulo
  the rotation of the whole (theta and theta2 turned together) and the speed, the
  eigenvalues -V/l and -m0 d V / J. Before, the rotation's 0 stayed: "spectrally stable
  ... cannot decide" at every speed, and a map over the speed was grey everywhere.
- tests/study/scenes/mexican_hat.toml: a particle at rest at the angle a on the circle
  of minima of V = (r^2 - 1)^2 / 4 with damping c: radial lambda^2 + c lambda + 2 = 0,
  angular 0 (the orbit) and -c (J' = -c J); undamped, J is conserved: +-i sqrt(2) alone.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from nhham import load_scene
from nhham.cli.main import main
from nhham.journeys import linearize
from nhham.numerics.codegen import numeric_model

SCENES = Path(__file__).resolve().parents[1] / "study" / "scenes"
TRAILER = SCENES / "trailer_robot.toml"
HAT = SCENES / "mexican_hat.toml"


def trailer_eigenvalues(w):
    """-V/l and -m0 d V / J at V = r w (the scene's header)."""
    m0, Ic, Iw, r, b, d, l = 4.0, 0.08, 0.0015, 0.1, 0.15, 0.05, 0.8
    V = r * w
    J = Ic + m0 * d ** 2 + 2 * Iw * b ** 2 / r ** 2
    return sorted([-V / l, -m0 * d * V / J])


@pytest.fixture(scope="module")
def trailer():
    scene = load_scene(TRAILER)
    return scene, numeric_model(scene.steady_system())


@pytest.mark.parametrize("w, stable", [(5.0, True), (-5.0, False)])
def test_the_trailer_robot_straight_run_is_decided_modulo_the_rotation(trailer, w, stable):
    scene, model = trailer
    lin = linearize(scene, model=model.with_parameters(w=w)).payload["linearization"]
    assert "orbit(xi)" in lin.neutral and "d/dw" in lin.neutral
    assert len(lin.eigenvalues) == 2
    got = sorted(lin.eigenvalues.real)
    assert np.abs(np.array(got) - trailer_eigenvalues(w)).max() < 1e-12
    assert np.abs(lin.eigenvalues.imag).max() < 1e-12
    assert lin.stable is stable
    assert lin.relative["orbit"] and not lin.relative["momentum"]


def test_the_trailer_robot_stability_map_is_no_longer_grey():
    """``sweep --what linearize`` over the speed: stable forward, unstable backward, the
    crossing at w = 0 (both eigenvalues through 0 at once: real); the verdict codes have
    their meanings in the Dataset's attributes."""
    from nhham.study.sweep import sweep

    ds = sweep(str(TRAILER), "linearize", ["w=-2:2:5"], workers=1).dataset
    assert ds["verdict"].values.tolist() == [0, 0, -1, 1, 1]
    assert ds["stable"].values.tolist() == [False, False, False, True, True]
    for i, w in enumerate([-2.0, -1.0, 0.0, 1.0, 2.0]):
        if w == 0.0:
            continue
        got = np.sort(ds["eigenvalue_real"].values[i])
        assert np.abs(got - trailer_eigenvalues(w)).max() < 1e-12
    (value,) = ds["boundary"].values[np.isfinite(ds["boundary"].values)]
    assert value == 0.0 and int(ds["boundary_kind"].values[0]) == 0
    assert int(ds["boundary_direction"].values[0]) == -1
    attrs = ds["verdict"].attrs
    assert list(attrs["flag_values"]) == [1, 0, -1]
    assert attrs["flag_meanings"] == "stable unstable undecided"
    assert "1: asymptotically stable" in attrs["description"]
    assert list(ds["status"].attrs["flag_values"]) == [0, 1, 2, 3]
    assert ds["boundary_kind"].attrs["flag_meanings"] == "real complex none"


@pytest.mark.parametrize("method", ["auto", "complex-step"])
def test_a_damped_particle_at_rest_on_its_circle_of_minima(method):
    """The orbit at a point where it is no coordinate axis (a = 0.7): -c and the radial
    pair, asymptotically stable; exactly (n = 2: the exact Jacobian, the orbit divided
    out exactly) and by the complex step."""
    c = 0.3
    scene = load_scene(HAT)
    model = numeric_model(scene.steady_system()).with_parameters(c=c)
    lin = linearize(scene, method=method, model=model).payload["linearization"]
    assert lin.method == ("exact" if method == "auto" else "complex-step")
    assert lin.neutral == ("orbit(xi)",) and lin.stable is True
    want = np.sort_complex(np.concatenate([[-c], np.roots([1.0, c, 2.0])]))
    got = np.sort_complex(lin.eigenvalues)
    assert np.abs(got - want).max() < 1e-12


def test_a_conserved_momentum_s_level_is_divided_out_too():
    """Undamped: J = x y_dot - y x_dot is conserved (no force along xi): the orbit and
    the level of J divided out leave +-i sqrt(2); ``--exact`` is refused (the level's
    differential on M_1 is formed by the complex step only)."""
    scene = load_scene(HAT)
    lin = linearize(scene).payload["linearization"]
    assert lin.neutral == ("orbit(xi)", "level(J)") and lin.method == "complex-step"
    assert lin.relative["momentum"] and lin.relative["orbit"]
    got = np.sort_complex(lin.eigenvalues)
    assert np.abs(got - np.array([-1j * np.sqrt(2), 1j * np.sqrt(2)])).max() < 1e-12
    assert lin.stable is None and lin.spectrally_stable
    from nhham import InputError

    with pytest.raises(InputError) as info:
        linearize(scene, method="exact")
    assert info.value.key == "method" and "momentum" in str(info.value)


def test_the_command_says_what_it_divided_out(capsys):
    status = main(["linearize", str(TRAILER)])
    out = capsys.readouterr().out
    assert status == 0
    assert "orbit(xi)" in out and "symmetry divided out" in out
    assert "asymptotically stable" in out
    status = main(["linearize", str(TRAILER), "--json"])
    env = json.loads(capsys.readouterr().out)
    rel = env["result"]["relative_equilibrium"]
    assert status == 0 and rel["orbit"] is True and rel["momentum"] is False
    assert env["result"]["stable"] is True
