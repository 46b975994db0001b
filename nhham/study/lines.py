"""Lines of a linearize grid longer than a chunk: located in pieces, merged as written.

The crossings along ``along`` (and, on a grid of two or more dimensions, along ``across``,
the first other dimension) are located within a chunk (between consecutive points of
each of its lines). A line longer than the chunk is cut into pieces (memory is bounded by
the chunk, not by the line: chunks hold whole lines along ``along`` when they fit, so the
lines along ``across`` are cut whenever the grid is larger than a chunk); each piece
after the first is evaluated with the last point of the piece before it
(:func:`extended`, along each of the two axes), so that every bracket between two
consecutive points of a line belongs to exactly one piece, and that point's own values
are dropped again (:func:`trimmed`: they are its piece's; so are the lines through it).
The crossings of the pieces of one line are merged as the pieces are written
(:func:`merged`): sorted by value, the first ``CROSSINGS`` kept, counted once each (a
piece merged twice, after a failure between its two writes, adds nothing).
"""

from __future__ import annotations

import numpy as np

__all__ = ["LINE_VARIABLES", "ACROSS_VARIABLES", "extended", "trimmed", "merged"]

#: The per-line variables of a linearize grid (lines along ``along``).
LINE_VARIABLES = ("boundary", "boundary_kind", "boundary_direction", "boundary_count",
                  "boundary_unlocated")

#: The same for the lines along ``across`` (the second axis of a grid).
ACROSS_VARIABLES = tuple(n.replace("boundary", "boundary_across", 1) for n in LINE_VARIABLES)


def extended(region: tuple, axis: int, *more: int) -> tuple:
    """(``region`` with one more point before it along ``axis`` (and each of ``more``)
    when it does not start the line, how many points were added: 0 or 1 (a tuple of
    them, one per axis, when ``more`` are given))."""
    added = []
    for a in (axis, *more):
        s = region[a]
        added.append(1 if s.start else 0)
        if s.start:
            region = region[:a] + (slice(s.start - 1, s.stop),) + region[a + 1:]
    return region, (tuple(added) if more else added[0])


def trimmed(data: dict, axis: int, added: int, across: int | None = None,
            added_across: int = 0) -> dict:
    """``data`` without the leading points added by :func:`extended`: the per-point
    variables without the ``added`` points along ``axis`` (and ``added_across`` along
    ``across``); the lines along ``axis`` without those through the points added along
    ``across``, and the lines along ``across`` without those through the points added
    along ``axis``."""
    if not added and not added_across:
        return data

    def drop(v, at, n):
        return np.take(v, np.arange(n, v.shape[at]), axis=at) if n else v

    out = {}
    for k, v in data.items():
        if across is None:   # the lines along axis (dims without it) as they are
            out[k] = v if k in LINE_VARIABLES else drop(v, axis, added)
        elif k in LINE_VARIABLES:
            out[k] = drop(v, across - (across > axis), added_across)
        elif k in ACROSS_VARIABLES:
            out[k] = drop(v, axis - (axis > across), added)
        else:
            out[k] = drop(drop(v, axis, added), across, added_across)
    return out


def merged(old: dict, new: dict, names: tuple = LINE_VARIABLES) -> dict:
    """The per-line variables ``names`` of ``new`` merged with those stored (``old``,
    the same lines; a count of -1: nothing stored yet); the other variables of ``new``
    as they are."""
    out = dict(new)
    value, kind, direction, count = (np.array(old[k]) for k in names[:4])
    # unlocated intervals: each belongs to one piece (pieces share no bracket), so the
    # pieces' counts add up
    unlocated = (np.maximum(np.asarray(old.get(names[4], 0)), 0)
                 + np.maximum(np.asarray(new.get(names[4], 0)), 0))
    room = value.shape[-1]
    for line in np.ndindex(*count.shape):
        have = _entries(old, line, names)
        piece = _entries(new, line, names)
        added = [e for e in piece if e not in have]
        entries = sorted(have + added)[:room]
        before = max(int(old[names[3]][line]), 0)
        # the crossings of the piece not kept in its own slots are new as well
        beyond = max(int(new[names[3]][line]) - len(piece), 0)
        count[line] = before + len(added) + (beyond if added or not piece else 0)
        value[line] = np.nan
        kind[line] = -1
        direction[line] = 0
        for j, (v, k, d) in enumerate(entries):
            value[line + (j,)], kind[line + (j,)], direction[line + (j,)] = v, k, d
    out.update(dict(zip(names, (value, kind, direction, count, np.broadcast_to(
        unlocated, count.shape).astype(np.int16)))))
    return out


def _entries(data: dict, line: tuple, names: tuple = LINE_VARIABLES) -> list:
    values = np.asarray(data[names[0]])[line]
    kinds = np.asarray(data[names[1]])[line]
    dirs = np.asarray(data[names[2]])[line]
    return [(float(v), int(k), int(d)) for v, k, d in zip(values, kinds, dirs)
            if np.isfinite(v) and k >= 0]
