"""One status vocabulary for the numerics: the compiled kernels, the integrators, the results.

:class:`Status` is an :class:`enum.IntEnum` (as diffrax's ``RESULTS``): every member has a
message, the generated C receives the codes as ``#define NHHAM_<NAME> <code>`` lines made
from this enum (:func:`c_defines`), the integrators return its members and every result's
``status`` is one of them (an ``int`` for JSON and comparisons: ``result.status == 0``).
:class:`NumericalFailure` is the one exception a failed numeric evaluation or step raises;
it carries its status. No sympy here.
"""

from __future__ import annotations

import enum

from nhham.errors import ComputationError

__all__ = ["Status", "NumericalFailure", "c_defines", "STOPPED"]


class Status(enum.IntEnum):
    """Outcome of a numeric evaluation or integration; ``status.message`` says it in words.

    As in scipy, a run succeeded when its status is >= 0 (``SUCCESS``, or ``EVENT``: a
    terminal event stopped it); a run that fails keeps what it computed up to the failure,
    and its ``message`` is the member's message with where it happened. ``PAUSED`` is
    internal to the compiled loop, never the status of a result.
    """

    SUCCESS = 0
    EVENT = 1
    PAUSED = 2
    STEP_FAILED = -1
    NONFINITE = -2
    SINGULAR = -3
    NOT_CONVERGED = -4
    TIME_LIMIT = -5
    INTERRUPTED = -6

    @property
    def message(self) -> str:
        return _MESSAGES[self]


_MESSAGES = {
    Status.SUCCESS: "reached the end of the interval",
    Status.EVENT: "a termination event occurred",
    Status.PAUSED: "paused (the compiled loop hands control back between chunks of steps; "
                   "never the status of a result)",
    Status.STEP_FAILED: "integration step failed (step size too small)",
    Status.NONFINITE: "non-finite or overflowing state or right-hand side (NaN or overflow)",
    Status.SINGULAR: "singular saddle-point system",
    Status.NOT_CONVERGED: "Newton iteration or projection did not converge",
    Status.TIME_LIMIT: "stopped at the time limit (wall time) before the end of the interval",
    Status.INTERRUPTED: "interrupted (Ctrl-C) before the end of the interval",
}

#: Stopped from outside (a time limit, a Ctrl-C), not by the run: what it computed is kept
#: and good.
STOPPED = frozenset({Status.TIME_LIMIT, Status.INTERRUPTED})


class NumericalFailure(ComputationError):
    """A numeric evaluation or integration step failed; ``status`` says how.

    Parameters
    ----------
    status : Status or int
    message : str, optional
        What happened and where; default: the status's own message.
    state : ndarray, optional
        The state at which it happened, when known (``self.state``, else None).
    """

    def __init__(self, status, message: str | None = None, state=None):
        self.status = Status(status)
        self.state = state
        super().__init__(message or self.status.message)


def c_defines() -> str:
    """``#define NHHAM_<NAME> <code>`` for every member: the codes the C kernels return."""
    return "\n".join(f"#define NHHAM_{s.name} ({int(s)})" for s in Status) + "\n"
