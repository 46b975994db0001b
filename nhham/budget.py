"""A bound on the time a computation may take: ``with nhham.time_budget(60): ...``.

Symbolic work (sympy's determinants, solves and simplifications) cannot be made to stop
politely from outside, so the budget is an interval timer: when it runs out,
:class:`~nhham.errors.BudgetExceeded` is raised in the main thread wherever the work is.
The command's ``--budget`` is this bound, and the library takes the same one::

    with nhham.time_budget(60):
        G = nhham.lagrangian_geometry(system)
        lam = G.multipliers          # BudgetExceeded after 60 s instead of running on

Budgets nest: an inner bound never extends an outer one, and when the inner block ends
the outer timer runs on with what is left of it. Off the main thread (where Python
delivers no signals) the bound cannot be enforced: a warning says so.
"""

from __future__ import annotations

import math
import signal
import sys
import threading
import time
import warnings
from contextlib import contextmanager
from typing import Callable, Iterator

from nhham.errors import BudgetExceeded, InputError, NhhamWarning

__all__ = ["time_budget", "remaining_time"]

#: After a budget runs out its alarm repeats at this interval until the block is left: an
#: expiry raised where Python drops exceptions (a garbage-collector callback, a
#: ``__del__``, an ``except Exception`` that draws again) is raised again.
REPEAT_S = 0.05

# The deadlines (time.monotonic()) of the budgets in force, outermost first.
_DEADLINES: list[tuple[float, float, Callable[[], str]]] = []


def remaining_time() -> float:
    """Seconds left of the innermost budget in force (inf when there is none).

    Long numeric loops read it to stop at the budget without waiting for a signal.
    """
    return min((d - time.monotonic() for d, _, _ in _DEADLINES), default=math.inf)


@contextmanager
def time_budget(seconds: float | None, what: Callable[[], str] | None = None) -> Iterator[None]:
    """Raise :class:`~nhham.errors.BudgetExceeded` in this block after ``seconds``.

    Parameters
    ----------
    seconds : float or None
        A positive, finite number of seconds; None: no bound (the block just runs).
    what : callable returning str, optional
        Names the step that was running, for the message (the command passes the name
        of its current step).

    Examples
    --------
    >>> import time
    >>> from nhham import BudgetExceeded, time_budget
    >>> try:
    ...     with time_budget(0.05):
    ...         time.sleep(2)
    ... except BudgetExceeded as exc:
    ...     print(exc)
    the budget of 0.05 s ran out
    """
    if seconds is None:
        yield
        return
    if not (isinstance(seconds, (int, float)) and math.isfinite(seconds) and seconds > 0):
        raise InputError(f"time_budget: seconds must be a positive finite number, got "
                         f"{seconds!r}")
    if not hasattr(signal, "setitimer") or threading.current_thread() is not \
            threading.main_thread():
        warnings.warn(f"time_budget({seconds:g}) cannot be enforced off the main thread "
                      f"(no signals there); the block runs without a bound", NhhamWarning,
                      stacklevel=3)
        yield
        return
    now = time.monotonic()
    deadline = min([now + seconds] + [d for d, _, _ in _DEADLINES])
    _DEADLINES.append((deadline, seconds, what or (lambda: "")))

    def expire(signum, frame):
        # The innermost budget whose deadline has passed is the one that ran out.
        late = [b for b in _DEADLINES if b[0] <= time.monotonic() + 1e-3] or _DEADLINES
        _, total, name = late[0]
        step = name()
        where = "" if not step else f" {step}" if step.startswith("after ") else \
            f" during '{step}'"
        raise BudgetExceeded(f"the budget of {total:g} s ran out{where}")

    previous = signal.signal(signal.SIGALRM, expire)
    hook = sys.unraisablehook
    sys.unraisablehook = _quiet_expiry(hook)
    signal.setitimer(signal.ITIMER_REAL, max(deadline - now, 1e-6), REPEAT_S)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        _DEADLINES.pop()
        signal.signal(signal.SIGALRM, previous)
        sys.unraisablehook = hook
        if _DEADLINES:  # the outer budget runs on with what is left of it
            left = _DEADLINES[-1][0] - time.monotonic()
            signal.setitimer(signal.ITIMER_REAL, max(left, 1e-6), REPEAT_S)


def _quiet_expiry(hook):
    """``sys.unraisablehook`` that passes over an expiry raised where Python drops
    exceptions (a garbage-collector callback, a weakref finaliser): the alarm repeats
    until the block is left, so the budget still ends the work, and Python would print
    "Exception ignored in ..." with a traceback among the command's one-line messages.
    Any other unraisable exception goes to ``hook``."""

    def quiet(unraisable):
        if not isinstance(unraisable.exc_value, BudgetExceeded):
            hook(unraisable)

    return quiet
