"""``python -m nhham`` and the ``nhham`` script: the command (see :mod:`nhham.cli`).

:func:`run` loads the command inside a Ctrl-C handler: the imports (sympy, numpy) take
about a second, and an interrupt there ends as one later does, with one line and exit
status 130 (``EXIT_INTERRUPTED`` of :mod:`nhham.cli.envelope`), not a traceback. After an
interrupt or a stop (status 130 or 3: Ctrl-C, ``--budget``, a failed computation) the
process ends at once, once background compiler builds are stopped: tearing down a large
symbolic model object by object takes seconds, and nothing else is left to do.
"""

import os
import sys

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


if __name__ == "__main__":
    sys.exit(run())
