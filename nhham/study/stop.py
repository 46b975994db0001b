"""When the chunks of a study stop: its ``--budget``, or an interrupt of the study.

A chunk's runs look at a :class:`ChunkDeadline` every few milliseconds (the compiled
loop's :class:`~nhham.numerics.run.Deadline`): it passes at the study's deadline (a
``time.time()``, the same in every process of a machine) and, in this process, as soon
as the study is abandoned (:func:`stop_chunks`: Ctrl-C), so that the threads running
chunks end at once instead of keeping the interpreter from exiting.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass

from nhham.numerics.run import Deadline

__all__ = ["ChunkDeadline", "chunk_deadline", "stop_chunks", "resume_chunks"]

_STOP = threading.Event()


@dataclass(frozen=True)
class ChunkDeadline(Deadline):
    """A deadline that also passes when the study is abandoned."""

    def passed(self) -> bool:
        return _STOP.is_set() or super().passed()

    def remaining(self) -> float:
        return -1.0 if _STOP.is_set() else super().remaining()


def chunk_deadline(until: float | None) -> ChunkDeadline:
    """The deadline of a chunk's runs: ``until`` (a ``time.time()``, None: none)."""
    left = math.inf if until is None else until - time.time()
    return ChunkDeadline(left, time.perf_counter() + left)


def stop_chunks() -> None:
    """Make the chunks running in this process stop (their runs end at once)."""
    _STOP.set()


def resume_chunks() -> None:
    """Let chunks run again (a new study in this process)."""
    _STOP.clear()
