"""Plain-text and JSON rendering shared by the command and the result objects.

Text output is aligned tables of short strings; expressions are printed in
the scene's own names with :func:`nhham.system.expressions.to_text` (never raw
Python reprs). JSON values are numbers, booleans, null, strings and lists.
"""

from __future__ import annotations

import sys
import time
from contextlib import contextmanager
from dataclasses import dataclass, field

__all__ = ["table", "matrix_table", "labelled", "paragraph", "expr_text", "one_line", "Steps"]


def one_line(message) -> str:
    """A message as one line (whitespace runs, including newlines, become one space)."""
    return " ".join(str(message).split())


def expr_text(expr) -> str:
    """An expression as text that ``sympy.sympify`` parses back."""
    import sympy as sp

    from nhham.system.expressions import to_text

    return to_text(sp.sympify(expr))


def table(rows, header=None, indent="  ", total=None) -> str:
    """Align rows of strings into columns; the last cell of a row is wrapped to fit.

    The last cell (an expression, a sentence) does not set the width of its
    column: it is wrapped into the room left of ``total`` columns, continuation
    lines aligned under it, and elided past :data:`nhham.render.layout.MAX_LINES`
    lines with a pointer to ``--json`` and ``--latex`` (see
    :mod:`nhham.render.layout`). With less than 30 columns of room it starts on a
    line of its own.

    Parameters
    ----------
    rows : sequence of sequence of str
    header : sequence of str, optional
    indent : str
    total : int, optional
        The width to fit (default :func:`nhham.render.layout.width`).
    """
    from nhham.render.layout import width, wrap

    rows = [[str(c) for c in r] for r in rows]
    if header:
        rows = [list(map(str, header))] + rows
    if not rows:
        return ""
    total = width() if total is None else total
    ncols = max(map(len, rows))
    widths = [max((len(r[i]) for r in rows if i < len(r) - 1), default=0) for i in range(ncols)]
    lines = []
    for k, r in enumerate(rows):
        prefix = indent + "".join(c.ljust(widths[i]) + "  " for i, c in enumerate(r[:-1]))
        room = total - len(prefix)
        if r[:-1] and room < 30 and len(r[-1]) > room:
            lines.append(prefix.rstrip())
            prefix = indent + "    "
            room = total - len(prefix)
        pieces = wrap(r[-1], room)
        lines.append((prefix + pieces[0]).rstrip())
        lines += [(" " * len(prefix) + p).rstrip() for p in pieces[1:]]
        if header and k == 0:
            last = min(max(len(r[-1]) for r in rows if len(r) == ncols), max(room, 30))
            dashes = widths[:ncols - 1] + [last]
            lines.append(indent + "  ".join("-" * w for w in dashes))
    return "\n".join(lines)


def labelled(label: str, text: str) -> str:
    """``label: text``, the text wrapped (and elided) under its first character."""
    from nhham.render.layout import width, wrap

    hang = " " * (len(label) + 2)
    pieces = wrap(text, width() - len(hang))
    return "\n".join([f"{label}: {pieces[0]}"] + [hang + p for p in pieces[1:]])


def paragraph(text: str, hang: int = 2) -> str:
    """A heading or sentence wrapped to the width, continuation lines ``hang`` columns in
    (no elision: it is the report's own text)."""
    from nhham.render.layout import width, wrap

    pieces = wrap(text, width() - hang, max_lines=10**6)
    return "\n".join([pieces[0]] + [" " * hang + p for p in pieces[1:]])


def matrix_table(cells, name: str, rows, cols, indent="  ") -> str:
    """A matrix of expression strings: a grid when it fits the width, else its entries.

    Parameters
    ----------
    cells : list of list of str
    name : str
        The matrix's name in the entry list (``W[x, theta] = ...``).
    rows, cols : sequence of str
        Labels of the rows and columns in the entry list.
    """
    from nhham.render.layout import grid_fits

    if grid_fits(cells, len(indent)):
        return table(cells, indent=indent)
    square = len(cells) == len(cells[0]) if cells else False
    symmetric = square and all(cells[i][j] == cells[j][i] for i in range(len(cells))
                               for j in range(i))
    entries = [(f"{name}[{rows[i]}, {cols[j]}]", "=", c) for i, row in enumerate(cells)
               for j, c in enumerate(row) if c != "0" and not (symmetric and j < i)]
    note = ("symmetric: entries below the diagonal not listed; " if symmetric else "") + \
        "entries not listed are 0"
    return table(entries, indent=indent) + f"\n{indent}({note})"


@dataclass
class Steps:
    """Records what a command derived, and how long each step took.

    With ``progress`` true (stderr is a terminal), each step is announced on
    stderr as it starts, so long steps do not look like a hang.
    """

    progress: bool = False
    records: list = field(default_factory=list)
    current: str | None = None
    opened: str | None = None

    @contextmanager
    def step(self, what: str):
        if self.progress:
            print(f"nhham: {what} ...", file=sys.stderr, flush=True)
        start, at = time.perf_counter(), len(self.records)
        outer, self.current = self.current, what
        opened, self.opened = self.opened, what
        try:
            yield
        finally:
            self.current, self.opened = outer, opened
        # Only finished steps are recorded (a budget that runs out interrupts one), each
        # before the parts it contains (nhham.progress).
        self.records.insert(at, (what, time.perf_counter() - start))

    def part(self, what: str, note: str = "", show: bool = True) -> None:
        """A part of the open step begins (a run of a long step): the step's name in a
        budget's message gains ``what``; on a terminal (``show``) ``what`` and ``note``
        (progress, an estimate) are shown."""
        self.current = f"{self.opened}: {what}" if self.opened else what
        if show:
            self.show(what, note)

    def show(self, what: str, note: str = "", depth: int = 0) -> None:
        """On a terminal: ``what`` (a part at ``depth`` in the open parts) and ``note``."""
        if self.progress:
            print("nhham:   " + "  " * depth + what + (f" ({note})" if note else ""),
                  file=sys.stderr, flush=True)

    def where(self) -> str:
        """The step running now, for a budget's message: the innermost open step, else
        (between steps) the last one finished, else start-up."""
        if self.current:
            return self.current
        done = [what for what, t in self.records if t is not None]
        return f"after '{done[-1]}', between steps" if done else "start-up"

    def decided(self) -> str:
        """The steps finished and the notes recorded so far, on one line."""
        done = [what for what, t in self.records]
        return "; ".join(done) if done else "nothing yet"

    def note(self, what: str):
        """Record a fact (a decision and how it was made) without timing."""
        self.records.append((what, None))

    def render(self) -> str:
        """The steps in order, each with its time (the notes without), descriptions last."""
        rows = [("" if t is None else f"{t * 1e3:.1f} ms", what) for what, t in self.records]
        return "derived (in order):\n" + table([(t.rjust(10), what) for t, what in rows])
