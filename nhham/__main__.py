"""``python -m nhham`` and the ``nhham`` script: the command (see :mod:`nhham.cli`).

:func:`run` loads the command inside a Ctrl-C handler: the imports (sympy, numpy) take
about a second, and an interrupt there ends as one later does, with one line and exit
status 130 (``EXIT_INTERRUPTED`` of :mod:`nhham.cli.envelope`), not a traceback. After an
interrupt or a stop (status 130 or 3: Ctrl-C, ``--budget``, a failed computation) the
process ends at once, once background compiler builds are stopped: tearing down a large
symbolic model object by object takes seconds, and nothing else is left to do.

:func:`script` (the ``nhham`` script and ``python -m nhham``) ends every run that way,
after the exit handlers (the background builds' hand-over, the private cache's removal):
the interpreter's teardown of sympy's objects took 0.25-0.5 s of each command. It also
collects garbage less often (a command allocates millions of objects that live until it
ends). :func:`run` itself returns, for callers in Python.
"""

import atexit
import gc
import os
import sys
import threading

_STOPPED = (3, 130)


def run(argv=None) -> int:
    """Run the command; returns the exit status (after a stop the process ends here)."""
    try:
        from nhham.cli.main import main

        status = main(argv)
    except KeyboardInterrupt:  # while loading, or in the last lines of main
        print("nhham: interrupted", file=sys.stderr)
        status = 130
    if status in _STOPPED:
        builds = sys.modules.get("nhham.numerics.codegen.background")
        if builds is not None:  # what its exit handler does: no compiler outlives us
            builds.stop_background_builds()
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)
    return status


def script() -> None:
    """The ``nhham`` script: :func:`run`, then the process ends without tearing down its
    objects (unless a thread that is not a daemon is still running: then as usual)."""
    gc.set_threshold(50_000, 20, 100)
    status = run()
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except BrokenPipeError:   # the reader stopped early (| head): not an error of ours
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    if any(t.is_alive() and not t.daemon for t in threading.enumerate()
           if t is not threading.main_thread()):
        sys.exit(status)
    atexit._run_exitfuncs()
    os._exit(status)


if __name__ == "__main__":
    script()
