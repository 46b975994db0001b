"""derive and classify as people read them: simplified, labelled, complete."""

import json

import sympy as sp

import nhham

from conftest import EXAMPLES, long_expression, run_inprocess
from nhham.render import layout
from nhham.render.results import classify_text


def envelope(*args):
    rc, out, err = run_inprocess(*args, "--json")
    assert rc == 0, err
    return json.loads(out)


def test_derive_explicit_is_simplified():
    """The 5-coordinate differential drive (W constant: closed forms by default): the
    heading law of its header, and no sin^2 + cos^2 left in any line."""
    scene = str(EXAMPLES / "differential_drive_mass_centre.toml")
    env = envelope("derive", scene)
    res, names = env["result"], env["scene"]["names"]
    assert res["form"] == "explicit"
    i = res["state"].index("theta_dot")
    theta_ddot = nhham.parse_expression(res["field"][i], names)
    th, m, I, Iw, r, b, d = sp.symbols("theta m I Iw r b d")
    xd, yd, thd = sp.symbols("x_dot y_dot theta_dot")
    hand = -d * m * r**2 * thd * (xd * sp.cos(th) + yd * sp.sin(th)) / (
        I * r**2 + 2 * Iw * b**2 + d**2 * m * r**2)
    assert sp.cancel(theta_ddot - hand) == 0
    rc, text, err = run_inprocess("derive", scene)
    assert "sin(theta)**3" not in text and "cos(theta)**3" not in text
    assert "sin(theta)*cos(theta)**2" not in text
    assert len(text) < 4000


def test_implicit_forcing_rows_are_named_by_coordinate():
    """F is the right-hand side of W a + mu^T lambda = F, not an acceleration."""
    rc, text, err = run_inprocess("derive", str(EXAMPLES / "differential_drive.toml"))
    assert rc == 0, err
    assert "F[x]" in text and "F[theta]" in text
    assert "x''" not in text and "theta''" not in text
    # the forcing of the heading row is d mc theta_dot^2 (cos, sin) on x, y: by hand from
    # L = ... - d mc theta_dot x_dot sin(theta) + d mc theta_dot y_dot cos(theta)
    assert "F[x]      =  d*mc*theta_dot**2*cos(theta)" in text


def test_classify_reports_the_first_class_combination_it_counts():
    """Decided at points (W depends on theta): 'first class 1' used to come with an
    empty list. Now the combination and its coefficients on the constraints."""
    res = envelope("classify", str(EXAMPLES / "differential_drive.toml"))["result"]
    assert res["first_class"] == 1
    assert len(res["first_class_combinations"]) == 1
    coefficients = res["first_class_coefficients"][0]
    assert [c["label"] for c in coefficients] == ["constraints[0]", "constraints[1]",
                                                  "constraints[2]"]
    assert coefficients[-1]["coefficient"] == "1"
    rc, text, err = run_inprocess("classify", str(EXAMPLES / "differential_drive.toml"))
    assert "first-class combinations (in q, p):" in text and "*constraints[0]" in text


def test_classify_text_lists_each_constraint_once():
    data = {"n": 8, "m": 5, "regular": True, "rank_c": 5, "rank_c_method": "sampled",
            "status": "determined", "free_multipliers": 0, "free_multiplier_symbols": [],
            "redundant": [], "integrable": False, "first_class": 0, "second_class": 6,
            "stages": [{"index": 1, "labels": ["holonomic[0]", "constraints[0]"],
                        "constraints": [long_expression(), "x_dot"], "rank": 5}],
            "final_labels": ["holonomic[0]", "constraints[0]"],
            "final_constraints": [long_expression(), "x_dot"],
            "first_class_combinations": [], "first_class_coefficients": None,
            "inconsistency": None,
            "constraint_kinds": [{"label": "holonomic[0]", "kind": "holonomic",
                                  "time_dependent": False},
                                 {"label": "constraints[0]", "kind": "linear",
                                  "time_dependent": False}]}
    out = classify_text("bicycle", data)
    assert out.count("k0*sin(q0)") == 1
    assert "  M_1  rank 5  holonomic[0], constraints[0]" in out
    assert max(len(line) for line in out.splitlines()) <= layout.width()
