"""Libraries built in the background while numpy answers.

The compiler is a wrapper script that waits for a file before it runs the real compiler,
so the tests decide when the build may finish (no timing). Agreement of the two backends
is checked against each other and against the Chaplygin sleigh's closed form.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from nhham.numerics.codegen import numeric_model
from nhham.numerics.codegen.background import stop_background_builds
from nhham.numerics.codegen.build import c_compiler
from nhham.numerics.integrate import simulate
from nhham.numerics.model import NumericsWarning

from test_exact_solutions import chaplygin_sleigh, sleigh_exact, sleigh_state

REAL_CC = c_compiler()
pytestmark = pytest.mark.skipif(REAL_CC is None, reason="no C compiler on this machine")


@pytest.fixture
def held_compiler(tmp_path, monkeypatch):
    """A compiler that logs its process group, then waits for ``go`` before compiling;
    the cache is a fresh one. Yields ``(go, log)``; stops leftover builds afterwards."""
    go, log = tmp_path / "go", tmp_path / "pids"
    script = tmp_path / "held-cc"
    script.write_text(f"#!/bin/sh\necho $$ >> {log}\n"
                      f"while [ ! -e {go} ]; do sleep 0.02; done\nexec {REAL_CC} \"$@\"\n")
    script.chmod(0o755)
    monkeypatch.setenv("CC", str(script))
    monkeypatch.setenv("NHHAM_CACHE", str(tmp_path / "cache"))
    yield go, log
    stop_background_builds()


def live_members(group: int) -> list:
    """Processes of process group ``group`` that are not zombies (read from /proc)."""
    out = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == group and fields[0] != "Z":
            out.append(int(entry.name))
    return out


def sleigh_error(res) -> float:
    """Largest deviation of u, w, theta from the closed form."""
    th, xd, yd, w = res["theta"], res["x_dot"], res["y_dot"], res["theta_dot"]
    u, w_ex, th_ex = sleigh_exact(res.t)
    u_num = np.cos(th) * xd + np.sin(th) * yd
    return max(np.max(np.abs(u_num - u)), np.max(np.abs(w - w_ex)), np.max(np.abs(th - th_ex)))


def test_numpy_answers_while_the_compiler_runs(held_compiler):
    """The first run does not wait for the compiler, says numpy ran, and agrees with the
    compiled run made once the library exists (and both with the closed form)."""
    go, _ = held_compiler
    times = np.linspace(0.0, 4.0, 17)
    opts = dict(method="DOP853", rtol=1e-10, atol=1e-12, t_eval=times, warn=False)
    first = simulate(chaplygin_sleigh(), (0, 4), sleigh_state(), **opts)
    assert first.settings["backend"] == "numpy" and first.settings["loop"] == "scipy"
    assert "background" in first.settings["backend_note"]
    pending = first.model.pending
    assert pending is not None and not pending.ready()
    go.touch()
    assert pending.wait(600) and pending.succeeded(), pending.outcome
    second = simulate(chaplygin_sleigh(), (0, 4), sleigh_state(), **opts)
    assert second.settings["backend"] == "c" and second.settings["loop"] == "compiled"
    assert second.model.pending is None
    # The same method, its error estimates at rtol 1e-10 made of differences at round-off
    # level: step sizes agree to about 1e-6, the states to the tolerance.
    assert np.array_equal(first.t, times) and np.array_equal(second.t, times)
    assert np.allclose(first.y, second.y, rtol=1e-9, atol=1e-10)
    assert sleigh_error(first) < 1e-8 and sleigh_error(second) < 1e-8


def test_a_run_starts_again_on_c_when_the_build_wins(held_compiler):
    """A build that is over before the run ends: the whole run is made again with the
    compiled loop and is the same as a run on a model that had the library at once."""
    go, _ = held_compiler
    model = numeric_model(chaplygin_sleigh(), background=True)
    assert model.backend == "numpy" and model.pending is not None
    go.touch()
    model.pending.wait(600)
    res = simulate(model, (0, 4), sleigh_state(), rtol=1e-10, atol=1e-12, warn=False)
    assert res.settings["backend"] == "c" and res.settings["loop"] == "compiled"
    assert res.model.backend == "c" and res.model.pending is None
    direct = simulate(numeric_model(chaplygin_sleigh()), (0, 4), sleigh_state(), rtol=1e-10,
                      atol=1e-12, warn=False)
    assert np.array_equal(res.t, direct.t) and np.array_equal(res.y, direct.y)
    assert sleigh_error(res) < 1e-8


def test_stopping_kills_the_compiler_and_leaves_nothing(held_compiler, tmp_path):
    """What interpreter exit does: the compiler's whole process group is killed and its
    build directory removed; no library, record or marker appears in the cache."""
    go, log = held_compiler
    model = numeric_model(chaplygin_sleigh(), background=True)
    for _ in range(3000):  # the worker has started the held compiler
        if log.exists() and log.read_text().strip():
            break
        os.sched_yield()
        model.pending.wait(0.01)
    group = int(log.read_text().split()[0])
    assert live_members(group)
    stop_background_builds()
    assert model.pending.ready() and not model.pending.succeeded()
    assert model.pending.state == "stopped"
    assert live_members(group) == []
    assert len(log.read_text().split()) == 1  # no other compilation tried after the stop
    # no library, record or marker (the generated sources, kept before the build, stay)
    assert [f for f in os.listdir(tmp_path / "cache") if not f.startswith("sources_")] in (
        [], [".lock"])
    with pytest.warns(NumericsWarning, match="C backend unavailable.*stopped"):
        still = model.with_library()
    assert still.backend == "numpy"
    # the worker takes new builds after a stop
    go.touch()
    again = numeric_model(chaplygin_sleigh(), background=True)
    assert again.pending.wait(600) and again.pending.succeeded()


def test_a_synchronous_build_waits_for_the_background_one(held_compiler):
    """numeric_model without background=True, while the same library is being built in
    the background, waits for that build: the compiler runs once."""
    go, log = held_compiler
    pending = numeric_model(chaplygin_sleigh(), background=True).pending
    for _ in range(3000):
        if log.exists():
            break
        pending.wait(0.01)
    go.touch()
    model = numeric_model(chaplygin_sleigh())
    assert model.backend == "c" and pending.succeeded()
    assert len(log.read_text().split()) == 1  # one compilation, not two


def test_a_failed_build_leaves_numpy_with_a_warning(tmp_path, monkeypatch):
    """A build that failed during the run: numpy goes on, and a warning says why."""
    script = tmp_path / "broken-cc"
    script.write_text('#!/bin/sh\necho "model.c:1:1: error: no compiler today" >&2\nexit 1\n')
    script.chmod(0o755)
    monkeypatch.setenv("CC", str(script))
    monkeypatch.setenv("NHHAM_CACHE", str(tmp_path / "cache"))
    model = numeric_model(chaplygin_sleigh(), background=True)
    assert model.pending.wait(600) and not model.pending.succeeded()
    with pytest.warns(NumericsWarning, match="C backend unavailable.*no compiler today"):
        res = simulate(model, (0, 4), sleigh_state(), rtol=1e-10, atol=1e-12, warn=False)
    assert res.success and res.settings["backend"] == "numpy"
    assert sleigh_error(res) < 1e-8


def test_a_forked_child_does_not_wait_for_the_parents_build(held_compiler):
    """The worker thread is not in a forked child: builds the child inherited are over
    there (stopped), and the child builds its own library."""
    go, _ = held_compiler
    model = numeric_model(chaplygin_sleigh(), background=True)
    pid = os.fork()
    if pid == 0:  # the child: exit status 0 only if everything holds
        ok = model.pending.wait(5) and model.pending.state == "stopped"
        go.touch()
        ok = ok and numeric_model(chaplygin_sleigh()).backend == "c"
        os._exit(0 if ok else 1)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
    assert model.pending.wait(600) and model.pending.succeeded()  # the parent's own build


def test_a_normal_exit_hands_the_unfinished_build_over(held_compiler):
    """What a normal interpreter exit does: this process's compiler is stopped and a
    builder of its own finishes the library, which the next model then loads at once
    (without it, a command shorter than the compiler never gets its library)."""
    from nhham.numerics.codegen import background

    go, log = held_compiler
    model = numeric_model(chaplygin_sleigh(), background=True)
    for _ in range(3000):  # the worker has started the held compiler
        if log.exists() and log.read_text().strip():
            break
        model.pending.wait(0.01)
    group = int(log.read_text().split()[0])
    builder = background._WORKER.exit()
    assert builder is not None and model.pending.state == "stopped"
    assert live_members(group) == []       # this process's compiler is gone
    go.touch()                             # the builder's compiler may run now
    assert builder.wait(600) == 0
    later = numeric_model(chaplygin_sleigh(), background=True)
    assert later.backend == "c" and later.pending is None
    assert background._WORKER.exit() is None  # nothing left to hand over


def test_an_interrupt_hands_nothing_over(held_compiler, monkeypatch):
    """After Ctrl-C or a stop the user asked for everything to end: no builder starts."""
    from nhham.numerics.codegen import background

    started = []
    monkeypatch.setattr(background, "hand_over", lambda jobs: started.append(jobs))
    model = numeric_model(chaplygin_sleigh(), background=True)
    stop_background_builds()
    assert model.pending.state == "stopped" and started == []


def test_a_build_stopped_while_queued_is_forgotten(held_compiler):
    """A build still queued when the builds stop is gone from the worker's books: the same
    model asked for again starts a new build instead of finding the stopped one (whose
    withdrawal by a synchronous build crashed: it was in the books but not in the queue)."""
    from nhham import models
    from nhham.numerics.codegen import background

    go, _ = held_compiler
    running = numeric_model(chaplygin_sleigh(), background=True)
    queued = numeric_model(models.rolling_disk(), background=True)  # behind the held one
    assert queued.pending.state == "queued"
    stop_background_builds()
    assert running.pending.state == queued.pending.state == "stopped"
    assert background._WORKER.builds == {}
    go.touch()
    assert numeric_model(models.rolling_disk()).backend == "c"
