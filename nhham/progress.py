"""What a long computation is doing, said where it happens: ``with progress.part(...)``.

A command records its steps (:class:`nhham.render.text.Steps`): on a terminal each is
announced as it starts, ``--verbose`` lists them with their times and ``--budget`` names
the one that was running when it ran out. The steps are coarse (one is "the constraint
algorithm at the parameter values"); a part of one that can take long (a symbolic inverse,
a cross-check, a reduction's check) opens a *part* here, wherever it is in the library, so
that the name the user sees is the work actually running. In a library call no recorder is
installed and a part costs a context-variable read.

Examples
--------
>>> from nhham import progress
>>> with progress.part("Legendre inverse"):   # no command running: nothing is shown
...     pass
"""

from __future__ import annotations

import contextvars
import time
from contextlib import contextmanager
from typing import Iterator

__all__ = ["reporting", "part"]

_STEPS: contextvars.ContextVar = contextvars.ContextVar("nhham_steps", default=None)


@contextmanager
def reporting(steps) -> Iterator[None]:
    """Parts opened in this block are reported to ``steps`` (a ``Steps``)."""
    token = _STEPS.set(steps)
    try:
        yield
    finally:
        _STEPS.reset(token)


@contextmanager
def part(what: str, note: str = "") -> Iterator[None]:
    """A part of the running step: named while it runs (terminal, budget), recorded with
    its time when it ends (``--verbose``).

    Parameters
    ----------
    what : str
        What is computed, in the words of the report ("Legendre inverse v(q, p) by the
        adjugate of W").
    note : str, optional
        Shown beside it on a terminal (a size, an estimate).
    """
    steps = _STEPS.get()
    if steps is None:
        yield
        return
    outer = steps.current
    steps.part(what, note)
    start = time.perf_counter()
    try:
        yield
    finally:
        steps.current = outer
    steps.records.append((f"  {what}", time.perf_counter() - start))
