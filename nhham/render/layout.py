"""Text layout for a terminal: long expressions wrapped, very long ones elided.

A derived expression can run to thousands of characters (the bicycle's
holonomic constraint, its forcing terms). Printed in a table column it would
pad every row to its width. Here an expression is the last cell of its row;
it is wrapped at the width of the terminal (breaking before a ``+`` or ``-``
at the shallowest parenthesis depth), continuation lines aligned under its
first character, and beyond :data:`MAX_LINES` lines elided with a pointer to
``--json`` and ``--latex``, which always carry it whole.
"""

from __future__ import annotations

import os
import re
import shutil

__all__ = ["width", "wrap", "grid_fits", "MAX_LINES", "ELIDED"]

#: Width of piped output (no terminal) when COLUMNS is not set.
DEFAULT_WIDTH = 100
#: An expression longer than this many lines is elided.
MAX_LINES = 8
#: The pointer printed in place of an elided expression's rest.
ELIDED = "... [{rest} more characters: the whole expression is in --json and --latex]"
#: The same where that does not fit the line.
ELIDED_SHORT = "... [{rest} more characters: see --json]"
# The narrowest column an expression is wrapped into.
_MIN_ROOM = 30


def width() -> int:
    """Columns to lay text out in: COLUMNS, else the terminal's, else 100 (at least 60)."""
    if os.environ.get("COLUMNS", "").isdigit():
        return max(60, int(os.environ["COLUMNS"]))
    return max(60, shutil.get_terminal_size((DEFAULT_WIDTH, 24)).columns)


def wrap(text: str, room: int, max_lines: int = MAX_LINES) -> list:
    """``text`` in lines of at most ``room`` characters (elided past ``max_lines``).

    Parameters
    ----------
    text : str
    room : int
        Characters per line (at least 30 are used).
    max_lines : int
        More lines than this: the first ``max_lines - 1`` and the pointer
        :data:`ELIDED` with the number of characters left out.
    """
    room = max(room, _MIN_ROOM)
    lines: list = []
    start = 0  # where the rest of ``text`` begins
    while len(text) - start > room and len(lines) < max_lines:
        cut = _break_at(text[start:], room)
        lines.append(text[start:start + cut].rstrip())
        start += cut
        while start < len(text) and text[start] == " ":
            start += 1
    if len(lines) < max_lines:
        return lines + [text[start:]] if start < len(text) or not lines else lines
    if start >= len(text):
        return lines
    # past max_lines: keep the first max_lines - 1 lines and say how much is left out
    left = len(text) - start + sum(len(line) for line in lines[max_lines - 1:])
    pointer = ELIDED.format(rest=f"{left:,}")
    if len(pointer) > room:
        pointer = ELIDED_SHORT.format(rest=f"{left:,}")
    return lines[:max_lines - 1] + [pointer]


#: The tokens of an expression: a number (with its exponent), a name, ``**``, or one
#: other character. A line breaks only between two of them.
_TOKEN = re.compile(r"(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|[^\W\d]\w*|\*\*|.", re.S)


def _break_at(text: str, room: int) -> int:
    """Where to break ``text`` (longer than ``room``): the space within the line that
    is shallowest in parentheses, preferring one before ``+`` or ``-``, then the latest;
    without a space past its first third, the shallowest (then latest) boundary between
    two tokens (never inside a name or a number); without one, after the first token
    (a line longer than ``room`` rather than a name cut in two)."""
    best, best_key, depth = None, None, 0
    for i, ch in enumerate(text[:room + 1]):
        if ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        elif ch == " " and i > room // 3 and text[i - 2:i] not in (" +", " -"):
            # (a space after a binary + or - is never a break: the one before it is)
            key = (depth, text[i + 1:i + 2] not in ("+", "-"), -i)
            if best_key is None or key < best_key:
                best, best_key = i, key
    if best is not None:
        return best
    return _token_break(text, room)


def _token_break(text: str, room: int) -> int:
    """A token boundary in ``text[1:room + 1]``: one after an operator (``*``, ``/``),
    a comma or an opening bracket first, then one past the line's first third, then the
    shallowest in brackets, then the latest. Never before a closing bracket, a comma,
    ``**`` or the bracket of a call, nor after ``**`` (``cos(phi)``, ``x**2`` stay
    whole)."""
    best, best_key, depth, before = None, None, 0, ""
    for match in _TOKEN.finditer(text):
        i, token = match.start(), match.group()
        if i > room:
            break
        call = token == "(" and (before[-1:].isalnum() or before[-1:] == "_")
        if 0 < i and token not in (")", "]", "}", ",", "**") and before != "**" and not call:
            # after an operator or an opening bracket first: cos(phi) stays whole
            key = (before not in ("*", "/", ",", "(", "[", "="), i <= room // 3, depth, -i)
            if best_key is None or key < best_key:
                best, best_key = i, key
        before = token
        if token in ("(", "[", "{"):
            depth += 1
        elif token in (")", "]", "}"):
            depth -= 1
    if best is not None:
        return best
    first = _TOKEN.match(text)
    return first.end() if first else room


def grid_fits(rows, indent: int = 2, total: int | None = None) -> bool:
    """True when ``rows`` of cells fit side by side (two spaces apart) in the width."""
    if not rows:
        return True
    cols = max(len(r) for r in rows)
    widths = [max((len(str(r[i])) for r in rows if i < len(r)), default=0) for i in range(cols)]
    return indent + sum(widths) + 2 * (cols - 1) <= (width() if total is None else total)
