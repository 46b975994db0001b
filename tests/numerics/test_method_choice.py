"""``method="auto"`` (nhham.numerics.method_choice): the decision table on systems whose
structure is known by hand, through the library and the command."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

import nhham
from nhham.numerics.method_choice import LONG_PERIODS, RULES, choose_method, scene_facts

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _model(system):
    return nhham.numeric_model(system, backend="numpy")


@pytest.fixture(scope="module")
def spring():
    return _model(nhham.System(["x"], "x_dot**2/2 - x**2/2"))


def _scene_model(name):
    scene = nhham.load_scene(str(EXAMPLES / f"{name}.toml"))
    model = _model(scene.system)
    return model, model.state(scene.checked_initial())


def test_the_spring_by_hand(spring):
    """x'' = -x: eigenvalues +-i, so rho = 1, no decay; 10 s hold 10/(2 pi) periods."""
    facts = scene_facts(spring, [1.0, 0.0], (0.0, 10.0))
    assert facts.rho == pytest.approx(1.0, rel=1e-6) and facts.sigma < 1e-6
    assert facts.periods == pytest.approx(10 / (2 * math.pi), rel=1e-6)
    assert facts.mechanical and facts.reversible
    assert choose_method(spring, [1.0, 0.0], (0.0, 10.0)).method == "DOP853"
    long = choose_method(spring, [1.0, 0.0], (0.0, 2 * math.pi * LONG_PERIODS * 1.01))
    assert (long.method, long.options, long.rule) == ("rattle", {"step": 0.05}, "reversible")


def test_four_kinds_of_scene_four_choices():
    """(a) reversible: rattle; (b) a gyroscopic term: the discrete gradient; a damped
    spring: DOP853 (forces); a stiff damper: Radau -- over the same long horizon."""
    span = (0.0, 1e4)
    a, ya = _scene_model("contact_oscillator")
    b, yb = _scene_model("contact_oscillator_magnetic")
    damped = _model(nhham.System(["x"], "x_dot**2/2 - x**2/2", dissipation="x_dot**2/4"))
    stiff = _model(nhham.System(["x"], "x_dot**2/2 - x**2/2", dissipation="1e5*x_dot**2/2"))
    chosen = [choose_method(a, ya, span), choose_method(b, yb, span),
              choose_method(damped, [1.0, 0.0], span), choose_method(stiff, [1.0, 0.0], span)]
    assert [c.method for c in chosen] == ["rattle", "discrete_gradient", "DOP853", "Radau"]
    assert "not reversible" in chosen[1].reason and "applied forces" in chosen[2].reason
    # x'' = -1e5 x' - x: lambda = -1e5 and -1e-5 (by hand): a ratio of 1e10
    assert chosen[3].facts.sigma == pytest.approx(1e5, rel=1e-3)
    assert chosen[3].facts.stiffness == pytest.approx(1e10, rel=1e-3)


def test_a_hamiltonizable_scene_is_run_in_chaplygins_time():
    """The nonholonomic particle over a long horizon: the reducer gives a field, auto
    takes it; where the reducer names an obstruction, the reversible rule follows and
    the facts keep the reason."""
    from nhham.errors import InputError
    from nhham.journeys.hamiltonized_motion import hamiltonized_field

    model, y0 = _scene_model("nonholonomic_particle")
    system = nhham.load_scene(str(EXAMPLES / "nonholonomic_particle.toml")).system
    chosen = choose_method(model, y0, (0.0, 1e5),
                           reducer=lambda: hamiltonized_field(system)[0])
    assert chosen.method == "hamiltonized" and chosen.facts.hamiltonizable
    assert chosen.options["reduced"].factor_text == "1/sqrt(y**2 + 1)"

    def refuse():
        raise InputError("method hamiltonized: no conformal factor (theta is not closed)")

    other = choose_method(model, y0, (0.0, 1e5), reducer=refuse)
    assert other.method == "rattle" and other.facts.hamiltonizable is False
    assert other.facts.why_not_hamiltonizable.startswith("no conformal factor")
    # a short run does not look for a factor at all
    assert choose_method(model, y0, (0.0, 10.0), reducer=refuse).facts.hamiltonizable is None


def test_the_options_given_keep_the_family(spring):
    long = (0.0, 1e4)
    assert choose_method(spring, [1.0, 0.0], long, {"rtol"}).method == "DOP853"
    # output at given times is the adaptive methods' (a fixed-step one keeps its grid)
    assert choose_method(spring, [1.0, 0.0], long, {"t_eval"}).method == "DOP853"
    # run over 159 periods, long already (100 are), not the 1,592 of ``long``: 10 s less
    run = nhham.simulate(spring, (0.0, 1e3), [1.0, 0.0], method="auto",
                         t_eval=[0.0, 5e2, 1e3])
    assert run.settings["method_choice"]["rule"] != "short horizon"
    assert run.method == "DOP853" and list(run.t) == [0.0, 5e2, 1e3]
    fixed = choose_method(spring, [1.0, 0.0], long, {"step"})
    assert fixed.method == "rattle" and fixed.options == {}      # the step given is kept
    damped = _model(nhham.System(["x"], "x_dot**2/2 - x**2/2", dissipation="x_dot**2/4"))
    assert choose_method(damped, [1.0, 0.0], long, {"step"}).method == "rk4"


def test_not_mechanical_names_why():
    timed = _model(nhham.System(["x"], "x_dot**2/2", forces={"x": "sin(t)"}))
    assert "applied forces" in choose_method(timed, [0.0, 0.0], (0.0, 1e4)).reason
    quartic = _model(nhham.System(["x"], "x_dot**4/12 - x**2/2"))
    assert "not 1/2 v^T W" in choose_method(quartic, [1.0, 1.0], (0.0, 1e4)).reason


def test_the_table_as_documented():
    """The rules in order and the method the registry gives each (the module docstring's
    table); every rule is reached by a system of the tests above."""
    assert [(r.name, r.method) for r in RULES] == [
        ("stiff", "Radau"), ("not mechanical", "DOP853"), ("short horizon", "DOP853"),
        ("hamiltonizable", "hamiltonized"), ("reversible", "rattle"),
        ("mechanical", "discrete_gradient")]


def test_simulate_auto_reports_the_choice(spring):
    run = nhham.simulate(spring, (0.0, 1e3), [1.0, 0.0], method="auto")
    choice = run.settings["method_choice"]
    assert run.method == "rattle" and choice["method"] == "rattle"
    assert run.settings["step"] == 0.05 and "chosen by auto" in run.describe()
    assert abs(run["x"][-1] - math.cos(1e3)) < 0.1     # order 2 at h = 0.05 over 1e3


def test_the_command_chooses_when_the_scene_names_no_method(tmp_path):
    """``nhham simulate`` on a scene without a method: auto, the reason in the text and
    JSON ``method_choice``; a named method: ``method_choice`` null."""
    scene = tmp_path / "spring.toml"
    scene.write_text('coordinates = ["x"]\nlagrangian = "x_dot**2/2 - x**2/2"\n'
                     'constraints = []\n[initial]\nx = 1.0\nx_dot = 0.0\n'
                     '[simulate]\nt_end = 2000.0\n')
    run = subprocess.run([sys.executable, "-m", "nhham", "simulate", str(scene), "--json"],
                         capture_output=True, text=True, check=True)
    result = json.loads(run.stdout)["result"]
    assert result["method"] == "rattle" and result["method_choice"]["rule"] == "reversible"
    named = subprocess.run([sys.executable, "-m", "nhham", "simulate", str(scene), "--json",
                            "--method", "DOP853"], capture_output=True, text=True, check=True)
    assert json.loads(named.stdout)["result"]["method_choice"] is None
    text = subprocess.run([sys.executable, "-m", "nhham", "simulate", str(scene)],
                          capture_output=True, text=True, check=True).stdout
    assert "chosen by auto: a long horizon" in text
