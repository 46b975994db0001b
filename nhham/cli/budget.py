"""The command's ``--budget SECONDS``: :func:`nhham.budget.time_budget` naming the step.

When the budget runs out the command reports what it had decided (the steps finished,
with how each decision was made) and the step that was running.
"""

from __future__ import annotations

from contextlib import contextmanager

from nhham.budget import time_budget as _library_budget
from nhham.errors import BudgetExceeded

__all__ = ["BudgetExceeded", "time_budget"]


@contextmanager
def time_budget(seconds: float | None, steps):
    """:func:`nhham.budget.time_budget` whose message names ``steps.current``.

    Parameters
    ----------
    seconds : float or None
        None: no bound.
    steps : nhham.render.text.Steps
    """
    with _library_budget(seconds, steps.where):
        yield
