"""``nhham linearize`` of a motion along a ``[symmetry]`` (in-process): the Chaplygin
sphere spinning about a vertical principal axis against a closed form worked out by
hand, a constant generator leaving today's answer alone, and the refusals.

The closed form (body frame, gamma the vertical, D = m r^2, K = I omega + D (omega -
(omega . gamma) gamma) the angular momentum about the contact point, K' = K x omega,
gamma' = gamma x omega): about omega = w e3, gamma = e3, with dK1 = (I1 + D) domega1
- D w dgamma1 and dK2 = (I2 + D) domega2 - D w dgamma2,

    (I1 + D) domega1' = w (I2 - I3) domega2,    (I2 + D) domega2' = w (I3 - I1) domega1,
    dgamma1' = w dgamma2 - domega2,             dgamma2' = -w dgamma1 + domega1,

so the spectrum modulo the rotation and the translations is +-i w (the tilt, turning in
the body frame) and +-w sqrt((I2 - I3)(I3 - I1) / ((I1 + D)(I2 + D))): real (unstable)
when I3 is the middle moment, imaginary otherwise.
"""

import cmath
from pathlib import Path

import numpy as np
import pytest

from nhham import InputError, loads_scene
from nhham.cli.main import main
from nhham.journeys import linearize

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
ROTATION = '\n[symmetry]\nyaw = "1"\nx = "-y"\ny = "x"\n'


def sphere(I3=0.12, steady=None, symmetry=ROTATION, w=2.0):
    text = (EXAMPLES / "chaplygin_sphere.toml").read_text()
    values = {s: "0.0" for s in ("yaw", "pitch", "roll", "x", "y", "pitch_dot", "roll_dot",
                                 "x_dot", "y_dot")} | {"yaw_dot": '"w"'} | (steady or {})
    return (text.replace("I3 = 0.12 }", f"I3 = {I3}, w = {w} }}") + "\n[steady]\n"
            + "".join(f"{k} = {v}\n" for k, v in values.items()) + symmetry)


@pytest.mark.parametrize("I3", [0.12, 0.09])
def test_chaplygin_sphere_spinning_about_a_vertical_principal_axis(I3):
    I1, I2, D, w = 0.08, 0.1, 1.0 * 0.5 ** 2, 2.0
    lin = linearize(loads_scene(sphere(I3))).payload["linearization"]
    rate = w * cmath.sqrt((I2 - I3) * (I3 - I1) / ((I1 + D) * (I2 + D)))
    want = sorted([1j * w, -1j * w, rate, -rate], key=lambda z: (z.real, z.imag))
    got = sorted(lin.eigenvalues, key=lambda z: (round(z.real, 9), z.imag))
    assert np.abs(np.array(got) - np.array(want)).max() < 1e-12
    assert lin.relative["rate"] == w and lin.relative["turning"]
    assert lin.stable is (None if I3 == 0.12 else False)


def test_a_constant_generator_leaves_the_answer_of_cyclic_coordinates():
    """The sleigh moving along x with xi = d/dx: w = u, X - w Xi has X's Jacobian, the
    exact method and its eigenvalue -m a u / (I + m a^2) = -2 as without the table."""
    from handmade import SLEIGH_SCENE

    text = SLEIGH_SCENE + ('[steady]\nx = 0\ny = 0\ntheta = 0\nx_dot = "u"\ny_dot = 0\n'
                           'theta_dot = 0\n')
    plain = linearize(loads_scene(text)).data
    moved = linearize(loads_scene(text + '[symmetry]\nx = "1"\n')).data
    assert moved["method"] == plain["method"] == "exact"
    assert moved["eigenvalues"] == plain["eigenvalues"] == [[-2.0, 0.0]]
    assert moved["neutral"] == plain["neutral"]
    assert moved["relative_equilibrium"]["rate"] == plain["steady_state"]["x_dot"]
    assert "relative_equilibrium" not in plain


