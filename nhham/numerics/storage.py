"""What a run keeps: every j-th step, and never more than a bounded number of states.

A long run must not grow without bound: at 1e7 time units the rolling disk takes 2.3e7
DOP853 steps, and keeping every one (as scipy does) needs gigabytes. A
:class:`Recorder` receives the states as an integration loop produces them and keeps

- every ``stride``-th step (``save_every``; the first state always, the last one at the
  end), in arrays that grow fourfold as they fill, up to room for ``max_points`` states;
- when they are full, every other state is dropped and the stride doubles, as often as
  needed: the kept states stay evenly spread over the steps of the whole run, and the
  memory stays below :func:`storage_bytes` of ``max_points``;
- or, for ``t_eval``, exactly the requested output times (no thinning: their number is
  known before the run, and the run is refused if it is above ``max_points``).

``max_points`` defaults to as many states as fit in :data:`STORE_BYTES`.
:class:`Storage` says what was kept (``SimulationResult.storage``). No sympy here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nhham.errors import InputError

__all__ = ["STORE_BYTES", "Storage", "Recorder", "default_max_points", "storage_bytes",
           "memory_text", "save_states", "storage_plan"]

#: Memory the stored states of a run may take by default (bytes): ``max_points``
#: defaults to the number of states that fit.
STORE_BYTES = 64 * 2**20

# Rows allocated at first; the arrays grow fourfold up to max_points as they fill.
_FIRST_ROWS = 4096


def storage_bytes(points: int, width: int) -> int:
    """Bytes of ``points`` stored states with ``width`` numbers each, and their times."""
    return 8 * (width + 1) * int(points)


def default_max_points(width: int) -> int:
    """As many states of ``width`` numbers as fit in :data:`STORE_BYTES` (at least 1024)."""
    return max(1024, STORE_BYTES // storage_bytes(1, width))


def memory_text(nbytes: float) -> str:
    """``12.3 MB`` (decimal units, as `time -v` and most tools print them)."""
    for unit, size in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if nbytes >= size:
            return f"{nbytes / size:.3g} {unit}"
    return f"{int(nbytes)} B"


@dataclass(frozen=True)
class Storage:
    """What a run kept.

    Attributes
    ----------
    points : int
        States kept (the length of ``result.t``).
    stride : int
        Every ``stride``-th step was kept (and the last state); 0 with ``t_eval``.
    requested_stride : int
        The stride asked for (``save_every``, 1 by default); ``stride`` is larger when the
        states were thinned to stay within ``max_points``.
    max_points : int
        The bound on the states kept.
    bytes : int
        Memory of the kept states and their times.
    """

    points: int
    stride: int
    requested_stride: int
    max_points: int
    bytes: int

    @property
    def thinned(self) -> bool:
        """States were dropped (the stride doubled) to stay within ``max_points``."""
        return self.stride > self.requested_stride

    def describe(self, nsteps: int) -> str:
        """One line: what was kept of the ``nsteps`` steps, and its memory."""
        size = memory_text(self.bytes)
        if self.stride == 0:
            return f"stored {self.points} states at the t_eval times ({size})"
        every = ("every step" if self.stride == 1 else
                 f"one every {self.stride} steps and the last")
        line = f"stored {self.points} states of {nsteps} steps: {every} ({size})"
        if self.thinned:
            line += (f"; thinned from every {self.requested_stride} to stay within "
                     f"max_points = {self.max_points}")
        return line

    def to_dict(self) -> dict:
        return {"points": self.points, "stride": self.stride,
                "requested_stride": self.requested_stride, "max_points": self.max_points,
                "bytes": self.bytes, "thinned": self.thinned}


def check_plan(points: int, max_points: int, width: int, what: str) -> None:
    """Refuse a run that asks for more states than ``max_points`` up front (``t_eval``)."""
    if points > max_points:
        raise InputError(
            f"{what}: {points} output states would take "
            f"{memory_text(storage_bytes(points, width))}, above max_points = {max_points} "
            f"({memory_text(storage_bytes(max_points, width))}); pass fewer, or a larger "
            f"max_points")


class Recorder:
    """The states of one run as they are produced (see the module docstring).

    Parameters
    ----------
    width : int
        Numbers per state (the loops carry the state and the work of the constraint
        forces: 2n + 1).
    max_points : int
        Bound on the kept states (the last state at the end may add one).
    stride : int
        Keep every ``stride``-th step.
    thin : bool
        Halve the kept states when full (steps); False for ``t_eval`` (exact room).

    Attributes
    ----------
    t, z : ndarray
        Room for ``capacity + 1`` times and states (at most ``max_points + 1``); the
        first :attr:`count` are kept. A compiled loop writes into :meth:`room` directly
        and reports with :meth:`advance`.
    """

    def __init__(self, width: int, max_points: int, stride: int = 1, thin: bool = True):
        if max_points < 2:
            raise InputError(f"max_points: at least 2 states must be kept, got {max_points}")
        if stride < 1:
            raise InputError(f"save_every: a positive number of steps, got {stride}")
        self.width = int(width)
        self.max_points = int(max_points)
        self.requested_stride = self.stride = int(stride)
        self.thin = thin
        self.capacity = min(self.max_points, _FIRST_ROWS) if thin else self.max_points
        self.t = np.empty(self.capacity + 1)
        self.z = np.empty((self.capacity + 1, self.width))
        self.count = 0

    def room(self):
        """``(t, z)`` views of the free rows (never empty while thinning is on)."""
        return self.t[self.count:self.capacity], self.z[self.count:self.capacity]

    def advance(self, rows: int) -> None:
        """``rows`` more rows were written into :meth:`room`; grow, or thin, when full."""
        self.count += int(rows)
        if self.count < self.capacity:
            return
        if self.capacity < self.max_points:
            self._grow(min(self.max_points, 4 * self.capacity))
        elif self.thin:
            self._halve()

    def _grow(self, capacity: int) -> None:
        t, z = np.empty(capacity + 1), np.empty((capacity + 1, self.width))
        t[:self.count], z[:self.count] = self.t[:self.count], self.z[:self.count]
        self.t, self.z, self.capacity = t, z, capacity

    def keep(self, step: int) -> bool:
        """Whether step number ``step`` (0 the initial state) is to be kept."""
        return step % self.stride == 0

    def add(self, t: float, z) -> None:
        """Keep one row (the caller has checked :meth:`keep` or is storing t_eval)."""
        if self.count >= self.capacity:
            raise RuntimeError("Recorder: no room (t_eval points beyond what was planned)")
        self.t[self.count] = t
        self.z[self.count] = z
        self.advance(1)

    def close(self, t: float, z) -> None:
        """Keep the last state of the run unless it is the last kept one."""
        if self.count and self.t[self.count - 1] == t:
            return
        self.t[self.count] = t
        self.z[self.count] = z
        self.count += 1

    def _halve(self) -> None:
        """Drop every other kept state (the kept ones are at steps 0, s, 2s, ...; those
        at 0, 2s, 4s, ... stay) and double the stride."""
        kept = (self.count + 1) // 2
        self.t[:kept] = self.t[0:self.count:2].copy()
        self.z[:kept] = self.z[0:self.count:2].copy()
        self.count = kept
        self.stride *= 2

    def result(self, n2: int):
        """``(t (K,), y (n2, K), extra)``: new contiguous arrays of the kept rows, once at
        the end (the recorder's room is freed); ``y`` as in scipy, ``extra`` the column after the state
        (the work of the forces) or None when the rows are the state only."""
        K = self.count
        y = np.ascontiguousarray(self.z[:K, :n2].T)
        extra = self.z[:K, n2].copy() if self.width > n2 else None
        t = self.t[:K].copy()
        self.t, self.z, self.capacity = np.empty(0), np.empty((0, self.width)), 0  # freed
        return t, y, extra

    def storage(self, t_eval: bool = False) -> Storage:
        return Storage(points=self.count, stride=0 if t_eval else self.stride,
                       requested_stride=0 if t_eval else self.requested_stride,
                       max_points=self.max_points,
                       bytes=storage_bytes(self.count, self.width))


def storage_plan(n: int, method, save_every: int = 1, max_points=None) -> str:
    """What a run of ``method`` (a name or a Method) on n coordinates will keep, and the
    memory that takes at most (without t_eval; "auto": the most a method keeps)."""
    from nhham.numerics.methods import lookup

    # the state, and the work of the forces where the loop carries it
    width = 2 * n + (1 if method == "auto" or lookup(method).carries_work else 0)
    bound = default_max_points(width) if max_points is None else int(max_points)
    kept = "every step" if save_every == 1 else f"one step in {save_every}"
    return f"keeps {kept}, at most {bound} states: {memory_text(storage_bytes(bound, width))}"


def save_states(path, t, y, names, energy, work) -> str:
    """Write a run: ``.npz`` (``t``, ``y`` of shape (N, K), ``names``, ``energy``,
    ``work``) or otherwise CSV (``t``, the states, ``energy`` by column, a header line).

    Parameters
    ----------
    path : str or os.PathLike
    t : ndarray, shape (K,)
    y : ndarray, shape (N, K)
        The states by row (``names``).
    names : sequence of str
    energy, work : ndarray, shape (K,)

    Returns
    -------
    str
        The path written.
    """
    path = str(path)
    if path.endswith(".npz"):
        np.savez(path, t=t, y=y, names=np.array(names), energy=energy, work=work)
    else:
        header = ",".join(("t",) + tuple(names) + ("energy",))
        data = np.column_stack([t, np.asarray(y).T, energy])
        np.savetxt(path, data, delimiter=",", header=header, comments="", fmt="%.17g")
    return path
