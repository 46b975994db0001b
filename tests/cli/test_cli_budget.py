"""``--budget`` and Ctrl-C: they stop a command wherever it is, the compiled integration
loops included (they hand control back every few milliseconds), with one line and the
contract's exit status (3 for the budget, 130 for Ctrl-C)."""

import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from nhham.cli.budget import BudgetExceeded, time_budget
from nhham.render.text import Steps
from nhham.numerics.codegen import numeric_model
from nhham.numerics.integrate import simulate

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "numerics"))
from test_exact_solutions import rolling_disk, rolling_disk_exact  # noqa: E402


@pytest.mark.parametrize("method, options", [("DOP853", {}), ("DOP853", {"projection": True}),
                                             ("rattle", {"step": 0.01}),
                                             ("rattle4", {"step": 0.01})])
def test_budget_stops_a_compiled_loop_before_its_end(monkeypatch, method, options):
    """A run of millions of steps (seconds to minutes) with a budget of 0.3 s: the
    budget's exception comes out of simulate while the compiled loop is still short of
    the end (the time it had reached at its last return, recorded by a wrapper, is below
    t_end; a loop that ran to the end in one call would have reached it first)."""
    model = numeric_model(rolling_disk())
    if model.backend != "c":
        pytest.skip("no C compiler on this machine")
    y0, _ = rolling_disk_exact(np.array(0.0))
    reached = []
    if method == "DOP853":
        erk = model.compiled.erk

        def wrapper(info, tab, ws, *rest):
            status = erk(info, tab, ws, *rest)
            reached.append(float(ws[0]))
            return status

        monkeypatch.setattr(model.compiled, "erk", wrapper)
    else:
        rattle = model.compiled.rattle

        def wrapper(y, h, *rest):
            status = rattle(y, h, *rest)
            reached.append(float(rest[-1][0]) * h)  # info[0]: steps done
            return status

        monkeypatch.setattr(model.compiled, "rattle", wrapper)
    t_end = 1e6 if method == "DOP853" else 1e5
    with pytest.raises(BudgetExceeded, match="0.3 s"):
        with time_budget(0.3, Steps()):
            simulate(model, (0, t_end), y0, method=method, warn=False, save_every=10**9,
                     **options)  # no stored step fills the room: only the clock pauses
    assert reached and reached[-1] < 0.5 * t_end


def _command(*args):
    # SIGINT as at a terminal: a test run started in the background (a shell's `&`) would
    # pass SIGINT on ignored, and Python keeps an ignored SIGINT ignored.
    return subprocess.Popen([sys.executable, "-m", "nhham", *map(str, args)], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


@pytest.mark.parametrize("delay", [0.2, 4.0])
def test_ctrl_c_exits_130_with_one_line(delay):
    """Ctrl-C while the command loads (0.2 s: sympy is being imported) or while it
    integrates (a run of minutes): exit 130 and one line (after the run's warnings), no
    traceback; during the run the states computed so far are printed (and written:
    tests/numerics/test_run.py)."""
    for wait in (delay, 2 * delay, 4 * delay):
        proc = _command("simulate", ROOT / "examples" / "rolling_disk.toml", "--t-end", "1e7")
        time.sleep(wait)
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=120)
        # on a loaded machine the signal can arrive while the interpreter itself starts
        # (its site module), before any code of nhham's: wait longer then
        if "init_import_site" not in err:
            break
    assert proc.returncode == 130, err
    if "final state" in out:   # the run had started: its states up to there are printed
        *before, last = err.splitlines()
        assert last.startswith("nhham: interrupted (Ctrl-C) at t = ")
        # a fast machine reaches t ~ 1e5 first: the drift warnings it gave stay, one line each
        assert all(line.startswith("nhham: warning: ") for line in before), err
    else:   # still loading
        assert err == "nhham: interrupted\n" and out == ""
