"""``nhham reduce`` and ``nhham hamiltonize`` on the gallery's Chaplygin scenes: the
schema, the hand values (tests/lagrangian/test_chaplygin.py and
tests/hamiltonian/test_hamiltonization.py derive them), and one-line refusals."""

import json
from pathlib import Path

import jsonschema
import sympy as sp

import nhham
from nhham.cli.main import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def run(capsys, *argv):
    status = main([str(a) for a in argv])
    out = capsys.readouterr()
    return status, out.out, out.err


def test_hamiltonize_the_nonholonomic_particle(capsys):
    status, out, err = run(capsys, "hamiltonize", EXAMPLES / "nonholonomic_particle.toml",
                           "--json")
    assert status == 0, err
    envelope = json.loads(out)
    jsonschema.validate(envelope, nhham.output_schema())
    result = envelope["result"]
    f = nhham.parse_expression(result["conformal_factor"], envelope["scene"]["names"])
    y = next(s for s in f.free_symbols if s.name == "y")
    assert result["hamiltonizable"] and sp.simplify(f - 1 / sp.sqrt(1 + y**2)) == 0
    assert result["jacobiator_after"] == [] and result["reduction_check"]["agrees"]
    status, text, _ = run(capsys, "hamiltonize", EXAMPLES / "nonholonomic_particle.toml")
    assert status == 0 and "conformal factor f  1/sqrt(y**2 + 1)" in text


def test_reduce_the_sleigh_with_its_symmetry_and_without_a_factor(capsys):
    status, out, err = run(capsys, "reduce", EXAMPLES / "chaplygin_sleigh.toml",
                           "--symmetry", "y", "--json")
    assert status == 0, err
    envelope = json.loads(out)
    jsonschema.validate(envelope, nhham.output_schema())
    assert envelope["result"]["symmetry_coordinates"] == ["y"]
    assert envelope["result"]["check"]["agrees"]
    status, out, _ = run(capsys, "hamiltonize", EXAMPLES / "chaplygin_sleigh.toml",
                         "--symmetry", "y", "--json")
    result = json.loads(out)["result"]
    assert status == 0 and result["hamiltonizable"] is False
    assert result["obstruction"].startswith("theta is not closed")


def test_a_scene_that_is_not_chaplygin_is_refused_in_one_line(capsys):
    status, out, err = run(capsys, "reduce", EXAMPLES / "pendulum_cartesian.toml")
    assert status == 2 and "not of Chaplygin type" in err
    assert len(err.strip().splitlines()) == 1


def test_latex_of_the_particle_s_reduction_and_factor(capsys):
    status, out, _ = run(capsys, "reduce", EXAMPLES / "nonholonomic_particle.toml", "--latex")
    assert status == 0 and r"\ddot{x} &= - \frac{\dot{x} y \dot{y}}{y^{2} + 1}" in out
    status, out, _ = run(capsys, "hamiltonize", EXAMPLES / "nonholonomic_particle.toml",
                         "--latex")
    assert status == 0 and r"f &= \frac{1}{\sqrt{y^{2} + 1}}" in out
