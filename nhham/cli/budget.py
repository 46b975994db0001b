"""A bound on the time a command may take (``--budget SECONDS``).

Symbolic work cannot be made to stop politely from outside, so the budget is an
interval timer: when it runs out, :class:`BudgetExceeded` is raised in the main
thread wherever the work is, and the command reports what it had decided (the
steps finished, with how each decision was made) and the step that was running.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

from nhham.errors import InputError, NhhamError

__all__ = ["BudgetExceeded", "time_budget"]


class BudgetExceeded(NhhamError):
    """The command's time budget ran out."""


@contextmanager
def time_budget(seconds: float | None, steps):
    """Raise :class:`BudgetExceeded` in this block after ``seconds`` (None: no bound).

    Parameters
    ----------
    seconds : float or None
    steps : nhham.cli.report.Steps
        Names the step that was running in the message.
    """
    usable = (seconds is not None and hasattr(signal, "setitimer")
              and threading.current_thread() is threading.main_thread())
    if seconds is not None and seconds <= 0:
        raise InputError(f"--budget must be a positive number of seconds, got {seconds:g}")
    if not usable or seconds is None:
        yield
        return

    def expire(signum, frame):
        raise BudgetExceeded(f"the budget of {seconds:g} s ran out during "
                             f"'{steps.current or 'start-up'}'")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
