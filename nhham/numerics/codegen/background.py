"""Building a model's library in the background while numpy answers.

A first run on a model whose library is not in the compile cache need not wait for the C
compiler: :func:`build_in_background` queues the build and returns a
:class:`BackgroundBuild` at once; the numpy kernels evaluate the model meanwhile (see
``NumericModel.pending``), and :func:`nhham.numerics.integrate.simulate` runs again with
the compiled code when the build finishes before the run does.

One worker thread builds the queued libraries one at a time (one compiler at a time, so a
process that makes many models does not start a compiler for each at once). Builds still
queued or running when the interpreter exits are stopped: the compiler's process group is
killed and its build directory removed (no half-written file is left); at a normal exit they
are then handed to a builder process of their own (:mod:`.handover`), so that a later run
finds the library even when every run is shorter than the compiler; after an interrupt or
a stop (:func:`stop_background_builds`) nothing is handed over and no compiler outlives
the process. A synchronous request for
a library being built in the background waits for that build instead of starting another
(:func:`take_over`). Messages meant as warnings are kept in the outcome and issued by the
thread that uses it (warnings from the worker thread would escape the caller's capture).
No sympy here.
"""

from __future__ import annotations

import atexit
import collections
import os
import threading
import warnings

from nhham.numerics.codegen.build import (LibraryBuild, build_library, kill_group, load_library,
                                          signal_group)
from nhham.numerics.codegen.cache import CompileCache
from nhham.numerics.codegen.handover import hand_over
from nhham.numerics.model import NumericsWarning

__all__ = ["BackgroundBuild", "build_in_background", "take_over", "stop_background_builds"]

_JOIN_AT_EXIT_S = 10.0


class BackgroundBuild:
    """A model's library being built by the worker thread.

    ``ready()`` and ``succeeded()`` are cheap (an event), so that an integration can ask
    at every evaluation; :attr:`outcome` is the :class:`~.build.LibraryBuild` once ready.
    """

    def __init__(self, sources, cache: CompileCache) -> None:
        self.sources = sources
        self.cache = cache
        self.outcome: LibraryBuild | None = None
        self.state = "queued"  # -> running -> done; or withdrawn / stopped
        self._done = threading.Event()

    def __repr__(self):
        return f"BackgroundBuild({self.state})"

    def ready(self) -> bool:
        """The build is over (built, failed, withdrawn or stopped)."""
        return self._done.is_set()

    def succeeded(self) -> bool:
        """The build is over and a library was built."""
        return self._done.is_set() and self.outcome is not None and self.outcome.path is not None

    def wait(self, timeout=None) -> bool:
        """Wait until the build is over; False when ``timeout`` passed first."""
        return self._done.wait(timeout)

    def failure(self) -> str:
        """Why no library came out of a build that is over (empty while it runs or when
        it succeeded)."""
        if not self.ready() or self.succeeded():
            return ""
        return self.outcome.note if self.outcome is not None else f"the build was {self.state}"

    def load(self, layout) -> tuple:
        """``(CompiledRHS or None, note)``: the library, loaded, once the build is over
        (waits for it); a :class:`~nhham.numerics.model.NumericsWarning` when numpy
        stays (why) or the plain library replaces the CPython entry points. Called by
        the thread that uses the model."""
        self.wait()
        outcome = self.outcome or LibraryBuild(None, False, self.failure())
        compiled, note = load_library(outcome, layout)
        if compiled is None:
            warnings.warn(f"C backend unavailable ({note}); using numpy", NumericsWarning,
                          stacklevel=3)
        return compiled, note

    def _finish(self, state: str, outcome: LibraryBuild | None) -> None:
        self.state, self.outcome = state, outcome
        self._done.set()


