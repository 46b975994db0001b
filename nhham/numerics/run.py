"""The raw output of one integration loop, before diagnostics: :class:`Run`.

Every loop (scipy's solvers, the compiled Runge-Kutta loop, the fixed-step schemes, the
mpmath reference) returns a :class:`Run`; :func:`nhham.numerics.integrate.simulate` adds
the diagnostics and returns a :class:`~nhham.numerics.integrate.SimulationResult`. States
are columns, as in scipy: ``y`` has shape (2n, K). No sympy here.
"""

from __future__ import annotations

import math
import signal
import sys
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Iterator

import numpy as np

from nhham.numerics.status import Status

__all__ = ["Run", "report_progress", "PAUSE_SECONDS", "Deadline", "interruptible",
           "final_state_text"]

#: Wall time after which the compiled loops hand control back to Python: a signal
#: (Ctrl-C, the command's ``--budget``) is handled within this, never after a long run
#: of steps (one return costs microseconds).
PAUSE_SECONDS = 0.005


@dataclass(frozen=True)
class Run:
    """Raw output of an integration loop.

    Attributes
    ----------
    t : ndarray (K,)
    y : ndarray (2n, K)
        ``y[i]`` is the i-th state variable over time.
    work : ndarray (K,) or None
        Work of the constraint forces when the loop carries it.
    status : Status
    message : str
    nfev : int
        Right-hand-side evaluations in states (batched calls count each state); for
        RATTLE: one per (sub)step plus one per Newton iteration.
    nsteps : int
    njev, nlu : int
        Jacobian evaluations and LU decompositions (implicit scipy methods).
    newton_iterations : int
        Newton iterations of the RATTLE schemes.
    step : float or None
        The step actually used by a fixed-step scheme ((t1 - t0)/N).
    sol : DenseOutput or None
        The continuous solution (scipy methods with ``dense_output=True``).
    t_events, y_events : list of ndarray or None
        Event times and states, one entry per event function (scipy methods with
        ``events``).
    failed_state : ndarray (2n,) or None
        The state at which an evaluation of the field failed (a stage of the step that
        did not complete), when the loop knows it; the stored trajectory ends at the
        last completed step before it.
    """

    t: np.ndarray
    y: np.ndarray
    work: np.ndarray | None
    status: Status
    message: str
    nfev: int
    nsteps: int
    njev: int = 0
    nlu: int = 0
    newton_iterations: int = 0
    step: float | None = None
    sol: object = None
    t_events: list | None = None
    y_events: list | None = None
    failed_state: np.ndarray | None = None


@dataclass(frozen=True)
class Deadline:
    """When a run stops early: its wall-time limit (``simulate(time_limit=...)``; inf for
    none) or a Ctrl-C inside :func:`interruptible`. The loops look at it after every step
    (Python) or every return of the compiled loop (every few ms) and stop with
    :meth:`stop_status`, keeping what they computed."""

    seconds: float
    end: float

    @classmethod
    def after(cls, seconds) -> "Deadline":
        if seconds is None:
            return cls(math.inf, math.inf)
        return cls(float(seconds), time.perf_counter() + seconds)

    def passed(self) -> bool:
        return _INTERRUPTED.is_set() or time.perf_counter() > self.end

    def remaining(self) -> float:
        """Seconds left (negative once passed)."""
        return self.end - time.perf_counter()

    def stop_status(self) -> Status:
        """INTERRUPTED after a Ctrl-C, else TIME_LIMIT."""
        return Status.INTERRUPTED if _INTERRUPTED.is_set() else Status.TIME_LIMIT

    def message(self, t) -> str:
        if _INTERRUPTED.is_set():
            return (f"interrupted (Ctrl-C) at t = {t:.6g}, before the end of the interval; "
                    f"the states up to there are kept")
        return (f"stopped at the time limit of {self.seconds:g} s (wall time) at t = {t:.6g}, "
                f"before the end of the interval")


#: Set by the first Ctrl-C inside :func:`interruptible`.
_INTERRUPTED = threading.Event()


@contextmanager
def interruptible() -> Iterator[None]:
    """A Ctrl-C in this block stops the run at the loops' next look at their
    :class:`Deadline` (status ``INTERRUPTED``), keeping the states computed; a second one
    interrupts at once (KeyboardInterrupt). Off the main thread (no signals) nothing
    changes.

    Examples
    --------
    >>> with interruptible():
    ...     Deadline.after(None).passed()
    False
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def first(signum, frame):
        if _INTERRUPTED.is_set():
            raise KeyboardInterrupt
        _INTERRUPTED.set()

    _INTERRUPTED.clear()
    previous = signal.signal(signal.SIGINT, first)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        _INTERRUPTED.clear()


def report_progress(t, t0, t1, reported):
    """Print each passed tenth of the interval on stderr; returns the tenths done."""
    tenths = int(10 * (t - t0) / (t1 - t0))
    if tenths > reported:
        print(f"  t = {t:.6g} ({10 * tenths}%)", file=sys.stderr, flush=True)
    return max(reported, tenths)


def final_state_text(state, label: str = "final state") -> str:
    """``<label>: x = ..., y = ...`` packed into lines of the terminal's width (COLUMNS
    first), a value never split from its name.

    Examples
    --------
    >>> print(final_state_text({"x": 1.0, "x_dot": 0.5}))
      final state: x = 1, x_dot = 0.5
    """
    import shutil

    room = max(60, shutil.get_terminal_size((100, 24)).columns)
    head = f"  {label}: "
    items = [f"{k} = {v:.10g}" for k, v in state.items()]
    lines, line = [], head
    for i, item in enumerate(items):
        piece = item + ("," if i < len(items) - 1 else "")
        if len(line) + len(piece) > room and line != head:
            lines.append(line.rstrip())
            line = " " * len(head)
        line += piece + " "
    return "\n".join(lines + [line.rstrip()])
