"""The work-precision driver (nhham.numerics.workprecision): its rows, the time to a
given error, the quick reference against the sleigh's closed form, skipped settings, and
a reference that cannot be computed."""

from __future__ import annotations

import numpy as np
import pytest

import nhham
from nhham.numerics.codegen import numeric_model
from nhham.numerics.integrate import simulate
from nhham.numerics.model import NumericsWarning
from nhham.numerics.status import NumericalFailure
from nhham.numerics.workprecision import work_precision

from test_exact_solutions import sleigh_exact, sleigh_state


def test_work_precision_rows_and_time_to_solution(sleigh):
    wp = work_precision(sleigh, sleigh_state(), (0, 2.0), methods=["DOP853", "rattle"],
                        tolerances=(1e-6, 1e-10), steps=(0.05, 0.01), reference_digits=25)
    labels = [(r.method, r.setting) for r in wp.rows]
    assert ("DOP853", "rtol=1e-06") in labels and ("DOP853+projection", "rtol=1e-10") in labels
    assert ("rattle", "h=0.01") in labels
    errs = {(r.method, r.setting): r.error for r in wp.rows}
    assert errs[("DOP853", "rtol=1e-10")] < errs[("DOP853", "rtol=1e-06")] < 1e-4
    assert errs[("rattle", "h=0.01")] < errs[("rattle", "h=0.05")]
    for r in wp.rows:
        if r.method in ("rattle", "DOP853+projection"):
            assert r.constraint_residual <= 1e-12
    tts = wp.time_to_solution(1e-6)
    assert tts["DOP853"] is not None
    assert "| method |" in wp.table()
    assert wp.reference_error_estimate < 1e-18


def test_work_precision_quick_timing_and_skipped_settings(sleigh):
    """--quick: the float64 reference agrees with the sleigh's closed form; each setting
    runs `repeats` times at least (min_time 0: exactly); slow = 0 keeps only the loosest
    setting of every method and lists the others as skipped."""
    with pytest.warns(NumericsWarning, match="not 100 times below"):  # rk4 at h = 0.0025
        wp = work_precision(sleigh, sleigh_state(), (0, 2.0), quick=True,
                            methods=["DOP853", "rk4"], repeats=3, min_time=0.0)
    assert "float64 DOP853" in wp.reference and wp.reference_digits == 16
    assert wp.reference_error_estimate < 1e-11 and not wp.skipped
    assert all(r.runs == 3 for r in wp.rows)
    best = min(r.error for r in wp.rows if r.method == "DOP853")
    assert best < 1e-9  # rtol 1e-8 against the reference
    u, w, th = sleigh_exact(np.array(2.0))
    ref = simulate(sleigh, (0, 2.0), sleigh_state(), rtol=1e-13, atol=1e-16, projection=True,
                   warn=False)  # the quick reference's run
    assert abs(ref["theta"][-1] - th) < 1e-11 and abs(ref["theta_dot"][-1] - w) < 1e-11
    lean = work_precision(sleigh, sleigh_state(), (0, 2.0), quick=True,
                          methods=["DOP853", "rk4"], min_time=0.0, slow=0.0)
    assert [(r.method, r.setting) for r in lean.rows] == [
        ("DOP853", "rtol=1e-05"), ("DOP853+projection", "rtol=1e-05"), ("rk4", "h=0.04"),
        ("rk4+projection", "h=0.04")]
    assert [(m, s) for m, s, _ in lean.skipped] == [
        ("DOP853", "rtol=1e-08"), ("DOP853+projection", "rtol=1e-08"), ("rk4", "h=0.01"),
        ("rk4", "h=0.0025"), ("rk4+projection", "h=0.01"), ("rk4+projection", "h=0.0025")]
    assert "skipped: DOP853 rtol=1e-08 (DOP853 rtol=1e-05 took" in lean.describe()


def test_reference_failure_is_a_numerical_failure_saying_what():
    """C = 0 identically (a free multiplier): nothing to measure against."""
    model = numeric_model(nhham.System(["x", "y", "z"], "(x_dot**2 + y_dot**2 - z_dot**2)/2",
                                       ["y_dot + z_dot"]))
    with pytest.raises(NumericalFailure, match=r"reference solution stopped at t = 0 .*C = "
                                               r"-mu W\^-1 mu\^T is singular"):
        work_precision(model, [0.0, 0.0, 0.0, 1.0, 1.0, -1.0], (0, 1.0), quick=True)


def test_an_affine_constraint_shows_the_energy_balance_and_says_why():
    """y' = w x on a spring in x. By hand: the reaction is -lambda (0, 1), so x'' = -x and
    y'' = -lambda = w x' (lambda = -w x'); its power -lambda y' = w^2 x x', so E = (x'^2 +
    y'^2 + x^2)/2 changes by w^2 (x^2 - x0^2)/2 (x = cos t: up to 2 at w = 2) while the
    balance E - int P dt stays. The table measures each method by the balance and says why;
    y' = w x' (h = 0) conserves E."""
    system = nhham.System(["x", "y"], "(x_dot**2 + y_dot**2 - x**2)/2", ["y_dot - w*x"],
                          parameters={"w": 2.0})
    model = numeric_model(system, backend="numpy")
    assert "affine constraints do work" in model.energy_change
    assert numeric_model(nhham.System(["x", "y"], "(x_dot**2 + y_dot**2 - x**2)/2",
                                      ["y_dot - w*x_dot"], parameters={"w": 2.0}),
                         backend="numpy").energy_change == ""
    y0 = model.state({"x": 1.0, "y": 0.0, "x_dot": 0.0, "y_dot": 2.0})
    wp = work_precision(model, y0, (0, 3.0), quick=True, methods=["DOP853"], min_time=0.0)
    assert "| energy balance |" in wp.table() and "affine constraints do work" in wp.describe()
    drift = [r.energy_drift for r in wp.rows]
    balance = [r.energy_balance_residual for r in wp.rows]
    assert min(drift) > 0.1 and max(balance) < 1e-4   # the drift is the physics, not error
