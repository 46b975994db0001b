"""``linearize`` says which acceleration solve it used (issue 43, item 8), and a change of
a coordinate's unit leaves its eigenvalues and its solve.

L = (a x'^2 + b y'^2)/2 - k x^2/2, R = c x'^2/2, x' + y' = 1: by hand (a + b) x'' =
-k x - c x', so about x = 0, x' = 0, y' = 1 (steady; y cyclic) the state matrix in
(x, x_dot) is [[0, 1], [-k/(a + b), -c/(a + b)]], eigenvalues the roots of
lambda^2 + (c lambda + k)/(a + b). Written with x in millimetres (x = X / 1000: a, k, c
times 1e-6, the constraint X'/1000 + y' = 1) the eigenvalues are the same, and so is the
solve (the null-space solve in every unit; W's diagonal ratio, b/a in metres and 1e6 b/a
in millimetres, is reported and decides nothing).
"""

import json

import numpy as np
import pytest

import nhham
from nhham.cli.main import main
from nhham.journeys import linearize

SCENE = """name = "a light and a heavy mass, x in {unit}"
coordinates = ["x", "y"]
parameters = {{ a = {a!r}, b = {b!r}, k = {k!r}, c = {c!r} }}
lagrangian = "(a*x_dot**2 + b*y_dot**2)/2 - k*x**2/2"
dissipation = "c*x_dot**2/2"
constraints = ["{s}*x_dot + y_dot - 1"]

[steady]
x = 0.0
y = 0.0
x_dot = 0.0
y_dot = 1.0
"""


def scene(b, millimetres=False):
    f = 1e-6 if millimetres else 1.0
    return nhham.loads_scene(SCENE.format(unit="mm" if millimetres else "m", a=1.0 * f,
                                          b=b, k=1.0 * f, c=1.0 * f,
                                          s=1e-3 if millimetres else 1.0))


@pytest.mark.parametrize("b", [1e3, 5e3])
@pytest.mark.parametrize("method", ["auto", "complex-step"])
def test_a_coordinate_in_millimetres_keeps_the_eigenvalues(b, method):
    metres = linearize(scene(b), method=method).payload["linearization"]
    mm = linearize(scene(b, millimetres=True), method=method).payload["linearization"]
    want = np.sort_complex(np.roots([1.0, 1.0 / (1.0 + b), 1.0 / (1.0 + b)]))
    for lin in (metres, mm):   # (the charts may differ: x_dot or y_dot independent)
        assert np.abs(np.sort_complex(lin.eigenvalues) - want).max() <= 1e-12 * abs(want).max()
        assert lin.kkt_solve == "null-space"
    assert metres.kkt_ratio == pytest.approx(b, rel=1e-12)   # max W_AA / min W_AA
    assert mm.kkt_ratio == pytest.approx(1e6 * b, rel=1e-12)


def test_the_command_says_which_solve(capsys, tmp_path):
    path = tmp_path / "ratio.toml"
    path.write_text(SCENE.format(unit="m", a=1.0, b=1e5, k=1.0, c=1.0, s=1.0))
    assert main(["linearize", str(path)]) == 0
    out = capsys.readouterr().out
    assert "null-space" not in out   # one solve everywhere: said in the JSON only
    assert main(["linearize", str(path), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)["result"]
    assert result["kkt_solve"] == "null-space"
    assert result["kkt_ratio"] == pytest.approx(1e5, rel=1e-12)
