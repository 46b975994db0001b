"""Plain-text and JSON rendering shared by the command and the result objects.

Text output is aligned tables of short strings; expressions are printed in
the scene's own names with :func:`nhham.expressions.to_text` (never raw
Python reprs). JSON values are numbers, booleans, null, strings and lists.
"""

from __future__ import annotations

import sys
import time
from contextlib import contextmanager
from dataclasses import dataclass, field

import sympy as sp

__all__ = ["table", "expr_text", "display_form", "Steps"]

# Expressions larger than this are shown as derived, without simplification:
# simplifying them would cost more than the user asked for.
_SIMPLIFY_LIMIT = 300


def expr_text(expr) -> str:
    """An expression as text that ``sympy.sympify`` parses back."""
    from nhham.system.expressions import to_text

    return to_text(sp.sympify(expr))


def display_form(expr):
    """A cheaply simplified form of ``expr`` for display (small ones only)."""
    expr = sp.sympify(expr)
    if expr.is_number or sp.count_ops(expr) > _SIMPLIFY_LIMIT:
        return expr
    try:
        simpler = sp.factor_terms(sp.trigsimp(sp.cancel(sp.together(expr))))
    except Exception:  # pragma: no cover - sympy corner cases; show as derived
        return expr
    return simpler if sp.count_ops(simpler) <= sp.count_ops(expr) else expr


def table(rows, header=None, indent="  ") -> str:
    """Align rows of strings into columns.

    Parameters
    ----------
    rows : sequence of sequence of str
    header : sequence of str, optional
    """
    rows = [[str(c) for c in r] for r in rows]
    if header:
        rows = [list(map(str, header))] + rows
    if not rows:
        return ""
    widths = [max(len(r[i]) for r in rows if i < len(r)) for i in range(max(map(len, rows)))]
    lines = []
    for k, r in enumerate(rows):
        cells = [c.ljust(widths[i]) if i < len(r) - 1 else c for i, c in enumerate(r)]
        lines.append(indent + "  ".join(cells).rstrip())
        if header and k == 0:
            lines.append(indent + "  ".join("-" * w for w in widths))
    return "\n".join(lines)


@dataclass
class Steps:
    """Records what a command derived, and how long each step took.

    With ``progress`` true (stderr is a terminal), each step is announced on
    stderr as it starts, so long steps do not look like a hang.
    """

    progress: bool = False
    records: list = field(default_factory=list)
    current: str | None = None

    @contextmanager
    def step(self, what: str):
        if self.progress:
            print(f"nhham: {what} ...", file=sys.stderr, flush=True)
        start = time.perf_counter()
        outer, self.current = self.current, what
        try:
            yield
        finally:
            self.current = outer
        # Only finished steps are recorded (a budget that runs out interrupts one).
        self.records.append((what, time.perf_counter() - start))

    def decided(self) -> str:
        """The steps finished and the notes recorded so far, on one line."""
        done = [what for what, t in self.records]
        return "; ".join(done) if done else "nothing yet"

    def note(self, what: str):
        """Record a fact (a decision and how it was made) without timing."""
        self.records.append((what, None))

    def render(self) -> str:
        rows = [(what, "" if t is None else f"{t * 1e3:.1f} ms") for what, t in self.records]
        return "derived (in order):\n" + table(rows)
