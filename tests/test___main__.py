"""``python -m nhham`` (nhham.__main__): the exit status of the command, and after an
interrupt (130: one line, no traceback) or a stop (3) the process ends at once, once
background compiler builds are stopped. The command and the process's end are replaced
here, so that what run() decides is seen without ending the test process."""

import importlib
import os
import sys

import pytest

import nhham.__main__ as entry

cli_main = importlib.import_module("nhham.cli.main")


class Ended(Exception):
    """os._exit(status), recorded instead of ending the process."""


@pytest.fixture
def command(monkeypatch):
    """Make ``main`` do what a test says; os._exit raises Ended(status)."""
    def exit_now(status):
        raise Ended(status)

    monkeypatch.setattr(os, "_exit", exit_now)

    def set_main(behaviour):
        monkeypatch.setattr(cli_main, "main", behaviour)

    return set_main


@pytest.mark.parametrize("status", [0, 1, 2])
def test_other_statuses_are_returned(command, status):
    command(lambda argv: status)
    assert entry.run(["classify", "x.toml"]) == status


def test_an_interrupt_is_one_line_and_status_130(command, capsys):
    def interrupted(argv):
        raise KeyboardInterrupt

    command(interrupted)
    with pytest.raises(Ended) as info:
        entry.run([])
    assert info.value.args == (130,)
    assert capsys.readouterr().err == "nhham: interrupted\n"


def test_a_stop_ends_the_process_after_stopping_the_builds(command, monkeypatch):
    stopped = []

    class Builds:
        @staticmethod
        def stop_background_builds():
            stopped.append(True)

    monkeypatch.setitem(sys.modules, "nhham.numerics.codegen.background", Builds)
    command(lambda argv: 3)
    with pytest.raises(Ended) as info:
        entry.run([])
    assert info.value.args == (3,) and stopped == [True]
    monkeypatch.delitem(sys.modules, "nhham.numerics.codegen.background")
    with pytest.raises(Ended):  # no builds module loaded: nothing to stop
        entry.run([])
    assert stopped == [True]


def test_the_script_runs_the_exit_handlers_then_ends_without_teardown(command, monkeypatch):
    """script(): the status of run(), the exit handlers first (the background builds'
    hand-over lives there), then os._exit; with a live non-daemon thread, sys.exit."""
    import atexit
    import threading

    ran = []
    monkeypatch.setattr(atexit, "_run_exitfuncs", lambda: ran.append("handlers"))
    monkeypatch.setattr(entry.gc, "set_threshold", lambda *thresholds: None)
    main_only = [threading.main_thread()]
    monkeypatch.setattr(entry.threading, "enumerate", lambda: main_only)
    command(lambda argv: 2)
    monkeypatch.setattr(sys, "argv", ["nhham"])
    with pytest.raises(Ended) as info:
        entry.script()
    assert info.value.args == (2,) and ran == ["handlers"]

    class Working:   # a thread the command left running: the usual end
        daemon = False

        @staticmethod
        def is_alive():
            return True

    main_only.append(Working())
    with pytest.raises(SystemExit) as stop:
        entry.script()
    assert stop.value.code == 2 and ran == ["handlers"]
