"""The command on the time-dependent examples (in process): the verdict says which
question it answers, simulate reaches the closed forms of the scenes' headers, derive
shows the multiplier worked out by hand."""

import json
import math
from pathlib import Path

import sympy as sp

from nhham import parse_expression
from nhham.cli.main import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
BALL = EXAMPLES / "ball_on_turntable_spun_up.toml"
BEAD = EXAMPLES / "bead_on_turning_wire.toml"


def run(capsys, *argv):
    status = main([str(a) for a in argv])
    out = capsys.readouterr()
    return status, json.loads(out.out) if "--json" in argv else out.out


def test_classify_says_the_verdict_is_at_a_generic_instant_and_what_depends_on_t(capsys):
    status, envelope = run(capsys, "classify", BALL, "--json")
    result = envelope["result"]
    assert status == 0 and result["regular"] and result["status"] == "determined"
    assert result["integrable"] is False
    time = result["time"]
    assert time["name"] == "t" and "generic instant" in time["question"]
    assert not time["lagrangian"]
    assert "constraints" not in time  # one record per constraint: constraint_kinds
    # {Ψ_1, Ψ_2} on M_f does not depend on t (C is the rolling ball's): one split always
    assert time["class_split"]["changes"] is False and time["class_split"]["instants"] == []
    assert [(c["kind"], c["time_dependent"]) for c in result["constraint_kinds"]] == [
        ("affine", True), ("affine", True)]
    status, text = run(capsys, "classify", BALL)
    assert status == 0 and "depends on t            constraints[0], constraints[1]" in text


def test_simulate_the_spun_up_ball_to_its_closed_form(capsys):
    status, envelope = run(capsys, "simulate", BALL, "--json")
    result = envelope["result"]
    y = dict(zip(result["state"], result["y_final"]))
    assert status == 0 and result["t_final"] == 3.0
    assert abs(y["x"] + 1.8357633850033281069) < 1e-10
    assert abs(y["y"] - 2.7697346008192437249) < 1e-10


def test_simulate_and_derive_the_bead_on_a_turning_wire(capsys):
    status, envelope = run(capsys, "simulate", BEAD, "--json")
    y = dict(zip(envelope["result"]["state"], envelope["result"]["y_final"]))
    assert status == 0
    assert abs(y["x"] - math.cosh(2) * math.cos(2)) < 1e-10
    assert abs(y["y"] - math.cosh(2) * math.sin(2)) < 1e-10
    # r' = sinh t along the wire, r Ω across: the multiplier −2 m Ω r' (header) at t = 2
    assert envelope["result"]["energy_balance_residual"] < 1e-9
    status, envelope = run(capsys, "derive", BEAD, "--json")
    assert status == 0
    names = envelope["scene"]["names"]
    lam = parse_expression(envelope["result"]["multipliers"][0], names)
    at = {sp.Symbol(k): v for k, v in y.items()} | {sp.Symbol("t"): 2, sp.Symbol("m"): 1,
                                                    sp.Symbol("Omega"): 1}
    assert abs(float(lam.subs(at)) + 2 * math.sinh(2)) < 1e-9


def test_rattle_runs_the_bead_on_its_turning_wire(capsys):
    """(x, y) = cosh 2 (cos 2, sin 2) by hand; RATTLE of order 2 at h = 0.001."""
    status = main(["simulate", str(BEAD), "--method", "rattle", "--step", "0.001", "--json"])
    r = json.loads(capsys.readouterr().out)["result"]
    assert status == 0
    y = dict(zip(r["state"], r["y_final"]))
    assert abs(y["x"] - math.cosh(2) * math.cos(2)) < 1e-5
    assert abs(y["y"] - math.cosh(2) * math.sin(2)) < 1e-5


def test_a_moving_holonomic_constraint_is_holonomic_at_each_instant(capsys):
    """The bead's wire g = y cos t - x sin t is holonomic: its lift is affine only through
    dg/dt, so the Frobenius answer is 'holonomic at each instant', not 'rheonomic, not
    holonomic' (which is for an affine h that is not a time derivative)."""
    status, text = run(capsys, "classify", BEAD)
    words = " ".join(text.split())  # the table wraps at the terminal's width
    assert status == 0 and "holonomic in disguise at each instant, moving with t" in words
