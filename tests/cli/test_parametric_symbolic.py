"""``classify --parametric --symbolic``: which parameters stay symbolic, and the progress.

The scene is issue 11's (see test_classify_parametric.py) with a friction force on q1:
L = (a q1'^2 + q2'^2 - q3'^2)/2, phi = q2' + b q3', Q_q1 = -k q1'. By hand:
C = -(1 - b^2) (W = diag(a, 1, -1), mu = (0, 1, b)): singular at b = +-1, where
xi_L(phi) + Z(phi)-terms = 0 (the force acts on q1 only, outside mu) leaves lambda free;
W is singular at a = 0. k enters neither W, mu nor xi_L(phi): it cannot change a verdict.
"""

from __future__ import annotations

import json
import re

import jsonschema
import pytest
import sympy as sp

from nhham import loads_scene
from nhham.render.text import Steps
from nhham.errors import InputError
from nhham.verdict.parametric import classifying_parameters, parametric_classification
from tests.cli.conftest import run_inprocess

SCENE = """name = "issue 11, forced"
coordinates = ["q1", "q2", "q3"]
parameters = { a = 1.0, b = 1.0, k = 0.3 }
lagrangian = "(a*q1_dot**2 + q2_dot**2 - q3_dot**2)/2"
constraints = ["q2_dot + b*q3_dot"]
forces = { q1 = "-k*q1_dot" }
"""


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("symbolic") / "forced.toml"
    path.write_text(SCENE)
    return str(path)


def run(*argv):
    rc, out, err = run_inprocess(*argv)
    return rc, (json.loads(out) if out.strip().startswith("{") else out), err


def test_classifying_parameters_are_those_of_L_and_the_constraints():
    system = loads_scene(SCENE).system
    assert [p.name for p in classifying_parameters(system)] == ["a", "b"]


def test_by_default_a_parameter_only_in_the_forces_is_held(scene, schema):
    rc, env, _ = run("classify", scene, "--parametric", "--json")
    assert rc == 0
    jsonschema.validate(env, schema)
    r = env["result"]
    assert r["parameters"] == ["a", "b"] and r["held"] == {"k": 0.3}
    assert sorted(c["conditions"] for c in r["cases"]) == [["a"], ["b + 1"], ["b - 1"]]
    # C is singular at b = +-1: there a force could enter the secondary constraints
    assert any("held k could change it" in n for n in r["notes"])


def test_symbolic_all_gives_the_same_cases_with_k_symbolic(scene):
    rc, env, _ = run("classify", scene, "--parametric", "--symbolic", "all", "--json")
    assert rc == 0
    r = env["result"]
    assert r["parameters"] == ["a", "b", "k"] and r["held"] == {}
    assert sorted(c["conditions"] for c in r["cases"]) == [["a"], ["b + 1"], ["b - 1"]]
    assert not any("held" in n for n in r["notes"])


def test_symbolic_b_holds_a_so_w_is_never_singular(scene):
    """a held at 1: W = diag(1, 1, -1) is regular, the case a = 0 is gone."""
    rc, env, _ = run("classify", scene, "--parametric", "--symbolic", "b", "--json")
    assert rc == 0
    r = env["result"]
    assert r["parameters"] == ["b"] and r["held"] == {"a": 1.0, "k": 0.3}
    assert sorted(c["conditions"] for c in r["cases"]) == [["b + 1"], ["b - 1"]]
    assert r["cases"][r["scene_case"]]["conditions"] == ["b - 1"]


def test_the_text_says_which_parameters_were_held(scene):
    rc, text, _ = run("classify", scene, "--parametric")
    assert rc == 0
    assert "verdicts for every value of the parameters a, b\n" in text
    assert "held at their values: k = 0.3 (--symbolic" in text


def test_symbolic_bad_names_exit_2(scene):
    rc, _, err = run("classify", scene, "--parametric", "--symbolic", "bb")
    assert rc == 2 and "--symbolic: 'bb' is not a parameter of the scene; did you mean 'b'?" in err
    rc, _, err = run("classify", scene, "--symbolic", "b")
    assert rc == 2 and "--symbolic: only with --parametric" in err


def test_a_parameter_without_a_value_cannot_be_held():
    system = loads_scene(SCENE.replace(", k = 0.3 }", " }\nsymbolic_parameters = [\"k\"]")).system
    with pytest.raises(InputError, match="'k' has no value to be held at"):
        parametric_classification(system, symbolic=["a", "b"])


def test_progress_names_every_run_with_an_estimate():
    """b symbolic only: the generic run, then one run per component of C = 0 (b = +-1)."""
    system = loads_scene(SCENE).system
    told = []
    pv = parametric_classification(system, symbolic=["b"],
                                   progress=lambda run, note: told.append((run, note)))
    runs = [r for r, _ in told]
    assert runs[0] == "generic run" and sorted(runs[1:]) == ["run b + 1 = 0", "run b - 1 = 0"]
    assert told[0][1].startswith("0 runs done in")
    # after the generic run: two components known, one still pending after this one
    assert re.fullmatch(r"1 run done in [\d.]+ s; about \d+ s for this run and the 1 more "
                        r"known", told[1][1])
    assert re.fullmatch(r"2 runs done in [\d.]+ s; about \d+ s for this run and the 0 more "
                        r"known", told[2][1])
    assert pv.held == {sp.Symbol("a"): 1.0, sp.Symbol("k"): 0.3}


def test_a_part_of_a_step_is_shown_and_named_in_a_budget_message(capsys):
    steps = Steps(progress=True)
    with steps.step("verdicts"):
        steps.part("run b - 1 = 0", "1 run done in 0.5 s")
        assert steps.where() == "verdicts: run b - 1 = 0"
    assert steps.where() == "after 'verdicts', between steps"
    err = capsys.readouterr().err
    assert err == "nhham: verdicts ...\nnhham:   run b - 1 = 0 (1 run done in 0.5 s)\n"
