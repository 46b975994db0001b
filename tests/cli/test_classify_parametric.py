"""``nhham classify`` at the scene's parameter values, and ``classify --parametric``.

The scene is the one of issue 11: L = (a q1'^2 + q2'^2 - q3'^2)/2, phi = q2' + b q3', so
C = -(1 - b^2) (W = diag(a, 1, -1), mu = (0, 1, b)): regular except at b = +-1, where
C = 0 and xi_L(phi) = 0 leaves lambda_1 free; W is singular at a = 0.
"""

from __future__ import annotations

import json

import jsonschema
import sympy as sp
import pytest

from tests.cli.conftest import run_inprocess

SCENE = """name = "issue 11 example"
coordinates = ["q1", "q2", "q3"]
parameters = {{ a = 1.0, b = {b} }}
lagrangian = "(a*q1_dot**2 + q2_dot**2 - q3_dot**2)/2"
constraints = ["q2_dot + b*q3_dot"]
"""


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    d = tmp_path_factory.mktemp("parametric")
    out = {}
    for key, b in (("on", "1.0"), ("off", "0.5"), ("near", "1.0000000001")):
        path = d / f"issue_{key}.toml"
        path.write_text(SCENE.format(b=b))
        out[key] = str(path)
    return out


def run(*argv):
    rc, out, err = run_inprocess(*argv)
    return rc, (json.loads(out) if out.strip().startswith("{") else out), err


def test_plain_classify_answers_at_b_equal_one(scenes, schema):
    rc, env, _ = run("classify", scenes["on"], "--json")
    assert rc == 0
    jsonschema.validate(env, schema)
    r = env["result"]
    assert (r["regular"], r["rank_c"], r["status"], r["free_multipliers"]) == \
        (False, 0, "underdetermined", 1)
    assert r["parameter_case"]["conditions"] == ["b - 1"]
    assert r["parameter_case"]["generic_differs"] is True
    assert r["parameter_case"]["generic"]["rank_c"] == 1
    assert r["final_constraints"] == ["q2_dot + q3_dot"]


def test_plain_classify_text_says_the_generic_verdict_differs(scenes):
    rc, text, _ = run("classify", scenes["on"])
    assert rc == 0
    assert "C regular on M_1        no" in text
    assert "note: the parameter values satisfy b - 1 = 0" in text
    assert "differs from the generic one" in text


def test_generic_values_keep_the_generic_verdict(scenes):
    rc, env, _ = run("classify", scenes["off"], "--json")
    assert rc == 0
    r = env["result"]
    assert (r["regular"], r["rank_c"], r["status"]) == (True, 1, "determined")
    assert r["parameter_case"] is None
    assert not any("relative distance" in w for w in env["warnings"])


def test_values_near_the_exceptional_set_are_warned_about(scenes):
    rc, env, _ = run("classify", scenes["near"], "--json")
    assert rc == 0 and env["result"]["regular"] is True
    assert any("relative distance" in w and "C singular" in w for w in env["warnings"])


def test_parametric_json(scenes, schema):
    rc, env, _ = run("classify", scenes["on"], "--parametric", "--positive", "a", "--json")
    assert rc == 0
    jsonschema.validate(env, schema)
    r = env["result"]
    assert r["parameters"] == ["a", "b"] and r["positive"] == ["a"]
    assert r["generic"]["status"] == "determined" and r["generic"]["rank_c"] == 1
    conditions = [c["conditions"] for c in r["cases"]]
    assert sorted(conditions) == [["b + 1"], ["b - 1"]]
    for case in r["cases"]:
        assert case["excluding"] == []
        v = case["verdict"]
        assert (v["regular"], v["rank_c"], v["status"], v["free_multipliers"]) == \
            (False, 0, "underdetermined", 1)
    assert r["cases"][r["scene_case"]]["conditions"] == ["b - 1"]
    assert [d["conditions"] for d in r["dropped"]] == [["a"]]


def test_parametric_without_signs_reports_the_singular_lagrangian(scenes, schema):
    rc, env, _ = run("classify", scenes["off"], "--parametric", "--json")
    assert rc == 0
    jsonschema.validate(env, schema)
    r = env["result"]
    invalid = [c for c in r["cases"] if c["verdict"]["status"] == "invalid"]
    assert [c["conditions"] for c in invalid] == [["a"]]
    assert "singular" in invalid[0]["verdict"]["note"]
    assert r["scene_case"] is None


def test_parametric_text(scenes):
    rc, text, _ = run("classify", scenes["on"], "--parametric", "--positive", "a")
    assert rc == 0
    assert "generic (where no case below holds):" in text
    assert "case 0: b - 1 = 0" in text
    assert "differs in" in text and "dropped (no real solution" in text
    assert "scene values a = 1.0, b = 1.0: case 0" in text


def test_parametric_bad_input_exits_2(scenes):
    rc, _, err = run("classify", scenes["on"], "--parametric", "--positive", "zz")
    assert rc == 2 and "positive: 'zz'" in err
    rc, _, err = run("classify", scenes["on"], "--parametric", "--latex")
    assert rc == 2 and "--parametric" in err


def test_derive_and_compare_answer_at_b_equal_one(scenes, schema):
    """At b = 1, C = -(1 - b^2) = 0 by hand: lambda_1 is free, q2'' = -lambda_1, q3'' = lambda_1."""
    rc, env, _ = run("derive", scenes["on"], "--json")
    assert rc == 0
    jsonschema.validate(env, schema)
    r = env["result"]
    assert r["constraint_matrix"] == [["0"]]
    assert r["free_multiplier_symbols"] == ["lambda_1"]
    assert r["field"][3:] == ["0", "-lambda_1", "lambda_1"]
    assert r["parameter_case"]["conditions"] == ["b - 1"]
    assert r["parameter_case"]["generic_differs"] is True
    rc, env, _ = run("compare", scenes["on"], "--json")
    assert rc == 0
    jsonschema.validate(env, schema)
    r = env["result"]
    assert r["agree"] and r["lagrangian_status"] == r["hamiltonian_status"] == "underdetermined"
    assert r["parameter_case"]["conditions"] == ["b - 1"]


def test_derive_at_generic_values_is_the_generic_one(scenes):
    """b = 1/2: C = -(1 - 1/4) = -3/4, lambda = 0 (xi_L(phi) = 0), no case."""
    rc, env, _ = run("derive", scenes["off"], "--json")
    assert rc == 0
    r = env["result"]
    assert r["parameter_case"] is None and r["free_multiplier_symbols"] == []
    c = sp.sympify(r["constraint_matrix"][0][0]).subs({"a": 1, "b": sp.Rational(1, 2)})
    assert abs(float(c) + 0.75) < 1e-12


@pytest.mark.parametrize("command", ["derive", "compare"])
def test_derive_and_compare_warn_near_the_exceptional_set(scenes, command):
    """b = 1 + 1e-10: generic (C = -(1 - b^2) != 0), but within 1e-8 of b = 1."""
    rc, env, _ = run(command, scenes["near"], "--json")
    assert rc == 0 and env["result"]["parameter_case"] is None
    assert any("relative distance" in w and "C singular" in w for w in env["warnings"])
