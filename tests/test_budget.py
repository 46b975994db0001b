"""The library's time bound (nhham.time_budget) and the size guard of closed forms."""

import threading
import time

import pytest
import sympy as sp

import nhham
from nhham.budget import remaining_time
from nhham.errors import BudgetExceeded, ClosedFormTooLarge, InputError, NhhamWarning


def _spin(seconds):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        pass


def test_a_budget_stops_a_block_that_runs_too_long():
    start = time.monotonic()
    with pytest.raises(BudgetExceeded, match="0.2 s"):
        with nhham.time_budget(0.2):
            _spin(5)
    assert time.monotonic() - start < 1.5


def test_an_expiry_that_is_swallowed_is_raised_again():
    """Python drops an exception raised in a garbage-collector callback (where the alarm
    can land: this made the closed-form test below flaky in the full suite); code that
    catches Exception and draws again drops it too. The alarm repeats every REPEAT_S
    until the block is left, so the next expiry stops the block."""
    from nhham.budget import REPEAT_S

    start = time.monotonic()
    swallowed = []
    with pytest.raises(BudgetExceeded, match="0.2 s"):
        with nhham.time_budget(0.2):
            try:
                _spin(5)
            except BudgetExceeded:
                swallowed.append(time.monotonic())
            _spin(5)
    assert len(swallowed) == 1
    assert time.monotonic() - swallowed[0] < 20 * REPEAT_S
    assert time.monotonic() - start < 1.5


def test_an_expiry_where_python_drops_it_prints_nothing(monkeypatch):
    """The alarm landing in a garbage-collector callback (or a weakref finaliser) was
    printed by Python as "Exception ignored in ..." with a traceback, among the
    command's one-line messages (seen in the scene fuzz); the repeated alarm stops the
    block all the same, so that expiry is passed over. Other unraisable exceptions
    still reach the hook."""
    import gc
    import sys

    seen = []
    monkeypatch.setattr(sys, "unraisablehook", seen.append)

    def slow(phase, info):
        if phase == "start":
            _spin(0.3)

    gc.callbacks.append(slow)
    try:
        with pytest.raises(BudgetExceeded, match="0.2 s"):
            with nhham.time_budget(0.2):
                gc.collect()   # the alarm lands in the callback, where Python drops it
                _spin(5)
    finally:
        gc.callbacks.remove(slow)
    assert seen == []
    assert sys.unraisablehook == seen.append  # the hook is given back


def test_a_block_within_its_budget_is_untouched_and_the_timer_is_cleared():
    with nhham.time_budget(5):
        assert 0 < remaining_time() <= 5
    assert remaining_time() == float("inf")
    _spin(0.1)  # no stray alarm afterwards


def test_an_inner_budget_never_extends_an_outer_one():
    with pytest.raises(BudgetExceeded, match="0.3 s"):
        with nhham.time_budget(0.3):
            with nhham.time_budget(30):
                assert remaining_time() <= 0.3
                _spin(5)


def test_the_outer_budget_runs_on_after_an_inner_one():
    with pytest.raises(BudgetExceeded, match="0.4 s"):
        with nhham.time_budget(0.4):
            with nhham.time_budget(10):
                pass
            _spin(5)


@pytest.mark.parametrize("bad", [0, -1, float("nan"), float("inf")])
def test_a_budget_must_be_positive_and_finite(bad):
    with pytest.raises(InputError, match="positive finite"):
        with nhham.time_budget(bad):
            pass


def test_off_the_main_thread_the_budget_warns_that_it_cannot_bound():
    caught = []

    def work():
        with pytest.warns(NhhamWarning, match="main thread") as rec:
            with nhham.time_budget(1):
                pass
        caught.extend(rec)

    t = threading.Thread(target=work)
    t.start()
    t.join()
    assert caught


def _car_with_trailer():
    """n = 4, m = 2, W depending on the trailer angle: C has about 550 operations and its
    symbolic solve takes tens of seconds (the issue's car took 50 min)."""
    return nhham.System(
        ["x", "y", "th1", "th2"],
        "m1*(x_dot**2 + y_dot**2)/2 + I1*th1_dot**2/2 + m2*((x_dot + d*sin(th2)*th2_dot)**2"
        " + (y_dot - d*cos(th2)*th2_dot)**2)/2 + I2*th2_dot**2/2",
        ["-sin(th1)*x_dot + cos(th1)*y_dot", "-sin(th2)*x_dot + cos(th2)*y_dot - L2*th2_dot"],
        parameters={"m1": 1.0, "m2": 0.5, "I1": 0.2, "I2": 0.1, "d": 0.4, "L2": 0.8})


def test_a_closed_form_beyond_the_guard_is_refused_with_the_implicit_form_named():
    G = nhham.lagrangian_geometry(_car_with_trailer())
    with pytest.raises(ClosedFormTooLarge, match="equations_of_motion") as err:
        G.multipliers
    assert "closed_form=True" in str(err.value) and "time_budget" in str(err.value)
    with pytest.raises(ClosedFormTooLarge):
        G.projected_field
    # the implicit form is there, at once: W a + mu^T lambda - F for every coordinate
    assert len(G.equations_of_motion) == 4
    with pytest.raises(ClosedFormTooLarge, match="hamiltonian_side"):
        nhham.hamiltonian_side(_car_with_trailer()).multipliers


def test_a_closed_form_asked_for_is_bounded_by_the_budget():
    G = nhham.lagrangian_geometry(_car_with_trailer(), closed_form=True)
    start = time.monotonic()
    with pytest.raises(BudgetExceeded):
        with nhham.time_budget(0.5):
            G.multipliers
    assert time.monotonic() - start < 5


def test_small_closed_forms_pass_the_guard():
    """The rolling disk (C of a few operations): lambda_1 = R m phi' theta' sin(theta), by
    hand from m x'' = -lambda_1 and x'' = -R phi' theta' sin(theta)."""
    G = nhham.lagrangian_geometry(nhham.models.rolling_disk(symbolic=True))
    m, R, th, phd, thd = sp.symbols("m R theta phi_dot theta_dot")
    assert sp.simplify(G.multipliers[0] - R * m * phd * thd * sp.sin(th)) == 0
