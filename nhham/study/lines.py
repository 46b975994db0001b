"""Lines of a linearize grid longer than a chunk: located in pieces, merged as written.

The crossings along ``along`` are located within a chunk (between consecutive points of
each of its lines). A line longer than ``--chunk`` points is cut into pieces (memory is
bounded by the chunk, not by the line); each piece after the first is evaluated with the
last point of the piece before it (:func:`extended`), so that every bracket between two
consecutive points of the line belongs to exactly one piece, and that point's own values
are dropped again (:func:`trimmed`: they are its piece's). The crossings of the pieces of
one line are merged as the pieces are written (:func:`merged`): sorted by value, the
first ``CROSSINGS`` kept, counted once each (a piece merged twice, after a failure
between its two writes, adds nothing).
"""

from __future__ import annotations

import numpy as np

__all__ = ["LINE_VARIABLES", "extended", "trimmed", "merged"]

#: The per-line variables of a linearize grid.
LINE_VARIABLES = ("boundary", "boundary_kind", "boundary_direction", "boundary_count",
                  "boundary_unlocated")


def extended(region: tuple, axis: int) -> tuple:
    """(``region`` with one more point before it along ``axis`` when it does not start
    the line, how many points were added: 0 or 1)."""
    s = region[axis]
    if not s.start:
        return region, 0
    grown = slice(s.start - 1, s.stop)
    return region[:axis] + (grown,) + region[axis + 1:], 1


def trimmed(data: dict, axis: int, added: int) -> dict:
    """The per-point variables of ``data`` without the ``added`` leading points along
    ``axis`` (the per-line variables as they are)."""
    if not added:
        return data
    return {k: v if k in LINE_VARIABLES else np.take(v, np.arange(added, v.shape[axis]),
                                                     axis=axis)
            for k, v in data.items()}


def merged(old: dict, new: dict) -> dict:
    """The per-line variables of ``new`` merged with those stored (``old``, the same
    lines; a count of -1: nothing stored yet); the other variables of ``new`` as they
    are."""
    out = dict(new)
    value, kind, direction, count = (np.array(old[k]) for k in LINE_VARIABLES[:4])
    # unlocated intervals: each belongs to one piece (pieces share no bracket), so the
    # pieces' counts add up
    unlocated = (np.maximum(np.asarray(old.get("boundary_unlocated", 0)), 0)
                 + np.maximum(np.asarray(new.get("boundary_unlocated", 0)), 0))
    room = value.shape[-1]
    for line in np.ndindex(*count.shape):
        have = _entries(old, line)
        piece = _entries(new, line)
        added = [e for e in piece if e not in have]
        entries = sorted(have + added)[:room]
        before = max(int(old["boundary_count"][line]), 0)
        # the crossings of the piece not kept in its own slots are new as well
        beyond = max(int(new["boundary_count"][line]) - len(piece), 0)
        count[line] = before + len(added) + (beyond if added or not piece else 0)
        value[line] = np.nan
        kind[line] = -1
        direction[line] = 0
        for j, (v, k, d) in enumerate(entries):
            value[line + (j,)], kind[line + (j,)], direction[line + (j,)] = v, k, d
    out.update({"boundary": value, "boundary_kind": kind, "boundary_direction": direction,
                "boundary_count": count,
                "boundary_unlocated": np.broadcast_to(unlocated, count.shape).astype(np.int16)})
    return out


def _entries(data: dict, line: tuple) -> list:
    values = np.asarray(data["boundary"])[line]
    kinds = np.asarray(data["boundary_kind"])[line]
    dirs = np.asarray(data["boundary_direction"])[line]
    return [(float(v), int(k), int(d)) for v, k, d in zip(values, kinds, dirs)
            if np.isfinite(v) and k >= 0]
