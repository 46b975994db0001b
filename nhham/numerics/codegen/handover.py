"""Finishing, after nhham exits, the libraries its background builds had not finished.

A short command on a new model answers with numpy while its library is compiled in the
background (:mod:`.background`); when the command ends first, the build would be lost,
and every later short command would start it again and lose it again: the user's runs
would never become compiled. So at a normal interpreter exit the builds still queued or
running are handed to one builder process of their own (a new session, no terminal, no
output), which compiles them into the same compile cache; a later run loads the library
from there. An interrupt or a stop (Ctrl-C, ``--budget``) hands nothing over: the user
asked for everything to end. A private temporary cache (an untrusted one was refused) is
removed at exit, so nothing of it is handed over.

The builder reads ``{"cache": DIRECTORY, "sources": [C TEXT, ...]}`` as JSON on its
standard input and builds each library as a synchronous build would
(:func:`~.build.build_library`: checked cache, atomic install, a failure remembered).
No sympy here.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

__all__ = ["hand_over", "main"]


def hand_over(jobs) -> subprocess.Popen | None:
    """Start the builder for ``jobs``, a list of ``(cache directory, C source)``; returns
    its process (not waited for), or None when there is nothing to build or it cannot
    start.

    Examples
    --------
    >>> hand_over([]) is None
    True
    """
    if not jobs:
        return None
    by_cache: dict = {}
    for directory, source in jobs:
        by_cache.setdefault(directory, []).append(source)
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(
        os.path.abspath(__file__)))))
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, (root, env.get("PYTHONPATH"))))
    payload = json.dumps([{"cache": d, "sources": s} for d, s in by_cache.items()])
    try:
        process = subprocess.Popen(
            [sys.executable, "-m", "nhham.numerics.codegen.handover"], stdin=subprocess.PIPE,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
            close_fds=True, env=env, cwd=root)
        assert process.stdin is not None
        with process.stdin:
            process.stdin.write(payload.encode())
    except OSError:  # no process could be started (limits, a full disk): a later run builds
        return None
    return process


def main() -> int:
    """The builder: build every library named on standard input; 0 when all were built."""
    entries = json.load(sys.stdin)  # first: the parent waits until its pipe is read
    from nhham.numerics.codegen.build import build_library
    from nhham.numerics.codegen.cache import CompileCache

    failed = 0
    for entry in entries:
        try:
            cache = CompileCache.open(entry["cache"])
        except OSError:
            failed += len(entry["sources"])
            continue
        if cache.private:  # the configured one is no longer trusted: build nothing there
            failed += len(entry["sources"])
            continue
        for source in entry["sources"]:
            built = build_library({"c": source}, cache)
            failed += built.path is None
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