def run(capsys, path):
    status = main(["linearize", str(path)])
    return status, capsys.readouterr().err


@pytest.mark.parametrize("case, words", [
    # no [symmetry]: the old refusal, now saying how to declare one
    (dict(symmetry=""), ["changes along it", "[symmetry]", 'yaw = "1"']),
    # turning the yaw alone turns the rolling constraints: not a symmetry
    (dict(symmetry='\n[symmetry]\nyaw = "1"\n'),
     ["symmetry:", "constraints[0], constraints[1]", "invariant"]),
    # rolling straight about the horizontal principal axis B.y: steady, but the roll
    # moves besides the group motion (w = 0) and the dynamics depends on it
    (dict(steady={"yaw_dot": "0.0", "roll_dot": "2.0", "x_dot": "1.0"}),
     ["not along the [symmetry] generator", "roll"]),
    # a vertical spin with the body tilted: omega is not a principal axis, the spin
    # precesses: not a relative equilibrium
    (dict(steady={"pitch": "0.3"}), ["not a relative equilibrium", "w = 2"]),
])
def test_refusals(capsys, tmp_path, case, words):
    path = tmp_path / "sphere.toml"
    path.write_text(sphere(**case))
    status, err = run(capsys, path)
    assert status == 2 and err.count("\n") == 1, err
    assert all(w in err for w in words), err


@pytest.mark.parametrize("table, key", [
    ('\n[symmetry]\nz = "1"\n', "symmetry.z"),
    ('\n[symmetry]\nx = "-y + q_dot"\n', "symmetry.x"),
    ('\n[symmetry]\nx = "-y_dot"\n', "symmetry.x"),
])
def test_a_bad_symmetry_table_is_refused_naming_its_key(table, key):
    with pytest.raises(InputError) as info:
        loads_scene(sphere(symmetry=table)).symmetry.field   # raised where it is read
    assert key in str(info.value) and info.value.key.startswith("symmetry")


@pytest.mark.parametrize("module", ["nhham.numerics.relative", "nhham.system.symmetry",
                                    "nhham.lagrangian.relative_symmetry"])
def test_the_new_modules_examples_run(module):
    """Their names are not in ``nhham.__all__`` (tests/test_examples.py): run here."""
    import doctest
    import importlib

    result = doctest.testmod(importlib.import_module(module),
                             optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0 and result.attempted > 0


def test_the_journey_s_generator_examples_run():
    import doctest

    from nhham.journeys import stability

    finder, runner = doctest.DocTestFinder(recurse=False), doctest.DocTestRunner(
        optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for f in (stability.symmetry_generator, stability.relative_generator):
        for test in finder.find(f, f.__name__, module=stability, globs={}):
            runner.run(test)
    assert runner.failures == 0 and runner.tries > 0


def test_json_and_the_exact_method(capsys, tmp_path):
    """``--json`` carries ``relative_equilibrium`` (valid against the schema); ``--method
    exact`` (``--exact``) is refused on a relative equilibrium naming the option."""
    import json

    import jsonschema

    from nhham.render.schema import output_schema

    path = tmp_path / "sphere.toml"
    path.write_text(sphere())
    status = main(["linearize", str(path), "--json"])
    env = json.loads(capsys.readouterr().out)
    assert status == 0
    jsonschema.validate(env, output_schema())
    rel = env["result"]["relative_equilibrium"]
    assert rel["generator"] == {"yaw": "1", "x": "-y", "y": "x"} and rel["rate"] == 2.0
    assert rel["frame"].startswith("co-moving") and rel["group"] == ["x", "y"]
    assert rel["invariance"] == {"lagrangian": "exact", "constraints[0]": "exact",
                                 "constraints[1]": "exact"}
    status = main(["linearize", str(path), "--exact"])
    err = capsys.readouterr().err
    assert status == 2 and "--exact" in err and "relative equilibrium" in err
