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
from tests.cli.conftest import run_fresh, run_inprocess

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


def test_by_default_a_force_parameter_is_symbolic_where_c_is_singular(scene, schema):
    """C is singular at b = +-1, where the forces enter the secondary constraints: k is
    kept symbolic by default (the runs again with it), and the cases are those without
    it, as derived above (k cannot change a verdict). Before, k was held at 0.3 and a
    note said it "could change" the verdict there."""
    rc, env, _ = run("classify", scene, "--parametric", "--json")
    assert rc == 0
    jsonschema.validate(env, schema)
    r = env["result"]
    assert r["parameters"] == ["a", "b", "k"] and r["held"] == {}
    assert sorted(c["conditions"] for c in r["cases"]) == [["a"], ["b + 1"], ["b - 1"]]
    assert any(n.startswith("k kept symbolic: k enters the forces") for n in r["notes"])
    assert r["search"]["complete"] is True and r["search"]["cut"] == []


def test_symbolic_a_b_holds_k_with_a_note(scene):
    """Held by the user: the note says k could change a verdict where C is singular."""
    rc, env, _ = run("classify", scene, "--parametric", "--symbolic", "a,b", "--json")
    assert rc == 0
    r = env["result"]
    assert r["parameters"] == ["a", "b"] and r["held"] == {"k": 0.3}
    assert sorted(c["conditions"] for c in r["cases"]) == [["a"], ["b + 1"], ["b - 1"]]
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
    rc, text, _ = run("classify", scene, "--parametric", "--symbolic", "a,b")
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


# ------------------------------------------------- the default set (issue 43, item 6)
DAMPER = """name = "null constraint with a damper"
coordinates = ["q1", "q2", "q3"]
parameters = { c = 0.5 }
lagrangian = "(q1_dot**2 + q2_dot**2 - q3_dot**2)/2"
constraints = ["q2_dot + q3_dot"]
dissipation = "c*q2_dot**2/2"
"""


@pytest.fixture(scope="module")
def damper(tmp_path_factory):
    path = tmp_path_factory.mktemp("damper") / "damper.toml"
    path.write_text(DAMPER)
    return str(path)


def test_a_damper_on_a_null_constraint_gives_its_case_c_0_with_no_option(damper, schema):
    """By hand: W = diag(1, 1, -1), mu = (0, 1, 1), so C = -mu W^-1 mu^T = -(1 - 1) = 0
    for every c: C is singular. The damper's force is Q = -dR/dv = (0, -c q2', 0), and
    with the reaction -lambda mu: q2'' = -c q2' - lambda, -q3'' = -lambda, so
    d/dt (q2' + q3') = -c q2' (lambda cancels: C = 0).
      c != 0: q2' = 0 is a secondary constraint (M_2: q2' = q3' = 0, dimension 4); its
        tangency q2'' = -lambda = 0 fixes lambda: determined, 2 stages, 0 free
        multipliers; on T*Q p_q2 = p_q3 = 0 are 2 first-class constraints.
      c = 0: the condition vanishes, lambda is free: underdetermined, 1 stage, 1 free
        multiplier, 1 first-class constraint.
    Before, c entered the dissipation only and was held at 0.5: the report listed the
    generic verdict alone, with a note that c "could change the verdict"."""
    rc, env, _ = run("classify", damper, "--parametric", "--json")
    assert rc == 0
    jsonschema.validate(env, schema)
    r = env["result"]
    assert r["parameters"] == ["c"] and r["held"] == {}
    g = r["generic"]
    assert (g["regular"], g["status"], len(g["stages"]), g["free_multipliers"],
            g["first_class"], g["second_class"]) == (False, "determined", 2, 0, 2, 0)
    assert [c["conditions"] for c in r["cases"]] == [["c"]]
    v = r["cases"][0]["verdict"]
    assert (v["regular"], v["status"], len(v["stages"]), v["free_multipliers"],
            v["first_class"]) == (False, "underdetermined", 1, 1, 1)
    assert r["scene_case"] is None  # c = 0.5: generic
    assert any(n.startswith("c kept symbolic") for n in r["notes"])


def test_keeping_it_symbolic_beyond_the_budget_is_said_with_the_estimate(damper,
                                                                        monkeypatch):
    """A planted estimate: the runs with c held "took" 5000 s, more than the default
    budget leaves (600 s): c stays held, and a warning says why, with the estimate and
    the option that insists."""
    from nhham.verdict import parametric

    monkeypatch.setattr(parametric._Clock, "spent", lambda self: 5000.0)
    rc, out, err = run_fresh("classify", damper, "--parametric", "--json")
    assert rc == 0
    r = json.loads(out)
    assert r["result"]["held"] == {"c": 0.5} and r["result"]["cases"] == []
    (warning,) = [w for w in r["warnings"] if "c enters the forces" in w]
    assert "about 5000 s or more" in warning and "--symbolic c" in warning