class _Worker:
    """The one thread that builds the queued libraries, and what it is doing."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.wake = threading.Condition(self.lock)
        self.queue: collections.deque = collections.deque()
        self.builds: dict = {}  # source text -> BackgroundBuild (queued or running)
        self.process = None     # the running compiler
        self.closing = False
        self.thread: threading.Thread | None = None

    def submit(self, sources, cache) -> BackgroundBuild:
        with self.lock:
            build = self.builds.get(sources["c"])
            if build is not None:
                return build
            build = BackgroundBuild(sources, cache)
            if self.closing:
                build._finish("stopped", None)
                return build
            self.builds[sources["c"]] = build
            self.queue.append(build)
            if self.thread is None:
                self.thread = threading.Thread(target=self.run, name="nhham-compile",
                                               daemon=True)
                self.thread.start()
                # Registered now, after the cache was opened: exit handlers run last
                # first, so the builds stop before a private cache directory is removed.
                atexit.register(self.exit)
            self.wake.notify()
        return build

    def run(self) -> None:
        while True:
            with self.lock:
                while not self.queue and not self.closing:
                    self.wake.wait()
                if self.closing:
                    return
                build = self.queue.popleft()
                build.state = "running"
            outcome = None
            try:
                outcome = build_library(build.sources, build.cache, self.started)
            except BaseException as exc:  # never let the worker die with a build pending
                outcome = LibraryBuild(None, False, f"background build failed: {exc}")
            finally:
                with self.lock:
                    self.process = None
                    self.builds.pop(build.sources["c"], None)
                    stopped = self.closing
                build._finish("stopped" if stopped else "done", None if stopped else outcome)

    def started(self, process) -> None:
        """The compiler of the running build started (killed at once when closing)."""
        with self.lock:
            self.process = process
            closing = self.closing
        if closing:
            kill_group(process)

    def withdraw(self, sources) -> BackgroundBuild | None:
        """A queued build of ``sources`` is taken off the queue; a running one returned."""
        with self.lock:
            build = self.builds.get(sources["c"])
            if build is None or build.state == "running":
                return build
            self.queue.remove(build)
            del self.builds[sources["c"]]
        build._finish("withdrawn", None)
        return None

    def after_fork(self) -> None:
        """In a child process: no worker thread, and the builds inherited from the parent
        are over (stopped) for the child; its own builds start a new worker."""
        for build in self.builds.values():
            build._done = threading.Event()  # the parent's may be locked by a lost thread
            build._finish("stopped", None)
        self.__init__()  # type: ignore[misc]

    def exit(self):
        """At a normal interpreter exit: the unfinished builds go to a builder process of
        their own (:mod:`.handover`), then this process's are stopped."""
        with self.lock:
            jobs = [(b.cache.directory, b.sources["c"]) for b in self.builds.values()
                    if not b.cache.private and not self.closing]
        self.stop()
        return hand_over(jobs)

    def stop(self) -> None:
        with self.lock:
            self.closing = True
            queued, self.queue = list(self.queue), collections.deque()
            for build in queued:  # a later request of the same source starts afresh
                self.builds.pop(build.sources["c"], None)
            process, thread = self.process, self.thread
            self.wake.notify_all()
        for build in queued:
            build._finish("stopped", None)
        if process is not None:
            signal_group(process)  # the worker reaps it and sees the signal: no fallback
        if thread is not None:
            thread.join(_JOIN_AT_EXIT_S)
            if thread.is_alive():
                return  # stays closed: no new build may start beside a stuck one
        with self.lock:
            self.closing, self.thread = False, None


_WORKER = _Worker()
os.register_at_fork(after_in_child=_WORKER.after_fork)


def build_in_background(sources, cache: CompileCache) -> BackgroundBuild:
    """Queue the build of a model's library (or return the one already queued or running
    for the same source)."""
    return _WORKER.submit(sources, cache)


def take_over(sources) -> None:
    """Before building ``sources`` synchronously: wait for a background build of the same
    source that is running (its library is then in the cache); withdraw a queued one."""
    build = _WORKER.withdraw(sources)
    if build is not None:
        build.wait()


def stop_background_builds() -> None:
    """Stop every queued and running background build and hand nothing over (after an
    interrupt or a stop; a normal interpreter exit hands the unfinished ones over)."""
    _WORKER.stop()
