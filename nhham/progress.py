"""What a long computation is doing, said where it happens: ``with progress.part(...)``.

A command records its steps (:class:`nhham.render.text.Steps`): on a terminal each is
announced as it starts, ``--verbose`` lists them with their times and ``--budget`` names
the one that was running when it ran out. The steps are coarse (one is "the constraint
algorithm at the parameter values"); a part of one that can take long (a symbolic inverse,
a cross-check, a reduction's check) opens a *part* here, wherever it is in the library, so
that the name the user sees is the work actually running. Parts nest: the name is the path
of the open parts ("run b - 1 = 0: exceptional values where C is singular"), which
:func:`current` gives in a library call too (a budget's message names it). A part that is
short more often than not is shown on the terminal only once it has run ``after``
seconds. In a library call no recorder is installed and a part costs two
context-variable writes.

Examples
--------
>>> from nhham import progress
>>> with progress.part("Legendre inverse"):   # no command running: nothing is shown
...     pass
"""

from __future__ import annotations

import contextvars
import threading
import time
from contextlib import contextmanager
from typing import Callable, Iterator

from nhham.errors import BudgetExceeded

__all__ = ["reporting", "part", "current", "SLOW"]

#: Seconds after which a part that is short more often than not is shown on a terminal
#: (``part(..., after=SLOW)``): a long run is announced, a quick one leaves no line.
SLOW = 1.0

_STEPS: contextvars.ContextVar = contextvars.ContextVar("nhham_steps", default=None)
# The names of the parts open here, outermost first.
_OPEN: contextvars.ContextVar = contextvars.ContextVar("nhham_parts", default=())


@contextmanager
def reporting(steps) -> Iterator[None]:
    """Parts opened in this block are reported to ``steps`` (a ``Steps``)."""
    token = _STEPS.set(steps)
    try:
        yield
    finally:
        _STEPS.reset(token)


@contextmanager
def part(what: str, note: str | Callable[[], str] = "", after: float = 0.0) -> Iterator[None]:
    """A part of the running step: named while it runs (terminal, budget), recorded with
    its time when it ends (``--verbose``).

    Parameters
    ----------
    what : str
        What is computed, in the words of the report ("Legendre inverse v(q, p) by the
        adjugate of W").
    note : str or callable returning str, optional
        Shown beside it on a terminal (a size, an estimate); a callable is asked when
        the line is shown (an estimate made then).
    after : float, optional
        Seconds the part must run before it is shown on the terminal (0: at once). It
        is named for a budget's message and recorded from the start either way.
    """
    opened = _OPEN.get()
    token = _OPEN.set(opened + (what,))
    try:
        steps = _STEPS.get()
        if steps is None:
            yield
            return
        with _reported(steps, what, opened, note, after):
            yield
    except BudgetExceeded as exc:  # the innermost part it leaves is where it ran out
        if not exc.part:
            exc.part = current()
        raise
    finally:
        _OPEN.reset(token)


def current() -> str:
    """The open parts, outermost first, joined by ": " ("" when none is open).

    Examples
    --------
    >>> from nhham import progress
    >>> with progress.part("run b - 1 = 0"), progress.part("exceptional values"):
    ...     progress.current()
    'run b - 1 = 0: exceptional values'
    """
    return ": ".join(_OPEN.get())


@contextmanager
def _reported(steps, what: str, opened: tuple, note, after: float) -> Iterator[None]:
    """Name the part on ``steps`` (a ``Steps``), show it now or after ``after`` seconds
    (a timer thread: a single long part would otherwise never be shown), record its time."""
    outer = steps.current
    depth = len(opened)
    path = ": ".join(opened + (what,))
    text = (lambda: note()) if callable(note) else (lambda: note)
    steps.part(path, "", show=False)
    timer = None
    if after <= 0:
        steps.show(what, text(), depth)
    elif steps.progress:
        timer = threading.Timer(after, lambda: steps.show(what, text(), depth))
        timer.daemon = True
        timer.start()
    start, at = time.perf_counter(), len(steps.records)
    try:
        yield
    finally:
        if timer is not None:
            timer.cancel()
        steps.current = outer
    # before the parts it contains, as a step is
    steps.records.insert(at, ("  " * (depth + 1) + what, time.perf_counter() - start))
